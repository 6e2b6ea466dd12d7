// Dispatch form (dispatcher role): destination by a click on the map or a street name, vehicle
// from the known vehicles or typed, priority 0-10, the vehicle type (its routing profile), optional
// origin by a second click; creates the mission with POST /v1/missions.
import L from 'leaflet';
import type { ApiClient } from '../api/client';
import { ApiError } from '../api/client';
import type { LatLon } from '../api/types';
import type { BaseMap } from '../map/basemap';
import type { Store } from '../store/store';
import type { State } from '../store/state';
import type { Sync } from '../store/sync';
import { byTestId, h } from './dom';

/** What the next map click does; shared by the dispatch and congestion panels. */
export interface ClickMode {
  current: 'destination' | 'origin' | 'congestion';
}

const fmt = (p: LatLon) => `${p.lat.toFixed(5)}, ${p.lon.toFixed(5)}`;

function pin(cls: string, testid: string): L.Marker {
  const m = L.marker([0, 0], {
    icon: L.divIcon({ className: 'pin-icon', html: `<div class="pin ${cls}"></div>`, iconSize: [14, 14], iconAnchor: [2, 18] }),
    interactive: false,
    keyboard: false,
    zIndexOffset: 2000,
  });
  m.on('add', () => m.getElement()?.setAttribute('data-testid', testid));
  return m;
}

export class DispatchPanel {
  private destination: LatLon | null = null;
  private origin: LatLon | null = null;
  private readonly destPin = pin('destination', 'destination-pin');
  private readonly originPin = pin('origin', 'origin-pin');
  private vehicleKey = '';

  constructor(
    private readonly map: L.Map,
    private readonly api: ApiClient,
    private readonly store: Store,
    private readonly sync: Sync,
    private readonly mode: ClickMode,
    base: BaseMap,
  ) {
    byTestId('dispatch-panel').hidden = false;
    const names = byTestId('dispatch-panel').querySelector('#street-names') as HTMLDataListElement;
    names.replaceChildren(...base.names.map((n) => h('option', { text: n })));

    map.on('click', (e: L.LeafletMouseEvent) => {
      if (this.mode.current === 'congestion') return;
      const p = { lat: e.latlng.lat, lon: e.latlng.lng };
      if (this.mode.current === 'origin') {
        this.setOrigin(p);
        this.setMode('destination');
      } else {
        this.setDestination(p);
      }
    });

    byTestId('set-origin').onclick = () => this.setMode(this.mode.current === 'origin' ? 'destination' : 'origin');
    byTestId('clear-origin').onclick = () => this.setOrigin(null);
    const search = byTestId<HTMLInputElement>('street-search');
    const go = () => {
      const found = base.findStreet(search.value);
      if (!found) {
        byTestId('dispatch-error').textContent = `no street named "${search.value}"`;
        return;
      }
      byTestId('dispatch-error').textContent = '';
      map.fitBounds(found.bounds, { maxZoom: 17, padding: [40, 40] });
      this.setDestination({ lat: found.at.lat, lon: found.at.lng });
    };
    byTestId('street-go').onclick = go;
    search.onkeydown = (e) => {
      if (e.key === 'Enter') {
        e.preventDefault();
        go();
      }
    };
    byTestId<HTMLFormElement>('dispatch-form').onsubmit = (e) => {
      e.preventDefault();
      void this.create();
    };
    this.setMode('destination');
  }

  setMode(mode: ClickMode['current']): void {
    this.mode.current = mode;
    byTestId('set-origin').setAttribute('aria-pressed', String(mode === 'origin'));
    this.map.getContainer().classList.toggle('picking', mode !== 'destination');
  }

  setDestination(p: LatLon): void {
    this.destination = p;
    byTestId('destination-text').textContent = fmt(p);
    this.destPin.setLatLng([p.lat, p.lon]);
    if (!this.map.hasLayer(this.destPin)) this.destPin.addTo(this.map);
  }

  setOrigin(p: LatLon | null): void {
    this.origin = p;
    byTestId('origin-text').textContent = p ? fmt(p) : "vehicle's last position";
    if (p) {
      this.originPin.setLatLng([p.lat, p.lon]);
      if (!this.map.hasLayer(this.originPin)) this.originPin.addTo(this.map);
    } else {
      this.originPin.remove();
    }
  }

  render(state: State, previous: State | null): void {
    if (previous && previous.vehicles === state.vehicles) return;
    const ids = Object.keys(state.vehicles).sort();
    const key = ids.join('\n');
    if (key === this.vehicleKey) return;
    this.vehicleKey = key;
    const list = byTestId('dispatch-panel').querySelector('#vehicle-ids') as HTMLDataListElement;
    list.replaceChildren(...ids.map((id) => h('option', { text: id })));
  }

  private async create(): Promise<void> {
    const error = byTestId('dispatch-error');
    const vehicle = byTestId<HTMLInputElement>('vehicle-input').value.trim();
    const priority = Number(byTestId<HTMLInputElement>('priority-input').value);
    const profile = byTestId<HTMLSelectElement>('profile-input').value === 'fire_engine' ? 'fire_engine' : 'ambulance';
    if (!this.destination) {
      error.textContent = 'Click the map (or search a street) to set the destination.';
      return;
    }
    if (!vehicle) {
      error.textContent = 'Pick or type a vehicle id.';
      return;
    }
    if (!Number.isInteger(priority) || priority < 0 || priority > 10) {
      error.textContent = 'Priority is a whole number from 0 to 10.';
      return;
    }
    error.textContent = '';
    const button = byTestId<HTMLButtonElement>('create-mission');
    button.disabled = true;
    try {
      const m = await this.api.createMission({
        vehicle_id: vehicle,
        destination: this.destination,
        priority,
        profile,
        ...(this.origin ? { origin: this.origin } : {}),
      });
      this.store.dispatch({ type: 'missions', missions: [m], nowMs: Date.now() });
      this.store.dispatch({ type: 'select', mission: m.id });
      void this.sync.refreshRoutes(m.id);
      this.destPin.remove();
      this.destination = null;
      byTestId('destination-text').textContent = 'click the map';
      this.setOrigin(null);
    } catch (e) {
      error.textContent = e instanceof ApiError ? `${e.code}: ${e.message}` : String(e);
    } finally {
      button.disabled = false;
    }
  }
}
