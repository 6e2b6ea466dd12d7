// The one reducer: (state, action) -> state, pure, so that a test can replay a stream of server
// events and REST snapshots and check where it ends. Unknown event types and fields are logged
// and otherwise ignored.
import type { Mission, ScheduleEntry, ServerEvent, Signal, SignalField, Vehicle } from '../api/types';
import { EVENT_LOG_LIMIT, FADED_ROUTE_MS, initialState, type Action, type State } from './state';

/** How many finished (completed or cancelled) missions the console keeps for the "recent" list. */
export const RECENT_MISSION_LIMIT = 50;

/** preemption_<suffix> events and the schedule entry state they leave behind. */
const PREEMPTION_ENTRY_STATE: Record<string, string> = {
  scheduled: 'planned',
  started: 'active',
  released: 'released',
  cancelled: 'cancelled',
  expired: 'expired',
};

const LINK_STATES = new Set(['up', 'degraded', 'unreachable']);

export function reduce(state: State, action: Action): State {
  switch (action.type) {
    case 'me':
      return { ...state, me: action.me };
    case 'connection':
      return {
        ...state,
        connection: {
          status: action.status,
          retryAtMs: action.retryAtMs ?? null,
          attempt: action.attempt ?? state.connection.attempt,
          detail: action.detail ?? '',
        },
      };
    case 'stream_open':
      // Events from the new stream wait until the REST snapshot that follows has been applied.
      return { ...state, syncing: true, pending: [] };
    case 'event':
      return receiveEvent(state, action.event, action.receivedMs);
    case 'snapshot':
      return applySnapshot(state, action);
    case 'missions': {
      let missions = state.missions;
      let previousRoutes = state.previousRoutes;
      for (const m of action.missions) {
        const merged = mergeMission(missions, previousRoutes, state.missionEventS, m, action.nowMs);
        missions = merged.missions;
        previousRoutes = merged.previousRoutes;
      }
      if (missions === state.missions) return state;
      return { ...state, missions: pruneFinished(missions), previousRoutes, vehicles: linkVehicles(state.vehicles, action.missions) };
    }
    case 'routes':
      return { ...state, routeHistory: { ...state.routeHistory, [action.mission]: action.revisions } };
    case 'calls':
      return { ...state, calls: { ...state.calls, [action.mission]: action.calls } };
    case 'select':
      return state.selectedMission === action.mission ? state : { ...state, selectedMission: action.mission };
    case 'expire': {
      const keep = Object.entries(state.previousRoutes).filter(([, r]) => r.untilMs > action.nowMs);
      if (keep.length === Object.keys(state.previousRoutes).length) return state;
      return { ...state, previousRoutes: Object.fromEntries(keep) };
    }
    case 'reset':
      return initialState();
  }
}

/** True when the event was already applied: same process (time not later) and seq not newer. */
function isDuplicate(state: State, e: ServerEvent): boolean {
  return e.seq <= state.lastSeq && e.time_s <= state.lastEventTimeS;
}

function receiveEvent(state: State, e: ServerEvent, receivedMs: number): State {
  if (state.syncing) {
    if (state.pending.some((p) => p.seq === e.seq && p.time_s === e.time_s) || isDuplicate(state, e)) {
      return { ...state, stats: { ...state.stats, duplicates: state.stats.duplicates + 1 } };
    }
    return { ...state, pending: [...state.pending, e], clockOffsetMs: estimateOffset(state.clockOffsetMs, e, receivedMs) };
  }
  const next = applyEvent(state, e);
  if (next === state) return state;
  return { ...next, clockOffsetMs: estimateOffset(state.clockOffsetMs, e, receivedMs) };
}

/**
 * Server clock minus local clock. An event reaches us after it was stamped, so every sample
 * underestimates the offset by the network delay: keep the largest, unless a sample is far below
 * (a clock was stepped).
 */
function estimateOffset(current: number | null, e: ServerEvent, receivedMs: number): number | null {
  if (typeof e.time_s !== 'number' || !Number.isFinite(e.time_s)) return current;
  const sample = e.time_s * 1000 - receivedMs;
  if (current === null || sample > current || sample < current - 5000) return sample;
  return current;
}

