import { describe, expect, it } from 'vitest';
import { reduce } from '../src/store/reducer';
import type { Signal, SignalCall } from '../src/api/types';
import { initialState, type Action, type State } from '../src/store/state';
import { T0, ev, mission, position, route, signal, vehicle } from './fixtures';

const replay = (actions: Action[], from: State = initialState()) => actions.reduce(reduce, from);
const event = (e: ReturnType<typeof ev>, receivedMs = (T0 + e.seq) * 1000): Action => ({ type: 'event', event: e, receivedMs });

describe('reducer: a replayed mission stream', () => {
  // Snapshot, then create -> positions -> route_changed -> preemption -> completed.
  const created = mission(1);
  const rerouted = mission(1, {
    route_revision: 2,
    updated_s: T0 + 5,
    last_position: { lat: 43.7395, lon: 7.4255 },
    route: route([
      [7.4246, 43.7384],
      [7.43, 43.745],
      [7.4365, 43.7496],
    ]),
  });
  const stream: Action[] = [
    { type: 'stream_open' },
    { type: 'snapshot', missions: [], vehicles: [vehicle('amb-1')], signals: [signal(408), signal(112)], nowMs: T0 * 1000 },
    event(ev(1, 'mission_created', { mission: 1, vehicle_id: 'amb-1', reason: 'created' })),
    { type: 'missions', missions: [created], nowMs: (T0 + 1) * 1000 },
    event(position(2, 1, 43.739, 7.425, 110)),
    event(position(3, 1, 43.7395, 7.4255, 100)),
    event(ev(4, 'route_changed', { mission: 1, revision: 2, eta_s: 95, reason: 'congestion' })),
    { type: 'missions', missions: [rerouted], nowMs: (T0 + 5) * 1000 },
    event(ev(6, 'preemption_started', { mission: 1, signal: 408, reason: 'started' })),
    event(ev(7, 'signal_state', { signal: 408, state: 'held' })),
    event(ev(8, 'preemption_released', { mission: 1, signal: 408 })),
    event(ev(9, 'signal_state', { signal: 408, state: 'recovering' })),
    event(ev(10, 'mission_completed', { mission: 1, vehicle_id: 'amb-1', reason: 'arrived' })),
  ];

  it('ends with the mission completed, the vehicle at its last position, and every event logged once', () => {
    const s = replay(stream);
    expect(s.missions[1].state).toBe('completed');
    expect(s.missions[1].route_revision).toBe(2);
    expect(s.missions[1].last_position).toEqual({ lat: 43.7395, lon: 7.4255 });
    expect(s.vehicles['amb-1']).toMatchObject({ lat: 43.7395, lon: 7.4255, heading_deg: 45, mission: null });
    expect(s.signals[408].state).toBe('recovering');
    expect(s.signals[112].state).toBe('normal');
    expect(s.missions[1].preemption.find((p) => p.signal === 408)?.state).toBe('released');
    expect(s.missions[1].preemption.find((p) => p.signal === 112)?.state).toBe('planned');
    expect(s.events.map((e) => e.seq)).toEqual([1, 2, 3, 4, 6, 7, 8, 9, 10]);
    expect(s.lastSeq).toBe(10);
    expect(s.stats.duplicates).toBe(0);
  });

  it('counts the ETA from the event time of the last position', () => {
    const s = replay(stream.slice(0, 6));
    expect(s.missions[1].eta_s).toBe(100);
    expect(s.missions[1].eta_at_s).toBe(T0 + 3 + 100);
  });

  it('keeps the previous route faded for 30 s after a new revision, then drops it', () => {
    const s = replay(stream.slice(0, 8));
    expect(s.previousRoutes[1]).toMatchObject({ revision: 1, untilMs: (T0 + 5) * 1000 + 30_000 });
    expect(s.previousRoutes[1].coordinates).toEqual(created.route?.geometry.coordinates);
    expect(reduce(s, { type: 'expire', nowMs: (T0 + 20) * 1000 }).previousRoutes[1]).toBeDefined();
    expect(reduce(s, { type: 'expire', nowMs: (T0 + 36) * 1000 }).previousRoutes[1]).toBeUndefined();
  });

  it('marks the schedule entry active when its preemption starts', () => {
    const s = replay(stream.slice(0, 9));
    expect(s.missions[1].preemption.find((p) => p.signal === 408)?.state).toBe('active');
  });

  it('ignores a REST copy older than the one it holds', () => {
    const s = replay([...stream.slice(0, 8), { type: 'missions', missions: [created], nowMs: (T0 + 6) * 1000 }]);
    expect(s.missions[1].route_revision).toBe(2);
    // ...and an active copy of a mission it knows has ended.
    const done = replay([...stream, { type: 'missions', missions: [rerouted], nowMs: (T0 + 11) * 1000 }]);
    expect(done.missions[1].state).toBe('completed');
  });

  it('drops duplicates and logs unknown event types without failing', () => {
    const s = replay([...stream, event(position(3, 1, 0, 0)), event(ev(11, 'something_new', { mission: 1, extra: 1 } as never))]);
    expect(s.stats.duplicates).toBe(1);
    expect(s.vehicles['amb-1'].lat).toBe(43.7395);
    expect(s.events[s.events.length - 1].type).toBe('something_new');
  });

  it('accepts a lower seq with a later time as a restarted server', () => {
    const s = replay([...stream, event(ev(1, 'congestion_applied', { time_s: T0 + 100, edges_changed: 2 }))]);
    expect(s.lastSeq).toBe(1);
    expect(s.events[s.events.length - 1].type).toBe('congestion_applied');
  });
});

