// Event log: every stream event, newest first, filterable by mission. New events are prepended
// once per frame; the list keeps the newest MAX_ROWS rows.
import type { ServerEvent } from '../api/types';
import type { State } from '../store/state';
import { byTestId, h } from './dom';
import { clockTime } from '../store/eta';

const MAX_ROWS = 300;

function detail(e: ServerEvent): string {
  const parts: string[] = [];
  if (e.vehicle_id) parts.push(e.vehicle_id);
  if (typeof e.signal === 'number') parts.push(`signal ${e.signal}`);
  if (e.state) parts.push(e.state);
  if (typeof e.revision === 'number') parts.push(`rev ${e.revision}`);
  if (typeof e.eta_s === 'number') parts.push(`eta ${Math.round(e.eta_s)} s`);
  if (typeof e.edges_changed === 'number') parts.push(`${e.edges_changed} edges`);
  if (e.reason) parts.push(e.reason);
  return parts.join(' · ');
}

export class EventLog {
  private filter: number | null = null;
  private shown: ServerEvent | null = null;
  private missionKey = '';

  constructor(private readonly getState: () => State) {
    const select = byTestId<HTMLSelectElement>('event-filter');
    select.onchange = () => {
      this.filter = select.value === '' ? null : Number(select.value);
      this.shown = null;
      byTestId('event-log').replaceChildren();
      this.render(this.getState(), null);
    };
  }

  render(state: State, previous: State | null): void {
    if (!previous || previous.missions !== state.missions) this.renderFilter(state);
    if (previous && previous.events === state.events && this.shown !== null) return;
    const events = state.events;
    // The log is append-only (capped at the front): new events are those after the last shown.
    const list = byTestId('event-log');
    let start = 0;
    if (this.shown) {
      const i = events.lastIndexOf(this.shown);
      if (i >= 0) start = i + 1;
      else list.replaceChildren(); // more events than the log keeps arrived at once
    }
    const fresh: HTMLElement[] = [];
    for (let i = start; i < events.length; i++) {
      const e = events[i];
      if (this.filter !== null && e.mission !== this.filter) continue;
      const li = h('li', { testid: 'event' }, [
        h('span', { class: 'mono', text: clockTime(e.time_s) }),
        h('span', { class: 'type', text: e.type }),
        h('span', { text: e.mission === null || e.mission === undefined ? '' : `#${e.mission}` }),
        h('span', { text: detail(e) }),
      ]);
      li.dataset.type = e.type;
      li.dataset.seq = String(e.seq);
      if (e.mission !== null && e.mission !== undefined) li.dataset.mission = String(e.mission);
      fresh.push(li);
    }
    if (events.length > 0) this.shown = events[events.length - 1];
    if (fresh.length === 0) return;
    fresh.reverse();
    list.prepend(...fresh.slice(0, MAX_ROWS));
    while (list.childElementCount > MAX_ROWS) list.lastElementChild?.remove();
  }

  private renderFilter(state: State): void {
    const ids = Object.keys(state.missions).map(Number).sort((a, b) => b - a);
    const key = ids.join(',');
    if (key === this.missionKey) return;
    this.missionKey = key;
    const select = byTestId<HTMLSelectElement>('event-filter');
    const value = select.value;
    select.replaceChildren(h('option', { text: 'all missions' }), ...ids.map((id) => h('option', { text: `mission #${id}` })));
    (select.options[0] as HTMLOptionElement).value = '';
    ids.forEach((id, i) => ((select.options[i + 1] as HTMLOptionElement).value = String(id)));
    select.value = value;
  }
}
