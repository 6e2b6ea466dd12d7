import { afterEach, beforeEach, describe, expect, it, vi } from 'vitest';
import { etaLabel, etaRemainingS, formatDuration } from '../src/store/eta';
import { T0, mission } from './fixtures';

describe('ETA countdown', () => {
  beforeEach(() => {
    vi.useFakeTimers();
    vi.setSystemTime(T0 * 1000);
  });
  afterEach(() => vi.useRealTimers());

  it('counts down from eta_at_s once a second and stops at 0:00', () => {
    const m = mission(1, { eta_at_s: T0 + 75 });
    const seen: string[] = [];
    const timer = setInterval(() => seen.push(etaLabel(m, Date.now(), 0)), 1000);
    vi.advanceTimersByTime(3000);
    expect(seen).toEqual(['1:14', '1:13', '1:12']);
    vi.advanceTimersByTime(80_000);
    expect(seen[seen.length - 1]).toBe('0:00');
    clearInterval(timer);
  });

  it('uses the server clock offset estimated from events', () => {
    const m = mission(1, { eta_at_s: T0 + 60 });
    // The server's clock is 10 s ahead of ours: 50 s are left, not 60.
    expect(etaRemainingS(m, T0 * 1000, 10_000)).toBe(50);
  });

  it('falls back to updated_s + eta_s without eta_at_s, and shows no countdown without an ETA', () => {
    expect(etaRemainingS(mission(1, { eta_at_s: null, eta_s: 30, updated_s: T0 - 10 }), T0 * 1000, 0)).toBe(20);
    expect(etaLabel(mission(1, { eta_at_s: null, eta_s: null }), T0 * 1000, 0)).toBe('–');
    expect(etaLabel(mission(1, { state: 'completed' }), T0 * 1000, 0)).toBe('completed');
  });

  it('formats hours, minutes and seconds', () => {
    expect(formatDuration(0)).toBe('0:00');
    expect(formatDuration(59.2)).toBe('1:00');
    expect(formatDuration(3725)).toBe('1:02:05');
  });
});