describe('reducer: vehicles and their missions', () => {
  it('marks a vehicle as on a mission when the mission is created, and frees it when it ends', () => {
    const base = replay([{ type: 'snapshot', missions: [], vehicles: [vehicle('amb-1')], signals: [], nowMs: 0 }]);
    const on = reduce(base, { type: 'missions', missions: [mission(1)], nowMs: 0 });
    expect(on.vehicles['amb-1'].mission).toBe(1);
    const off = reduce(on, { type: 'missions', missions: [mission(1, { state: 'cancelled', updated_s: T0 + 1 })], nowMs: 0 });
    expect(off.vehicles['amb-1'].mission).toBeNull();
  });
});

describe('reducer: snapshot then events', () => {
  it('holds events that arrive before the snapshot and applies them after it', () => {
    const s = replay([
      { type: 'stream_open' },
      event(position(5, 1, 43.75, 7.43, 50)),
      { type: 'snapshot', missions: [mission(1)], vehicles: [vehicle('amb-1', { mission: 1 })], signals: [], nowMs: T0 * 1000 },
    ]);
    expect(s.syncing).toBe(false);
    expect(s.pending).toEqual([]);
    expect(s.vehicles['amb-1']).toMatchObject({ lat: 43.75, lon: 7.43 });
    expect(s.missions[1].eta_s).toBe(50);
    expect(s.events.map((e) => e.seq)).toEqual([5]);
  });

  it('does not apply again events the snapshot already contains when it carries a seq', () => {
    const s = replay([
      { type: 'stream_open' },
      event(position(5, 1, 43.75, 7.43, 50)),
      event(position(6, 1, 43.76, 7.44, 40)),
      { type: 'snapshot', seq: 5, missions: [mission(1)], vehicles: [vehicle('amb-1', { lat: 43.7, lon: 7.4 })], signals: [], nowMs: T0 * 1000 },
    ]);
    expect(s.stats.applied).toBe(1);
    expect(s.vehicles['amb-1']).toMatchObject({ lat: 43.76, lon: 7.44 });
    expect(s.events.map((e) => e.seq)).toEqual([5, 6]);
    expect(s.lastSeq).toBe(6);
  });

  it('drops events of the old stream that a new stream delivers again', () => {
    const before = replay([
      { type: 'stream_open' },
      { type: 'snapshot', missions: [mission(1)], vehicles: [], signals: [], nowMs: T0 * 1000 },
      event(position(1, 1, 43.71, 7.41)),
      event(position(2, 1, 43.72, 7.42)),
    ]);
    const after = replay(
      [
        { type: 'stream_open' },
        event(position(2, 1, 43.72, 7.42)),
        event(position(3, 1, 43.73, 7.43)),
        { type: 'snapshot', missions: [mission(1)], vehicles: [], signals: [], nowMs: T0 * 1000 },
      ],
      before,
    );
    expect(after.events.map((e) => e.seq)).toEqual([1, 2, 3]);
    expect(after.stats.duplicates).toBe(1);
    expect(after.vehicles['amb-1']).toMatchObject({ lat: 43.73, lon: 7.43 });
  });

  it('replaces vehicles and signals with the snapshot but keeps finished missions it knows', () => {
    const before = replay([{ type: 'missions', missions: [mission(1, { state: 'completed' })], nowMs: 0 }]);
    const s = replay([{ type: 'snapshot', missions: [mission(2)], vehicles: [vehicle('v')], signals: [signal(3, 'held')], nowMs: 0 }], before);
    expect(Object.keys(s.missions).map(Number)).toEqual([1, 2]);
    expect(Object.keys(s.vehicles)).toEqual(['v']);
    expect(s.signals[3].state).toBe('held');
  });
});

