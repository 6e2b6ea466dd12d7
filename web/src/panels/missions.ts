// Mission panel: active and recent missions (vehicle, priority, state, ETA countdown), and the
// selected mission's directions, route changes with reasons, its preemption schedule with what each
// field controller reports beside Corridor's plan, and its calls on field controllers. Rows are
// keyed by mission id and updated in place; the countdown ticks once a second.
import type { ApiClient } from '../api/client';
import { ApiError } from '../api/client';
import type { Mission, SignalCall, Step } from '../api/types';
import { clockTime, etaLabel, formatDuration } from '../store/eta';
import type { State } from '../store/state';
import type { Store } from '../store/store';
import { byTestId, fmtDistance, h, setText } from './dom';

const NO_CALLS: SignalCall[] = [];

interface Row {
  tr: HTMLTableRowElement;
  cells: HTMLTableCellElement[];
  mission: Mission | null;
}

function stepText(s: Step): string {
  const road = s.name || s.ref || 'unnamed road';
  const m = s.maneuver;
  switch (m.type) {
    case 'depart':
      return `Depart on ${road}`;
    case 'arrive':
      return 'Arrive at the destination';
    case 'roundabout':
      return `At the roundabout take exit ${m.exit ?? '?'} onto ${road}`;
    case 'turn':
      return `Turn ${m.modifier ?? ''} onto ${road}`.replace('  ', ' ');
    case 'new name':
      return `Continue onto ${road}`;
    default:
      return `Continue${m.modifier && m.modifier !== 'straight' ? ` ${m.modifier}` : ''} on ${road}`;
  }
}

/** Active missions first (newest first), then finished ones (most recently updated first). */
export function missionOrder(missions: Mission[]): Mission[] {
  return missions.slice().sort((a, b) => {
    if ((a.state === 'active') !== (b.state === 'active')) return a.state === 'active' ? -1 : 1;
    return a.state === 'active' ? b.id - a.id : b.updated_s - a.updated_s;
  });
}

export class MissionPanel {
  private readonly rows = new Map<number, Row>();
  private order = '';
  private detailMission: Mission | null = null;
  private detailHistory: unknown = null;
  private detailCalls: unknown = null;
  private detailSignals: unknown = null;
  /** The schedule's controller cells by signal, refreshed as the controllers report. */
  private controllerCells = new Map<number, HTMLTableCellElement>();

  constructor(
    private readonly store: Store,
    private readonly api: ApiClient,
    private readonly canDispatch: boolean,
    private readonly onSelect: (id: number) => void,
  ) {
    byTestId('cancel-mission').onclick = () => void this.cancel();
    byTestId('calls-csv').onclick = () => void this.exportCalls();
  }

  render(state: State, previous: State | null, nowMs: number): void {
    const missionsChanged = !previous || previous.missions !== state.missions || previous.selectedMission !== state.selectedMission;
    if (missionsChanged) this.renderList(state, nowMs);
    if (
      missionsChanged ||
      !previous ||
      previous.routeHistory !== state.routeHistory ||
      previous.signals !== state.signals ||
      previous.calls !== state.calls
    ) {
      this.renderDetail(state, nowMs);
    }
  }

  /** The once-a-second countdown: ETA cells only. */
  tick(state: State, nowMs: number): void {
    for (const [id, row] of this.rows) {
      const m = state.missions[id];
      if (m) setText(row.cells[4], etaLabel(m, nowMs, state.clockOffsetMs));
    }
    const sel = state.selectedMission !== null ? state.missions[state.selectedMission] : undefined;
    if (sel) setText(byTestId('mission-summary'), this.summary(sel, state, nowMs));
  }

