// Keeps the store in step with the server: opens the event stream with a fresh single-use
// ticket, resynchronises from REST after every (re)connect, reconnects by itself with exponential
// backoff and jitter, and fetches the missions and route histories that events say have changed.
// It only dispatches actions; what they do is the reducer's business.
import { ApiError, type ApiClient } from '../api/client';
import type { ServerEvent } from '../api/types';
import type { Store } from './store';

export interface SocketLike {
  onopen: ((ev: Event) => void) | null;
  onmessage: ((ev: MessageEvent) => void) | null;
  onclose: ((ev: CloseEvent) => void) | null;
  onerror: ((ev: Event) => void) | null;
  close(): void;
}

export type SyncApi = Pick<ApiClient, 'ticket' | 'missions' | 'mission' | 'vehicles' | 'signals' | 'routes' | 'missionCalls'>;

export interface SyncDeps {
  api: SyncApi;
  store: Store;
  /** new WebSocket(url) in the page. */
  openSocket: (url: string) => SocketLike;
  /** The stream URL for a ticket (same host as the page). */
  streamUrl: (ticket: string) => string;
  now?: () => number;
  random?: () => number;
  isOnline?: () => boolean;
  /** Called when the server refuses the token: the page asks for another one. */
  onAuthFailure?: (e: ApiError) => void;
}

export const BACKOFF_BASE_MS = 1000;
export const BACKOFF_CAP_MS = 30_000;

/**
 * Delay before reconnect attempt n (1-based): doubling from BACKOFF_BASE_MS up to BACKOFF_CAP_MS,
 * times a jitter factor in [0.5, 1) so that many consoles do not reconnect in step.
 */
export function backoffDelayMs(attempt: number, random: number): number {
  const exp = Math.min(BACKOFF_CAP_MS, BACKOFF_BASE_MS * 2 ** Math.max(0, attempt - 1));
  return Math.round(exp * (0.5 + 0.5 * random));
}

/** Event types after which the mission's REST copy (route, schedule, ETA) is fetched again. */
const REFRESH_ON = new Set([
  'mission_created',
  'route_changed',
  'mission_completed',
  'mission_cancelled',
  'preemption_scheduled',
  'preemption_retimed',
  'preemption_deferred',
]);

export class Sync {
  private socket: SocketLike | null = null;
  private timer: ReturnType<typeof setTimeout> | null = null;
  /** Bumped on every connect and stop, so callbacks of an older socket are ignored. */
  private generation = 0;
  private attempt = 0;
  private running = false;
  private readonly inflight = new Map<string, Promise<void>>();
  private readonly again = new Set<string>();
  private readonly now: () => number;
  private readonly random: () => number;

  constructor(private readonly deps: SyncDeps) {
    this.now = deps.now ?? (() => Date.now());
    this.random = deps.random ?? Math.random;
  }

  start(): void {
    if (this.running) return;
    this.running = true;
    this.attempt = 0;
    void this.connect();
  }

  stop(): void {
    this.running = false;
    this.generation++;
    if (this.timer !== null) clearTimeout(this.timer);
    this.timer = null;
    const s = this.socket;
    this.socket = null;
    s?.close();
    this.deps.store.dispatch({ type: 'connection', status: 'idle', attempt: 0 });
  }

  /** Skips the wait of a pending reconnect (the browser came back online). */
  reconnectNow(): void {
    if (!this.running || this.socket) return;
    if (this.timer !== null) clearTimeout(this.timer);
    this.timer = null;
    void this.connect();
  }

  private async connect(): Promise<void> {
    const gen = ++this.generation;
    this.timer = null;
    this.deps.store.dispatch({ type: 'connection', status: 'connecting', attempt: this.attempt });
    let ticket: string;
    try {
      ticket = (await this.deps.api.ticket()).ticket;
    } catch (e) {
      if (gen !== this.generation) return;
      if (e instanceof ApiError && (e.status === 401 || e.status === 403)) {
        this.running = false;
        this.deps.store.dispatch({ type: 'connection', status: 'offline', attempt: this.attempt, detail: e.message });
        this.deps.onAuthFailure?.(e);
        return;
      }
      this.scheduleReconnect(`ticket: ${(e as Error).message}`);
      return;
    }
    if (gen !== this.generation) return;
    const socket = this.deps.openSocket(this.deps.streamUrl(ticket));
    this.socket = socket;
    socket.onopen = () => {
      if (gen !== this.generation) return;
      this.deps.store.dispatch({ type: 'stream_open' });
      void this.resync(gen);
    };
    socket.onmessage = (m) => {
      if (gen !== this.generation) return;
      this.receive(m.data);
    };
    socket.onerror = () => {};
    socket.onclose = () => {
      if (gen !== this.generation) return;
      this.socket = null;
      this.scheduleReconnect('stream closed');
    };
  }

