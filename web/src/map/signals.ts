// Signal markers coloured by state: normal program, preemption scheduled, held green for the
// emergency vehicle, recovering. A marker is created once per signal and only its class changes.
import L from 'leaflet';
import type { Signal, SignalField } from '../api/types';
import type { State } from '../store/state';

interface SignalMarker {
  marker: L.Marker;
  signal: Signal | null;
}

const STATE_LABEL: Record<string, string> = {
  normal: 'normal program',
  scheduled: 'preemption scheduled',
  held: 'held green for the emergency vehicle',
  recovering: 'recovering to its program',
};

/** A field controller in a line: its id, link, and its own preempt state where it reports one. */
export function fieldText(f: SignalField): string {
  const preempt = f.preempt ? ` · preempt ${f.preempt}${f.preempt_state ? ` ${f.preempt_state}` : ''}` : f.preempt_state ? ` · ${f.preempt_state}` : '';
  return `controller ${f.controller} ${f.link}${f.call_on ? ' · called' : ''}${preempt}${f.error ? ` · ${f.error}` : ''}`;
}

export class SignalLayer {
  private readonly markers = new Map<number, SignalMarker>();
  private readonly group = L.layerGroup();

  constructor(map: L.Map) {
    this.group.addTo(map);
  }

  update(state: State, previous: State | null): void {
    if (previous && previous.signals === state.signals) return;
    for (const s of Object.values(state.signals)) {
      let sm = this.markers.get(s.id);
      if (sm && sm.signal === s) continue;
      if (!sm) {
        const marker = L.marker([s.location.lat, s.location.lon], {
          icon: L.divIcon({ className: 'signal-icon', html: '<div class="signal-marker"></div>', iconSize: [10, 10], iconAnchor: [5, 5] }),
          keyboard: false,
          zIndexOffset: 200,
          bubblingMouseEvents: true,
        }).addTo(this.group);
        marker.getElement()?.setAttribute('data-testid', `signal-${s.id}`);
        sm = { marker, signal: null };
        this.markers.set(s.id, sm);
      }
      const el = sm.marker.getElement();
      if (el) {
        el.dataset.state = s.state;
        const dot = el.firstElementChild;
        if (dot) dot.className = `signal-marker state-${s.state}${s.field ? ` link-${s.field.link}` : ''}`;
        if (s.field) el.dataset.link = s.field.link;
        else delete el.dataset.link;
        const lights = s.lights.map((l) => `${l.movement}: ${l.light}`).join(', ');
        el.title = `Signal ${s.id} (OSM ${s.osm_node}) · ${STATE_LABEL[s.state] ?? s.state} · ${s.mode}${lights ? ` · ${lights}` : ''}${s.field ? ` · ${fieldText(s.field)}` : ''}`;
      }
      sm.signal = s;
    }
    for (const [id, sm] of this.markers) {
      if (!state.signals[id]) {
        sm.marker.remove();
        this.markers.delete(id);
      }
    }
  }
}