describe('reducer: field controllers', () => {
  const fielded = (): Signal => ({
    ...signal(408),
    field: { controller: 'ctl-408', link: 'up', call_on: false, lights_reported: true, answers: 10 },
  });
  const start = (): State =>
    replay([{ type: 'snapshot', missions: [mission(1)], vehicles: [], signals: [fielded(), signal(112)], nowMs: T0 * 1000 }]);

  it("follows a controller's link, its preempt state and Corridor's call from signal_field events", () => {
    const s = replay(
      [
        event(ev(1, 'signal_field', { signal: 408, link: 'up', call_on: true, preempt_state: 'entryStarted' })),
        event(ev(2, 'signal_field', { signal: 408, link: 'up', call_on: true, preempt_state: 'dwell' })),
      ],
      start(),
    );
    expect(s.signals[408].field).toMatchObject({ link: 'up', call_on: true, preempt_state: 'dwell' });
    const lost = replay([event(ev(3, 'signal_field', { signal: 408, link: 'unreachable', call_on: true, preempt_state: '', reason: 'timeout' }))], s);
    expect(lost.signals[408].field?.link).toBe('unreachable');
    expect(lost.signals[408].field?.preempt_state).toBeUndefined();
    expect(lost.signals[408].field?.error).toBe('timeout');
    const back = replay([event(ev(4, 'signal_field', { signal: 408, link: 'up', call_on: false, preempt_state: 'notActive' }))], lost);
    expect(back.signals[408].field).toMatchObject({ link: 'up', call_on: false, preempt_state: 'notActive' });
    expect(back.signals[408].field?.error).toBeUndefined();
  });

  it('ignores a signal_field event for a signal without a controller, or with a link state it does not know', () => {
    const s = replay(
      [
        event(ev(1, 'signal_field', { signal: 112, link: 'up', call_on: true })),
        event(ev(2, 'signal_field', { signal: 408, link: 'sideways', call_on: true })),
      ],
      start(),
    );
    expect(s.signals[112].field).toBeUndefined();
    expect(s.signals[408].field).toMatchObject({ link: 'up', call_on: false });
  });

  it("keeps each mission's call records apart", () => {
    const call = { signal: 408, mission: 1, vehicle_id: 'amb-1', controller: 'ctl-408', kind: 'preempt', number: 1, outcome: 'served' } as unknown as SignalCall;
    const s = replay([
      { type: 'calls', mission: 1, calls: [call] },
      { type: 'calls', mission: 2, calls: [] },
    ]);
    expect(s.calls[1]).toHaveLength(1);
    expect(s.calls[2]).toEqual([]);
  });
});
