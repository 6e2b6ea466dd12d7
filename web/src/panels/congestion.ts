// Congestion report (sensor role): pick a road on the map, then report a slow-down factor or a
// closure (speed_kmh 0) with an expiry, for one or both directions, via POST /v1/congestion.
import type { ApiClient } from '../api/client';
import { ApiError } from '../api/client';
import type { BaseMap, RoadHit } from '../map/basemap';
import type { ClickMode } from './dispatch';
import { byTestId } from './dom';

export class CongestionPanel {
  private road: RoadHit | null = null;

  constructor(
    private readonly api: ApiClient,
    private readonly mode: ClickMode,
    private readonly setMode: (mode: ClickMode['current']) => void,
    base: BaseMap,
  ) {
    byTestId('congestion-panel').hidden = false;
    const toggle = byTestId('congestion-mode');
    toggle.onclick = () => {
      this.setMode(this.mode.current === 'congestion' ? 'destination' : 'congestion');
      this.sync();
    };
    base.onRoadClick((hit) => {
      if (this.mode.current !== 'congestion') return;
      this.pick(hit);
    });
    const closed = byTestId<HTMLInputElement>('congestion-closed');
    closed.onchange = () => {
      byTestId<HTMLInputElement>('congestion-factor').disabled = closed.checked;
    };
    byTestId<HTMLFormElement>('congestion-form').onsubmit = (e) => {
      e.preventDefault();
      void this.submit();
    };
    this.sync();
  }

  /** Reflects the shared click mode on the toggle (the dispatch panel may change it). */
  sync(): void {
    byTestId('congestion-mode').setAttribute('aria-pressed', String(this.mode.current === 'congestion'));
  }

  pick(hit: RoadHit): void {
    this.road = hit;
    const name = hit.name || hit.ref || 'unnamed road';
    byTestId('congestion-edge').textContent = `${name} · edge ${hit.edge}${hit.twin !== null ? ` / ${hit.twin}` : ''}`;
    byTestId('congestion-edge').dataset.edge = String(hit.edge);
  }

  private async submit(): Promise<void> {
    const result = byTestId('congestion-result');
    if (!this.road) {
      result.textContent = 'Pick a road on the map first.';
      return;
    }
    const closed = byTestId<HTMLInputElement>('congestion-closed').checked;
    const factor = Number(byTestId<HTMLInputElement>('congestion-factor').value);
    const expires = Number(byTestId<HTMLInputElement>('congestion-expires').value);
    const both = byTestId<HTMLInputElement>('congestion-both').checked;
    if (!closed && !(factor > 0)) {
      result.textContent = 'The factor must be greater than 0.';
      return;
    }
    const edges = [this.road.edge, ...(both && this.road.twin !== null ? [this.road.twin] : [])];
    const updates = edges.map((edge) => ({
      edge,
      ...(closed ? { speed_kmh: 0 } : { factor }),
      ...(expires > 0 ? { expires_in_s: expires } : {}),
    }));
    try {
      const r = await this.api.congestion({ updates });
      result.textContent = `${r.edges_changed} edge(s) changed, ${r.missions_replanned} mission(s) replanned, ${r.routes_changed} route(s) changed in ${r.replan_latency_ms.toFixed(1)} ms`;
    } catch (e) {
      result.textContent = e instanceof ApiError ? `${e.code}: ${e.message}` : String(e);
    }
  }
}
