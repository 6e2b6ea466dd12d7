import { afterEach, beforeEach, describe, expect, it, vi } from 'vitest';
import { ApiError } from '../src/api/client';
import type { Mission } from '../src/api/types';
import type { State } from '../src/store/state';
import { Store } from '../src/store/store';
import { backoffDelayMs, Sync, type SocketLike, type SyncApi } from '../src/store/sync';
import { T0, mission, position, signal, vehicle } from './fixtures';

class FakeSocket implements SocketLike {
  onopen: SocketLike['onopen'] = null;
  onmessage: SocketLike['onmessage'] = null;
  onclose: SocketLike['onclose'] = null;
  onerror: SocketLike['onerror'] = null;
  closed = false;
  constructor(readonly url: string) {}
  open() {
    this.onopen?.({} as Event);
  }
  send(e: object) {
    this.onmessage?.({ data: JSON.stringify(e) } as MessageEvent);
  }
  drop() {
    this.closed = true;
    this.onclose?.({} as CloseEvent);
  }
  close() {
    this.closed = true;
  }
}

/** A server whose REST answers the test controls; snapshot answers can be held back. */
function fakeServer() {
  let ticketNo = 0;
  const state = {
    activeMissions: [mission(1)] as Mission[],
    missionsById: new Map<number, Mission>(),
    ticketFailures: 0,
    holdSnapshot: false,
    release: [] as (() => void)[],
    sockets: [] as FakeSocket[],
  };
  const api = {
    ticket: vi.fn(async () => {
      if (state.ticketFailures > 0) {
        state.ticketFailures--;
        throw new ApiError(0, 'network', 'connection refused');
      }
      ticketNo++;
      return { ticket: `ticket${ticketNo}`.padEnd(32, '0'), expires_in_s: 30 };
    }),
    missions: vi.fn(async () => {
      if (state.holdSnapshot) await new Promise<void>((r) => state.release.push(r));
      return state.activeMissions;
    }),
    mission: vi.fn(async (id: number) => state.missionsById.get(id) ?? mission(id)),
    vehicles: vi.fn(async () => [vehicle('amb-1', { mission: 1 })]),
    signals: vi.fn(async () => [signal(408)]),
    routes: vi.fn(async () => []),
    missionCalls: vi.fn(async () => []),
  } satisfies SyncApi;
  return Object.assign(state, { api });
}

