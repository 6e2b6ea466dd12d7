// Vehicle markers: an arrow rotated to the heading, labelled with the vehicle id, moved in place
// as position events arrive. The marker's HTML carries classes only (the CSP refuses style
// attributes); the rotation is set on the element from script.
import L from 'leaflet';
import type { Vehicle } from '../api/types';
import type { State } from '../store/state';

interface VehicleMarker {
  marker: L.Marker;
  vehicle: Vehicle | null;
}

export class VehicleLayer {
  private readonly markers = new Map<string, VehicleMarker>();
  private readonly group = L.layerGroup();
  private readonly clickHandlers: ((vehicle: Vehicle) => void)[] = [];

  constructor(map: L.Map) {
    this.group.addTo(map);
  }

  /** A click on a vehicle (the console selects its mission). */
  onClick(handler: (vehicle: Vehicle) => void): void {
    this.clickHandlers.push(handler);
  }

  update(state: State, previous: State | null): void {
    if (previous && previous.vehicles === state.vehicles) return;
    for (const v of Object.values(state.vehicles)) {
      let vm = this.markers.get(v.vehicle_id);
      if (vm && vm.vehicle === v) continue;
      if (!vm) {
        const marker = L.marker([v.lat, v.lon], {
          icon: L.divIcon({
            className: 'vehicle-marker',
            html: '<div class="vehicle-arrow"></div><span class="vehicle-label"></span>',
            iconSize: [24, 24],
            iconAnchor: [12, 12],
          }),
          keyboard: false,
          zIndexOffset: 1000,
        }).addTo(this.group);
        marker.on('click', () => {
          const latest = this.markers.get(v.vehicle_id)?.vehicle;
          if (latest) for (const h of this.clickHandlers) h(latest);
        });
        const el = marker.getElement();
        if (el) {
          el.setAttribute('data-testid', `vehicle-${v.vehicle_id}`);
          const label = el.querySelector('.vehicle-label');
          if (label) label.textContent = v.vehicle_id;
        }
        vm = { marker, vehicle: null };
        this.markers.set(v.vehicle_id, vm);
      } else {
        vm.marker.setLatLng([v.lat, v.lon]);
      }
      const el = vm.marker.getElement();
      if (el) {
        const arrow = el.firstElementChild as HTMLElement | null;
        if (arrow) arrow.style.transform = `rotate(${v.heading_deg ?? 0}deg)`;
        el.classList.toggle('on-mission', v.mission !== null && v.mission !== undefined);
        el.classList.toggle('no-heading', v.heading_deg === null || v.heading_deg === undefined);
        el.dataset.lat = String(v.lat);
        el.dataset.lon = String(v.lon);
        el.dataset.heading = String(v.heading_deg ?? '');
        el.title = `${v.vehicle_id}${v.mission ? ` · mission #${v.mission}` : ''}${v.speed_mps != null ? ` · ${(v.speed_mps * 3.6).toFixed(0)} km/h` : ''} · ${v.source}`;
      }
      vm.vehicle = v;
    }
    for (const [id, vm] of this.markers) {
      if (!state.vehicles[id]) {
        vm.marker.remove();
        this.markers.delete(id);
      }
    }
  }
}
