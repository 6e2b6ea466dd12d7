// Connection status: connecting / live / reconnecting in Ns / offline, with the reason on hover.
import type { State } from '../store/state';
import { byTestId, setText } from './dom';

export function renderStatus(state: State, nowMs: number): void {
  const el = byTestId('connection-status');
  const c = state.connection;
  let text: string = c.status;
  if (c.status === 'reconnecting' || (c.status === 'offline' && c.retryAtMs !== null)) {
    const s = Math.max(0, Math.ceil(((c.retryAtMs ?? nowMs) - nowMs) / 1000));
    text = `${c.status === 'offline' ? 'offline, retry' : 'reconnecting'} in ${s}s`;
  }
  if (el.dataset.state !== c.status) el.dataset.state = c.status;
  setText(el, text);
  el.title = c.detail;
}
