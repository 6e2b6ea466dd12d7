// The console's whole state and the actions that change it. Only reducer.ts turns an action into
// a new state; everything else reads.
import type { Me, Mission, RouteRevision, ServerEvent, Signal, SignalCall, Vehicle } from '../api/types';

export type ConnectionStatus = 'idle' | 'connecting' | 'live' | 'reconnecting' | 'offline';

export interface ConnectionState {
  status: ConnectionStatus;
  /** Local time (ms) of the next attempt while reconnecting. */
  retryAtMs: number | null;
  /** Consecutive failed attempts; 0 once live. */
  attempt: number;
  detail: string;
}

/** A route a mission no longer follows, drawn faded until untilMs. */
export interface FadedRoute {
  revision: number;
  coordinates: number[][];
  untilMs: number;
}

export interface State {
  me: Me | null;
  connection: ConnectionState;
  missions: Record<number, Mission>;
  vehicles: Record<string, Vehicle>;
  signals: Record<number, Signal>;
  routeHistory: Record<number, RouteRevision[]>;
  /** Per mission, its call records on field controllers (fetched for the selected mission). */
  calls: Record<number, SignalCall[]>;
  previousRoutes: Record<number, FadedRoute>;
  /** Per mission, time_s of the latest event that set its position or ETA. */
  missionEventS: Record<number, number>;
  /** Every applied event, oldest first, capped at EVENT_LOG_LIMIT. */
  events: ServerEvent[];
  /** Highest seq applied and the time_s of that event: duplicates are dropped against them. */
  lastSeq: number;
  lastEventTimeS: number;
  /** Server clock minus local clock, estimated from event times; ETAs count down on it. */
  clockOffsetMs: number | null;
  selectedMission: number | null;
  /** True between a stream opening and its REST snapshot: events wait in pending. */
  syncing: boolean;
  pending: ServerEvent[];
  /** Counters a test can read: events applied, duplicates dropped, snapshots applied. */
  stats: { applied: number; duplicates: number; snapshots: number };
}

export const EVENT_LOG_LIMIT = 1000;
export const FADED_ROUTE_MS = 30_000;

export type Action =
  | { type: 'me'; me: Me | null }
  | { type: 'connection'; status: ConnectionStatus; retryAtMs?: number | null; attempt?: number; detail?: string }
  | { type: 'stream_open' }
  | { type: 'event'; event: ServerEvent; receivedMs: number }
  | {
      type: 'snapshot';
      /** Active missions; missions not in the list keep their last known state. */
      missions: Mission[];
      vehicles: Vehicle[];
      signals: Signal[];
      /** The server's event seq at the snapshot, when it tells: older pending events are dropped. */
      seq?: number | null;
      nowMs: number;
    }
  | { type: 'missions'; missions: Mission[]; nowMs: number }
  | { type: 'routes'; mission: number; revisions: RouteRevision[] }
  | { type: 'calls'; mission: number; calls: SignalCall[] }
  | { type: 'select'; mission: number | null }
  | { type: 'expire'; nowMs: number }
  | { type: 'reset' };

export function initialState(): State {
  return {
    me: null,
    connection: { status: 'idle', retryAtMs: null, attempt: 0, detail: '' },
    missions: {},
    vehicles: {},
    signals: {},
    routeHistory: {},
    calls: {},
    previousRoutes: {},
    missionEventS: {},
    events: [],
    lastSeq: -1,
    lastEventTimeS: -Infinity,
    clockOffsetMs: null,
    selectedMission: null,
    syncing: false,
    pending: [],
    stats: { applied: 0, duplicates: 0, snapshots: 0 },
  };
}