  private renderList(state: State, nowMs: number): void {
    const tbody = byTestId('mission-list');
    const ordered = missionOrder(Object.values(state.missions));
    for (const m of ordered) {
      let row = this.rows.get(m.id);
      if (!row) {
        const cells = [0, 1, 2, 3, 4].map(() => h('td'));
        cells[4].className = 'eta';
        cells[4].setAttribute('data-testid', `eta-${m.id}`);
        const tr = h('tr', { testid: `mission-row-${m.id}` }, cells);
        tr.onclick = () => this.onSelect(m.id);
        tr.tabIndex = 0;
        tr.onkeydown = (e) => {
          if (e.key === 'Enter' || e.key === ' ') {
            e.preventDefault();
            this.onSelect(m.id);
          }
        };
        row = { tr, cells, mission: null };
        this.rows.set(m.id, row);
      }
      if (row.mission !== m) {
        setText(row.cells[0], String(m.id));
        setText(row.cells[1], m.vehicle_id);
        setText(row.cells[2], String(m.priority));
        setText(row.cells[3], m.state);
        row.tr.dataset.state = m.state;
        row.mission = m;
      }
      row.tr.className = `state-${m.state}${m.id === state.selectedMission ? ' selected' : ''}`;
      setText(row.cells[4], etaLabel(m, nowMs, state.clockOffsetMs));
    }
    for (const [id, row] of this.rows) {
      if (!state.missions[id]) {
        row.tr.remove();
        this.rows.delete(id);
      }
    }
    const order = ordered.map((m) => m.id).join(',');
    if (order !== this.order) {
      tbody.replaceChildren(...ordered.map((m) => (this.rows.get(m.id) as Row).tr));
      this.order = order;
    }
  }

  private summary(m: Mission, state: State, nowMs: number): string {
    const length = m.route ? fmtDistance(m.route.properties.length_m) : 'no route';
    return `${m.vehicle_id} · ${m.profile === 'fire_engine' ? 'fire engine' : 'ambulance'} · priority ${m.priority} · ${m.state} · ETA ${etaLabel(m, nowMs, state.clockOffsetMs)} · ${length} · revision ${m.route_revision}`;
  }

  private renderDetail(state: State, nowMs: number): void {
    const panel = byTestId('mission-detail');
    const m = state.selectedMission !== null ? state.missions[state.selectedMission] : undefined;
    if (!m) {
      panel.hidden = true;
      this.detailMission = null;
      return;
    }
    panel.hidden = false;
    panel.dataset.mission = String(m.id);
    setText(byTestId('mission-title'), `Mission #${m.id}`);
    setText(byTestId('mission-summary'), this.summary(m, state, nowMs));
    byTestId('cancel-mission').hidden = !this.canDispatch || m.state !== 'active';

    if (this.detailMission !== m) {
      const prev = this.detailMission;
      if (!prev || prev.id !== m.id || prev.route !== m.route) {
        const steps = m.route?.properties.steps ?? [];
        byTestId('steps').replaceChildren(
          ...steps.map((s, i) =>
            h('li', { testid: `step-${i}` }, [stepText(s), h('span', { class: 'hint', text: ` · ${fmtDistance(s.distance_m)} · ${formatDuration(s.duration_s)}` })]),
          ),
        );
      }
      if (!prev || prev.id !== m.id || prev.preemption !== m.preemption) {
        this.controllerCells.clear();
        byTestId('preemption-schedule').replaceChildren(
          ...m.preemption.map((e) => {
            const controller = h('td', { testid: `controller-${e.signal}` });
            this.controllerCells.set(e.signal, controller);
            const tr = h('tr', { testid: `preemption-${e.signal}` }, [
              h('td', { text: String(e.signal), title: `OSM node ${e.osm_node} · ${e.movement} · phase ${e.phase} · congestion ${e.congestion}` }),
              h('td', { text: clockTime(e.start_s) }),
              h('td', { text: clockTime(e.arrival_s) }),
              h('td', { text: clockTime(e.release_s) }),
              h('td', { text: `${e.state}${e.deferred ? ' (deferred)' : ''}` }),
              controller,
            ]);
            tr.dataset.state = e.state;
            return tr;
          }),
        );
        this.detailSignals = null;
      }
      this.detailMission = m;
    }
    if (state.signals !== this.detailSignals) {
      for (const [signal, td] of this.controllerCells) {
        const f = state.signals[signal]?.field;
        setText(td, f ? `${f.preempt_state ?? '–'} · ${f.link}` : '–');
        td.className = f ? `link-${f.link}` : '';
        td.title = f ? `controller ${f.controller}${f.preempt ? ` · preempt ${f.preempt}` : ''}${f.call_on ? ' · called' : ''}${f.error ? ` · ${f.error}` : ''}` : 'not on a field controller';
        if (f?.preempt_state) td.dataset.preemptState = f.preempt_state;
        else delete td.dataset.preemptState;
      }
      this.detailSignals = state.signals;
    }
    const calls = state.calls[m.id] ?? NO_CALLS;
    if (calls !== this.detailCalls) {
      byTestId('calls').replaceChildren(...calls.map((c) => callRow(c)));
      this.detailCalls = calls;
    }
    // Shown for a mission over field controllers, or one that has called them.
    byTestId('calls-panel').hidden = calls.length === 0 && !m.preemption.some((e) => state.signals[e.signal]?.field !== undefined);
    const history = state.routeHistory[m.id];
    if (history !== this.detailHistory) {
      byTestId('route-history').replaceChildren(
        ...(history ?? []).map((r) => {
          const tr = h('tr', { testid: `revision-${r.revision}` }, [
            h('td', { text: String(r.revision) }),
            h('td', { text: clockTime(r.time_s) }),
            h('td', { text: r.reason, class: 'reason' }),
            h('td', { text: r.eta_s === null || r.eta_s === undefined ? '–' : formatDuration(r.eta_s) }),
            h('td', { text: fmtDistance(r.length_m) }),
          ]);
          tr.dataset.reason = r.reason;
          return tr;
        }),
      );
      this.detailHistory = history;
    }
  }

