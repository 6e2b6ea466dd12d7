// The ETA countdown: seconds left until a mission's predicted arrival, on the server's clock.
import type { Mission } from '../api/types';

/**
 * Seconds until arrival at local time nowMs, never negative; null when the server gave no ETA.
 * eta_at_s is the server's unix time of arrival; without it, eta_s counts from updated_s.
 */
export function etaRemainingS(m: Mission, nowMs: number, clockOffsetMs: number | null): number | null {
  const serverNowS = (nowMs + (clockOffsetMs ?? 0)) / 1000;
  let at: number | null = null;
  if (typeof m.eta_at_s === 'number') at = m.eta_at_s;
  else if (typeof m.eta_s === 'number') at = m.updated_s + m.eta_s;
  if (at === null) return null;
  return Math.max(0, at - serverNowS);
}

/** 75 -> "1:15", 3725 -> "1:02:05"; whole seconds, rounded up so 0:00 means arrived. */
export function formatDuration(seconds: number): string {
  const s = Math.max(0, Math.ceil(seconds));
  const h = Math.floor(s / 3600);
  const m = Math.floor((s % 3600) / 60);
  const sec = s % 60;
  const mm = h > 0 ? String(m).padStart(2, '0') : String(m);
  return `${h > 0 ? `${h}:` : ''}${mm}:${String(sec).padStart(2, '0')}`;
}

/** The mission panel's ETA text: a countdown while active, the state once it ended. */
export function etaLabel(m: Mission, nowMs: number, clockOffsetMs: number | null): string {
  if (m.state !== 'active') return m.state;
  const left = etaRemainingS(m, nowMs, clockOffsetMs);
  return left === null ? '–' : formatDuration(left);
}

/** A unix time as local HH:MM:SS. */
export function clockTime(unixS: number): string {
  const d = new Date(unixS * 1000);
  return [d.getHours(), d.getMinutes(), d.getSeconds()].map((n) => String(n).padStart(2, '0')).join(':');
}