  private receive(data: unknown): void {
    if (typeof data !== 'string') return;
    let parsed: unknown;
    try {
      parsed = JSON.parse(data);
    } catch {
      return;
    }
    const e = parsed as ServerEvent;
    if (!e || typeof e !== 'object' || typeof e.type !== 'string' || typeof e.seq !== 'number') return;
    this.deps.store.dispatch({ type: 'event', event: e, receivedMs: this.now() });
    const id = typeof e.mission === 'number' ? e.mission : null;
    if (id === null) return;
    if (REFRESH_ON.has(e.type) || !this.deps.store.getState().missions[id]) this.refreshMission(id);
    const selected = this.deps.store.getState().selectedMission === id;
    if ((e.type === 'route_changed' || e.type === 'mission_created') && selected) this.refreshRoutes(id);
    if (e.type === 'signal_call' && selected) this.refreshCalls(id);
  }

  /** REST snapshot after the stream opened: events that arrived meanwhile wait in the reducer. */
  private async resync(gen: number): Promise<void> {
    try {
      const [missions, vehicles, signals] = await Promise.all([
        this.deps.api.missions('active'),
        this.deps.api.vehicles(),
        this.deps.api.signals(),
      ]);
      if (gen !== this.generation) return;
      const before = this.deps.store.getState();
      this.deps.store.dispatch({ type: 'snapshot', missions, vehicles, signals, nowMs: this.now() });
      const listed = new Set(missions.map((m) => m.id));
      for (const m of Object.values(before.missions)) {
        if (m.state === 'active' && !listed.has(m.id)) this.refreshMission(m.id);
      }
      const selected = this.deps.store.getState().selectedMission;
      if (selected !== null) {
        this.refreshRoutes(selected);
        this.refreshCalls(selected);
      }
      this.attempt = 0;
      this.deps.store.dispatch({ type: 'connection', status: 'live', attempt: 0 });
    } catch (e) {
      if (gen !== this.generation) return;
      if (e instanceof ApiError && (e.status === 401 || e.status === 403)) {
        this.stop();
        this.deps.store.dispatch({ type: 'connection', status: 'offline', detail: e.message });
        this.deps.onAuthFailure?.(e);
        return;
      }
      // Drop this stream (its callbacks are ignored from now on) and start again.
      this.generation++;
      const s = this.socket;
      this.socket = null;
      s?.close();
      this.scheduleReconnect(`resync: ${(e as Error).message}`);
    }
  }

  private scheduleReconnect(detail: string): void {
    if (!this.running) return;
    this.attempt += 1;
    const delay = backoffDelayMs(this.attempt, this.random());
    const offline = this.deps.isOnline ? !this.deps.isOnline() : false;
    this.deps.store.dispatch({
      type: 'connection',
      status: offline ? 'offline' : 'reconnecting',
      retryAtMs: this.now() + delay,
      attempt: this.attempt,
      detail,
    });
    this.timer = setTimeout(() => void this.connect(), delay);
  }

  /** Fetches one mission; concurrent requests for the same mission coalesce into one more fetch. */
  refreshMission(id: number): Promise<void> {
    return this.coalesce(`m${id}`, async () => {
      const m = await this.deps.api.mission(id);
      this.deps.store.dispatch({ type: 'missions', missions: [m], nowMs: this.now() });
    });
  }

  refreshRoutes(id: number): Promise<void> {
    return this.coalesce(`r${id}`, async () => {
      const revisions = await this.deps.api.routes(id);
      this.deps.store.dispatch({ type: 'routes', mission: id, revisions });
    });
  }

  refreshCalls(id: number): Promise<void> {
    return this.coalesce(`c${id}`, async () => {
      const calls = await this.deps.api.missionCalls(id);
      this.deps.store.dispatch({ type: 'calls', mission: id, calls });
    });
  }

  /** Recent finished missions, once at start, so the panel has something to show. */
  async loadRecent(): Promise<void> {
    const [completed, cancelled] = await Promise.all([this.deps.api.missions('completed'), this.deps.api.missions('cancelled')]);
    this.deps.store.dispatch({ type: 'missions', missions: [...completed, ...cancelled], nowMs: this.now() });
  }

  private coalesce(key: string, run: () => Promise<void>): Promise<void> {
    const running = this.inflight.get(key);
    if (running) {
      this.again.add(key);
      return running;
    }
    const p = run()
      .catch(() => {
        // A failed refresh is retried by the next event or resync; the stream status shows
        // whether the server is reachable at all.
      })
      .finally(() => {
        this.inflight.delete(key);
        if (this.again.delete(key)) void this.coalesce(key, run);
      });
    this.inflight.set(key, p);
    return p;
  }
}