  private async exportCalls(): Promise<void> {
    const id = this.store.getState().selectedMission;
    if (id === null) return;
    const error = byTestId('mission-error');
    error.textContent = '';
    try {
      const csv = await this.api.missionCallsCsv(id);
      const url = URL.createObjectURL(new Blob([csv], { type: 'text/csv' }));
      const a = document.createElement('a');
      a.href = url;
      a.download = `mission-${id}-calls.csv`;
      document.body.append(a);
      a.click();
      a.remove();
      setTimeout(() => URL.revokeObjectURL(url), 10_000);
    } catch (e) {
      error.textContent = e instanceof ApiError ? `${e.code}: ${e.message}` : String(e);
    }
  }

  private async cancel(): Promise<void> {
    const id = this.store.getState().selectedMission;
    if (id === null) return;
    const error = byTestId('mission-error');
    error.textContent = '';
    try {
      const m = await this.api.cancelMission(id);
      this.store.dispatch({ type: 'missions', missions: [m], nowMs: Date.now() });
    } catch (e) {
      error.textContent = e instanceof ApiError ? `${e.code}: ${e.message}` : String(e);
    }
  }
}

function optionalTime(s: number | undefined): string {
  return s === undefined ? '–' : clockTime(s);
}

/** One call record: the signal, the call (preempt N or phase control), its four times and outcome. */
export function callRow(c: SignalCall): HTMLTableRowElement {
  const call = c.kind === 'preempt' ? `preempt ${c.preempt ?? '?'} · ${c.approach}` : `priority ${c.priority} · ${c.approach}`;
  const tr = h('tr', { testid: `call-${c.id}` }, [
    h('td', { text: String(c.signal), title: `controller ${c.controller}` }),
    h('td', { text: call }),
    h('td', { text: clockTime(c.request_s) }),
    h('td', { text: optionalTime(c.grant_s) }),
    h('td', { text: optionalTime(c.release_s) }),
    h('td', { text: optionalTime(c.clear_s) }),
    h('td', { text: c.outcome }),
  ]);
  tr.className = `outcome-${c.outcome}`;
  tr.dataset.outcome = c.outcome;
  return tr;
}