function applySnapshot(state: State, a: Extract<Action, { type: 'snapshot' }>): State {
  let missions: Record<number, Mission> = { ...state.missions };
  let previousRoutes = state.previousRoutes;
  for (const m of a.missions) {
    const merged = mergeMission(missions, previousRoutes, state.missionEventS, m, a.nowMs);
    missions = merged.missions;
    previousRoutes = merged.previousRoutes;
  }
  // A mission still shown as active that the server no longer lists as active ended while the
  // stream was down: the sync layer fetches it by id (see sync.ts).
  const vehicles: Record<string, Vehicle> = {};
  for (const v of a.vehicles) vehicles[v.vehicle_id] = v;
  const signals: Record<number, Signal> = {};
  for (const s of a.signals) signals[s.id] = s;
  let next: State = {
    ...state,
    missions: pruneFinished(missions),
    previousRoutes,
    vehicles,
    signals,
    syncing: false,
    pending: [],
    stats: { ...state.stats, snapshots: state.stats.snapshots + 1 },
  };
  const snapshotSeq = a.seq ?? null;
  for (const e of state.pending) {
    if (snapshotSeq !== null && e.seq <= snapshotSeq) {
      // Already part of the snapshot: logged, not applied again.
      next = { ...next, events: appendLog(next.events, e), lastSeq: Math.max(next.lastSeq, e.seq), lastEventTimeS: Math.max(next.lastEventTimeS, e.time_s) };
      continue;
    }
    next = applyEvent(next, e);
  }
  return next;
}

function appendLog(events: ServerEvent[], e: ServerEvent): ServerEvent[] {
  const out = events.length >= EVENT_LOG_LIMIT ? events.slice(events.length - EVENT_LOG_LIMIT + 1) : events.slice();
  out.push(e);
  return out;
}

/** Applies one event that is not waiting for a snapshot. Returns state itself for a duplicate. */
export function applyEvent(state: State, e: ServerEvent): State {
  if (isDuplicate(state, e)) return { ...state, stats: { ...state.stats, duplicates: state.stats.duplicates + 1 } };
  let next: State = {
    ...state,
    events: appendLog(state.events, e),
    // A smaller seq with a later time is a restarted server: its numbering starts again.
    lastSeq: e.seq,
    lastEventTimeS: Math.max(state.lastEventTimeS, e.time_s),
    stats: { ...state.stats, applied: state.stats.applied + 1 },
  };
  const id = e.mission ?? null;
  const mission = id !== null ? next.missions[id] : undefined;
  const type = String(e.type);

  if (type === 'position' && typeof e.vehicle_id === 'string' && typeof e.lat === 'number' && typeof e.lon === 'number') {
    const old = next.vehicles[e.vehicle_id];
    const vehicle: Vehicle = {
      vehicle_id: e.vehicle_id,
      lat: e.lat,
      lon: e.lon,
      heading_deg: e.heading_deg ?? null,
      speed_mps: e.speed_mps ?? null,
      timestamp: e.time_s,
      source: e.source ?? old?.source ?? 'gps',
      mission: id ?? old?.mission ?? null,
    };
    next = { ...next, vehicles: { ...next.vehicles, [e.vehicle_id]: vehicle } };
    if (mission && mission.state === 'active') {
      const eta = typeof e.eta_s === 'number' ? e.eta_s : null;
      next = withMission(next, {
        ...mission,
        last_position: { lat: e.lat, lon: e.lon },
        ...(eta !== null ? { eta_s: eta, eta_at_s: e.time_s + eta } : {}),
      });
      next = { ...next, missionEventS: { ...next.missionEventS, [mission.id]: e.time_s } };
    }
  } else if (type === 'route_changed' && mission) {
    if (typeof e.eta_s === 'number') {
      next = withMission(next, { ...mission, eta_s: e.eta_s, eta_at_s: e.time_s + e.eta_s });
      next = { ...next, missionEventS: { ...next.missionEventS, [mission.id]: e.time_s } };
    }
  } else if ((type === 'mission_completed' || type === 'mission_cancelled') && mission) {
    const finished: Mission = { ...mission, state: type === 'mission_completed' ? 'completed' : 'cancelled', updated_s: Math.max(mission.updated_s, e.time_s) };
    next = withMission(next, finished);
    const v = next.vehicles[mission.vehicle_id];
    if (v && v.mission === mission.id) next = { ...next, vehicles: { ...next.vehicles, [v.vehicle_id]: { ...v, mission: null } } };
  } else if (type.startsWith('preemption_') && mission && typeof e.signal === 'number') {
    const suffix = type.slice('preemption_'.length);
    const entryState = PREEMPTION_ENTRY_STATE[suffix];
    const preemption = mission.preemption.map((p: ScheduleEntry) =>
      p.signal !== e.signal ? p : { ...p, ...(entryState ? { state: entryState } : {}), ...(suffix === 'deferred' ? { deferred: true } : {}) },
    );
    next = withMission(next, { ...mission, preemption });
  } else if (type === 'signal_state' && typeof e.signal === 'number' && typeof e.state === 'string') {
    const s = next.signals[e.signal];
    if (s && s.state !== e.state) next = { ...next, signals: { ...next.signals, [e.signal]: { ...s, state: e.state as Signal['state'] } } };
  } else if (type === 'signal_field' && typeof e.signal === 'number' && typeof e.link === 'string') {
    // A field controller's link, its own preempt state and Corridor's call, as they change.
    const s = next.signals[e.signal];
    if (s?.field && LINK_STATES.has(e.link)) {
      const field: SignalField = { ...s.field, link: e.link as SignalField['link'], call_on: e.call_on ?? s.field.call_on };
      if (typeof e.preempt_state === 'string' && e.preempt_state !== '') field.preempt_state = e.preempt_state as SignalField['preempt_state'];
      else delete field.preempt_state;
      if (e.reason) field.error = e.reason;
      else delete field.error;
      next = { ...next, signals: { ...next.signals, [e.signal]: { ...s, field } } };
    }
  }
  return next;
}

