import { describe, expect, it } from 'vitest';
import { missionOrder } from '../src/panels/missions';
import { Store } from '../src/store/store';
import { T0, mission, position } from './fixtures';

describe('store', () => {
  it('tells listeners once per frame however many events arrived, with the state they saw before', () => {
    const frames: (() => void)[] = [];
    const store = new Store((fn) => frames.push(fn));
    const calls: [number, number][] = [];
    store.subscribe((s, prev) => calls.push([s.events.length, prev.events.length]));
    store.dispatch({ type: 'missions', missions: [mission(1)], nowMs: 0 });
    for (let seq = 1; seq <= 200; seq++) store.dispatch({ type: 'event', event: position(seq, 1, 43.74 + seq * 1e-5, 7.42), receivedMs: (T0 + seq) * 1000 });
    expect(frames).toHaveLength(1);
    frames.shift()?.();
    expect(calls).toEqual([[200, 0]]);
    store.dispatch({ type: 'event', event: position(201, 1, 43.75, 7.43), receivedMs: (T0 + 201) * 1000 });
    frames.shift()?.();
    expect(calls).toEqual([
      [200, 0],
      [201, 200],
    ]);
  });

  it('does not schedule a frame for an action that changes nothing', () => {
    const frames: (() => void)[] = [];
    const store = new Store((fn) => frames.push(fn));
    store.subscribe(() => {});
    store.dispatch({ type: 'select', mission: null });
    store.dispatch({ type: 'expire', nowMs: 0 });
    expect(frames).toHaveLength(0);
  });
});

describe('mission list order', () => {
  it('lists active missions newest first, then finished ones by last update', () => {
    const list = missionOrder([
      mission(1, { state: 'completed', updated_s: T0 + 50 }),
      mission(2),
      mission(3, { state: 'cancelled', updated_s: T0 + 90 }),
      mission(4),
    ]);
    expect(list.map((m) => m.id)).toEqual([4, 2, 3, 1]);
  });
});
