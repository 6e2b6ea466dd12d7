// Mission overlays: each drawn mission's route coloured by congestion per edge, its previous
// route faded for a while after a change, its destination, and its signal preemption schedule
// with the predicted arrival at each signal. Layers are created once per mission and updated in
// place when the mission changes.
import L from 'leaflet';
import type { Mission, ScheduleEntry } from '../api/types';
import type { FadedRoute, State } from '../store/state';
import { clockTime } from '../store/eta';
import { BUCKET_COLOR, routePieces, type CongestionBucket } from './congestion';

const BUCKETS: CongestionBucket[] = ['free', 'slow', 'heavy', 'closed'];

interface MissionLayers {
  group: L.LayerGroup;
  lines: Record<CongestionBucket, L.Polyline>;
  faded: L.Polyline;
  fadedRevision: number | null;
  destination: L.Marker;
  schedule: Map<number, { marker: L.Marker; text: string; permanent: boolean; state: string }>;
  mission: Mission | null;
  selected: boolean;
}

const toLatLngs = (coords: number[][]): L.LatLngExpression[] => coords.map((c) => [c[1], c[0]] as L.LatLngTuple);

/** Whether a mission's route is drawn: every active one, and the selected one whatever its state. */
function drawn(m: Mission, selected: number | null): boolean {
  return m.state === 'active' || m.id === selected;
}

export function scheduleText(e: ScheduleEntry): string {
  return `Signal ${e.signal}: arrival ${clockTime(e.arrival_s)} · green ${clockTime(e.start_s)}–${clockTime(e.release_s)} · ${e.state}${e.deferred ? ' (deferred)' : ''}`;
}

export class RouteLayers {
  private readonly renderer: L.Canvas;
  private readonly layers = new Map<number, MissionLayers>();
  private readonly root = L.layerGroup();

  constructor(map: L.Map) {
    // Routes have their own canvas, so a route update does not redraw the road graph. Only the
    // top canvas of a stack gets mouse events: this one is in a pane that lets them through to
    // the roads below (clicks on a road pick it for congestion or as a destination).
    const pane = map.createPane('routes');
    pane.style.zIndex = '420';
    pane.style.pointerEvents = 'none';
    this.renderer = L.canvas({ padding: 0.3, pane: 'routes' });
    this.root.addTo(map);
  }

  update(state: State, previous: State | null): void {
    const sel = state.selectedMission;
    const changedSelection = !previous || previous.selectedMission !== sel;
    if (previous && previous.missions === state.missions && previous.previousRoutes === state.previousRoutes && !changedSelection) return;
    for (const m of Object.values(state.missions)) {
      const want = drawn(m, sel);
      let layers = this.layers.get(m.id);
      if (!want) {
        if (layers) this.remove(m.id);
        continue;
      }
      if (!layers) layers = this.create(m.id);
      const selected = m.id === sel;
      if (layers.mission !== m || layers.selected !== selected) this.updateMission(layers, m, selected);
      this.updateFaded(layers, state.previousRoutes[m.id] ?? null);
    }
    for (const id of [...this.layers.keys()]) if (!state.missions[id]) this.remove(id);
  }

  private create(id: number): MissionLayers {
    const group = L.layerGroup().addTo(this.root);
    const faded = L.polyline([], { renderer: this.renderer, pane: 'routes', color: '#5c6bc0', weight: 5, opacity: 0.35, dashArray: '6 6', interactive: false }).addTo(group);
    const lines = {} as Record<CongestionBucket, L.Polyline>;
    for (const b of BUCKETS) {
      lines[b] = L.polyline([], {
        renderer: this.renderer,
        pane: 'routes',
        color: BUCKET_COLOR[b],
        weight: 5,
        opacity: 0.9,
        lineCap: 'round',
        lineJoin: 'round',
        interactive: false,
      }).addTo(group);
    }
    const destination = L.marker([0, 0], {
      icon: L.divIcon({ className: 'pin-icon', html: '<div class="pin mission-destination"></div>', iconSize: [10, 10], iconAnchor: [1, 12] }),
      interactive: false,
      keyboard: false,
    });
    const layers: MissionLayers = { group, lines, faded, fadedRevision: null, destination, schedule: new Map(), mission: null, selected: false };
    this.layers.set(id, layers);
    return layers;
  }