/** A vehicle shows the mission it is on: set by an active mission's copy, cleared by an ended one. */
function linkVehicles(vehicles: Record<string, Vehicle>, missions: Mission[]): Record<string, Vehicle> {
  let out = vehicles;
  for (const m of missions) {
    const v = out[m.vehicle_id];
    if (!v) continue;
    const want = m.state === 'active' ? m.id : v.mission === m.id ? null : v.mission;
    if (v.mission !== want) out = { ...out, [m.vehicle_id]: { ...v, mission: want } };
  }
  return out;
}

function withMission(state: State, m: Mission): State {
  return { ...state, missions: { ...state.missions, [m.id]: m } };
}

/**
 * A REST copy of a mission replaces the one held unless it is older: a lower route revision, an
 * earlier update, or an active copy of a mission already known to have ended. A newer route
 * revision keeps the old route as a faded route for FADED_ROUTE_MS.
 */
function mergeMission(
  missions: Record<number, Mission>,
  previousRoutes: State['previousRoutes'],
  missionEventS: State['missionEventS'],
  incoming: Mission,
  nowMs: number,
): { missions: Record<number, Mission>; previousRoutes: State['previousRoutes'] } {
  const current = missions[incoming.id];
  if (current) {
    // A copy requested before the latest position event but answered after it: the route is
    // current, the position and ETA the event brought are newer.
    const eventS = missionEventS[incoming.id];
    if (incoming.route_revision === current.route_revision && eventS !== undefined && eventS > incoming.updated_s) {
      incoming = { ...incoming, last_position: current.last_position, eta_s: current.eta_s, eta_at_s: current.eta_at_s };
    }
    if (incoming.route_revision < current.route_revision) return { missions, previousRoutes };
    if (incoming.route_revision === current.route_revision && incoming.updated_s < current.updated_s) return { missions, previousRoutes };
    if (current.state !== 'active' && incoming.state === 'active') return { missions, previousRoutes };
    if (incoming.route_revision > current.route_revision && current.route) {
      previousRoutes = {
        ...previousRoutes,
        [incoming.id]: { revision: current.route_revision, coordinates: current.route.geometry.coordinates, untilMs: nowMs + FADED_ROUTE_MS },
      };
    }
  }
  return { missions: { ...missions, [incoming.id]: incoming }, previousRoutes };
}

/** Keeps every active mission and the RECENT_MISSION_LIMIT most recently updated finished ones. */
function pruneFinished(missions: Record<number, Mission>): Record<number, Mission> {
  const finished = Object.values(missions).filter((m) => m.state !== 'active');
  if (finished.length <= RECENT_MISSION_LIMIT) return missions;
  finished.sort((a, b) => b.updated_s - a.updated_s);
  const out = { ...missions };
  for (const m of finished.slice(RECENT_MISSION_LIMIT)) delete out[m.id];
  return out;
}