describe('sync: reconnect with backoff and resync', () => {
  beforeEach(() => {
    vi.useFakeTimers();
    vi.setSystemTime(T0 * 1000);
  });
  afterEach(() => vi.useRealTimers());

  it('grows the delay with each failed attempt, within the jitter band, up to the cap', () => {
    expect([1, 2, 3, 4, 5, 6, 7].map((n) => backoffDelayMs(n, 1))).toEqual([1000, 2000, 4000, 8000, 16000, 30000, 30000]);
    expect([1, 2, 3].map((n) => backoffDelayMs(n, 0))).toEqual([500, 1000, 2000]);
  });

  it('reconnects after a drop with growing delays, a fresh ticket each time, resyncs, and loses or repeats no event', async () => {
    const server = fakeServer();
    const store = new Store();
    const statuses: State['connection'][] = [];
    const sync = new Sync({
      api: server.api,
      store,
      openSocket: (url) => {
        const s = new FakeSocket(url);
        server.sockets.push(s);
        return s;
      },
      streamUrl: (t) => `ws://corridor.test/v1/stream?ticket=${t}`,
      random: () => 1,
    });
    const record = () => {
      const c = store.getState().connection;
      if (statuses[statuses.length - 1] !== c) statuses.push(c);
    };
    store.subscribe(record);

    sync.start();
    await vi.advanceTimersByTimeAsync(0);
    expect(server.sockets).toHaveLength(1);
    expect(server.sockets[0].url).toBe(`ws://corridor.test/v1/stream?ticket=${'ticket1'.padEnd(32, '0')}`);
    server.sockets[0].open();
    await vi.advanceTimersByTimeAsync(0);
    expect(store.getState().connection.status).toBe('live');
    expect(store.getState().missions[1].state).toBe('active');

    server.sockets[0].send(position(1, 1, 43.741, 7.426, 90));
    server.sockets[0].send(position(2, 1, 43.742, 7.427, 80));

    // The stream drops; the first retry's ticket request fails too.
    server.ticketFailures = 1;
    server.sockets[0].drop();
    await vi.advanceTimersByTimeAsync(0);
    expect(store.getState().connection).toMatchObject({ status: 'reconnecting', attempt: 1, retryAtMs: T0 * 1000 + 1000 });
    await vi.advanceTimersByTimeAsync(999);
    expect(server.api.ticket).toHaveBeenCalledTimes(1);
    await vi.advanceTimersByTimeAsync(1);
    expect(server.api.ticket).toHaveBeenCalledTimes(2);
    expect(store.getState().connection).toMatchObject({ status: 'reconnecting', attempt: 2, retryAtMs: T0 * 1000 + 1000 + 2000 });
    expect(server.sockets).toHaveLength(1);

    // Meanwhile mission 1 completed on the server (the event is lost with the old stream).
    server.activeMissions = [mission(2)];
    server.missionsById.set(1, mission(1, { state: 'completed', updated_s: T0 + 3 }));
    server.holdSnapshot = true;
    await vi.advanceTimersByTimeAsync(2000);
    expect(server.api.ticket).toHaveBeenCalledTimes(3);
    expect(server.sockets).toHaveLength(2);
    // The second ticket the server issued (the failed request got none): never the used one.
    expect(server.sockets[1].url).toContain('ticket2');
    server.sockets[1].open();
    await vi.advanceTimersByTimeAsync(0);
    expect(store.getState().connection.status).toBe('connecting');

    // Before the snapshot arrives the new stream repeats seq 2 and brings seq 3 and 4.
    server.sockets[1].send(position(2, 1, 43.742, 7.427, 80));
    server.sockets[1].send(position(3, 2, 43.743, 7.428, 70));
    server.sockets[1].send(position(4, 2, 43.744, 7.429, 60));
    expect(store.getState().vehicles['amb-2']).toBeUndefined();
    for (const r of server.release) r();
    await vi.advanceTimersByTimeAsync(0);

    const s = store.getState();
    expect(s.connection.status).toBe('live');
    expect(s.connection.attempt).toBe(0);
    expect(s.events.map((e) => e.seq)).toEqual([1, 2, 3, 4]);
    expect(s.stats.duplicates).toBe(1);
    expect(s.vehicles['amb-2']).toMatchObject({ lat: 43.744, lon: 7.429 });
    expect(s.missions[2].eta_s).toBe(60);
    // The mission that vanished from the active list was fetched by id.
    expect(server.api.mission).toHaveBeenCalledWith(1);
    expect(s.missions[1].state).toBe('completed');
    expect(server.api.missions).toHaveBeenCalledTimes(2);
    expect(statuses.map((c) => c.status)).toContain('reconnecting');
    sync.stop();
  });

  it('after a stable connection, the next drop starts again from the shortest delay', async () => {
    const server = fakeServer();
    const store = new Store();
    const sync = new Sync({
      api: server.api,
      store,
      openSocket: (url) => {
        const s = new FakeSocket(url);
        server.sockets.push(s);
        return s;
      },
      streamUrl: (t) => `ws://x/v1/stream?ticket=${t}`,
      random: () => 0,
    });
    sync.start();
    await vi.advanceTimersByTimeAsync(0);
    server.sockets[0].drop();
    await vi.advanceTimersByTimeAsync(0);
    expect(store.getState().connection).toMatchObject({ attempt: 1, retryAtMs: T0 * 1000 + 500 });
    await vi.advanceTimersByTimeAsync(500);
    // The socket closes before it opened: a second failure, longer wait.
    server.sockets[1].drop();
    await vi.advanceTimersByTimeAsync(0);
    expect(store.getState().connection).toMatchObject({ attempt: 2, retryAtMs: T0 * 1000 + 500 + 1000 });
    await vi.advanceTimersByTimeAsync(1000);
    server.sockets[2].open();
    await vi.advanceTimersByTimeAsync(0);
    expect(store.getState().connection.status).toBe('live');
    const t = Date.now();
    server.sockets[2].drop();
    await vi.advanceTimersByTimeAsync(0);
    expect(store.getState().connection).toMatchObject({ status: 'reconnecting', attempt: 1, retryAtMs: t + 500 });
    sync.stop();
  });

  it('stops and asks for a token when the ticket is refused', async () => {
    const server = fakeServer();
    server.api.ticket.mockRejectedValueOnce(new ApiError(401, 'unauthorized', 'unknown token'));
    const store = new Store();
    const refused: string[] = [];
    const sync = new Sync({
      api: server.api,
      store,
      openSocket: (url) => new FakeSocket(url),
      streamUrl: (t) => t,
      onAuthFailure: (e) => refused.push(e.code),
    });
    sync.start();
    await vi.advanceTimersByTimeAsync(60_000);
    expect(refused).toEqual(['unauthorized']);
    expect(store.getState().connection.status).toBe('offline');
    expect(server.api.ticket).toHaveBeenCalledTimes(1);
  });

  it('fetches a mission again when an event says its route changed, coalescing a burst', async () => {
    const server = fakeServer();
    const store = new Store();
    const sockets: FakeSocket[] = [];
    const sync = new Sync({
      api: server.api,
      store,
      openSocket: (url) => {
        const s = new FakeSocket(url);
        sockets.push(s);
        return s;
      },
      streamUrl: (t) => t,
    });
    sync.start();
    await vi.advanceTimersByTimeAsync(0);
    sockets[0].open();
    await vi.advanceTimersByTimeAsync(0);
    server.missionsById.set(1, mission(1, { route_revision: 3, updated_s: T0 + 9 }));
    for (let seq = 1; seq <= 5; seq++) sockets[0].send({ seq, type: 'route_changed', mission: 1, reason: 'congestion', time_s: T0 + seq, revision: seq + 1, eta_s: 60 });
    await vi.advanceTimersByTimeAsync(0);
    // One fetch in flight when the burst came, one more after it: not five.
    expect(server.api.mission).toHaveBeenCalledTimes(2);
    expect(store.getState().missions[1].route_revision).toBe(3);
    sync.stop();
  });
});