  private updateMission(layers: MissionLayers, m: Mission, selected: boolean): void {
    const routeChanged = !layers.mission || layers.mission.route !== m.route;
    if (routeChanged || layers.selected !== selected) {
      const pieces = m.route ? routePieces(m.route) : [];
      for (const b of BUCKETS) {
        const rings = pieces.filter((p) => p.bucket === b).map((p) => toLatLngs(p.coordinates));
        if (routeChanged) layers.lines[b].setLatLngs(rings);
        layers.lines[b].setStyle({ weight: selected ? 8 : 5, opacity: selected ? 1 : 0.8 });
      }
      if (selected) for (const b of BUCKETS) layers.lines[b].bringToFront();
    }
    if (!layers.mission || layers.mission.destination !== m.destination) layers.destination.setLatLng([m.destination.lat, m.destination.lon]);
    if (!layers.group.hasLayer(layers.destination)) {
      layers.destination.addTo(layers.group);
      layers.destination.getElement()?.setAttribute('data-testid', `mission-destination-${m.id}`);
    }

    // Preemption schedule: one small marker per signal on the route, with its predicted arrival.
    const seen = new Set<number>();
    for (const e of m.preemption) {
      seen.add(e.signal);
      const text = scheduleText(e);
      let s = layers.schedule.get(e.signal);
      if (!s) {
        const marker = L.marker([e.location.lat, e.location.lon], {
          icon: L.divIcon({ className: 'schedule-icon', html: '<div class="schedule-marker"></div>', iconSize: [8, 8] }),
          keyboard: false,
          zIndexOffset: 500,
          bubblingMouseEvents: true,
        }).addTo(layers.group);
        s = { marker, text: '', permanent: false, state: '' };
        layers.schedule.set(e.signal, s);
      }
      if (s.text !== text || s.permanent !== selected) {
        s.marker.unbindTooltip();
        s.marker.bindTooltip(selected ? `${clockTime(e.arrival_s)}` : text, { permanent: selected, direction: 'right', className: 'arrival', offset: L.point(6, 0) });
        s.text = text;
        s.permanent = selected;
      }
      if (s.state !== e.state) {
        const el = s.marker.getElement()?.firstElementChild;
        if (el) el.className = `schedule-marker state-${e.state}`;
        s.state = e.state;
      }
      const el = s.marker.getElement();
      if (el) {
        el.setAttribute('data-testid', `schedule-${m.id}-${e.signal}`);
        el.title = text;
      }
    }
    for (const [signal, s] of layers.schedule) {
      if (!seen.has(signal)) {
        s.marker.remove();
        layers.schedule.delete(signal);
      }
    }
    layers.mission = m;
    layers.selected = selected;
  }

  private updateFaded(layers: MissionLayers, faded: FadedRoute | null): void {
    const revision = faded ? faded.revision : null;
    if (layers.fadedRevision === revision) return;
    layers.faded.setLatLngs(faded ? toLatLngs(faded.coordinates) : []);
    layers.fadedRevision = revision;
  }

  private remove(id: number): void {
    const layers = this.layers.get(id);
    if (!layers) return;
    layers.group.remove();
    this.layers.delete(id);
  }

  /** The selected mission's route bounds, to zoom to. */
  bounds(id: number): L.LatLngBounds | null {
    const layers = this.layers.get(id);
    if (!layers) return null;
    const b = L.latLngBounds([]);
    for (const line of Object.values(layers.lines)) if (line.getLatLngs().length) b.extend(line.getBounds());
    return b.isValid() ? b : null;
  }
}
