// The base map: the server's road graph (GET /v1/map) drawn on one canvas renderer, coloured by
// road class, with the OSM attribution the FeatureCollection carries. No tiles: the console works
// offline. Each OSM way becomes one polyline (its edges are the polyline's parts), and one
// direction of each two-way road is drawn, so a city of 62k nodes is ~15k canvas paths, not 140k.
import L from 'leaflet';
import type { MapFeature, MapFeatureCollection } from '../api/types';

interface ClassStyle {
  color: string;
  weight: number;
}

const CLASS_STYLE: Record<string, ClassStyle> = {
  motorway: { color: '#d9a3a3', weight: 4 },
  motorway_link: { color: '#d9a3a3', weight: 2.5 },
  trunk: { color: '#e3b5a8', weight: 4 },
  trunk_link: { color: '#e3b5a8', weight: 2.5 },
  primary: { color: '#e8cfa6', weight: 3.5 },
  primary_link: { color: '#e8cfa6', weight: 2.5 },
  secondary: { color: '#e3dfb0', weight: 3 },
  secondary_link: { color: '#e3dfb0', weight: 2 },
  tertiary: { color: '#c9c9a0', weight: 2.5 },
  tertiary_link: { color: '#c9c9a0', weight: 2 },
  residential: { color: '#a9a9a9', weight: 1.8 },
  unclassified: { color: '#a9a9a9', weight: 1.8 },
  living_street: { color: '#bdbdbd', weight: 1.5 },
  service: { color: '#c4c4c4', weight: 1.2 },
};
const DEFAULT_STYLE: ClassStyle = { color: '#bdbdbd', weight: 1.2 };

export function roadStyle(cls: string): ClassStyle {
  return CLASS_STYLE[cls] ?? DEFAULT_STYLE;
}

/** One road the user pointed at: its edge, the opposite edge if two-way, and its name. */
export interface RoadHit {
  edge: number;
  twin: number | null;
  name: string;
  ref: string;
  cls: string;
  latlng: L.LatLng;
}

interface WayPart {
  feature: MapFeature;
  latlngs: L.LatLng[];
}

export interface BaseMap {
  layer: L.FeatureGroup;
  /** Sorted unique street names (name, or ref when unnamed). */
  names: string[];
  /** A point in the middle of the longest piece of the named street, and the street's bounds. */
  findStreet(name: string): { at: L.LatLng; bounds: L.LatLngBounds } | null;
  /** Features by edge id (both directions). */
  byEdge: Map<number, MapFeature>;
  onRoadClick(handler: (hit: RoadHit) => void): void;
  attribution: string;
}

function label(p: MapFeature['properties']): string {
  if (p.name && p.ref) return `${p.name} (${p.ref})`;
  return p.name || p.ref || '';
}

export function createBaseMap(map: L.Map, fc: MapFeatureCollection): BaseMap {
  const renderer = L.canvas({ padding: 0.3, tolerance: 4 });
  const layer = L.featureGroup();
  const byEdge = new Map<number, MapFeature>();
  const parts = new WeakMap<L.Polyline, WayPart[]>();
  const streets = new Map<string, MapFeature[]>();

  // Group by (way, class) so a way whose class changes midway keeps both colours.
  const ways = new Map<string, WayPart[]>();
  for (const f of fc.features) {
    const p = f.properties;
    byEdge.set(p.edge, f);
    const name = label(p);
    if (name) {
      const list = streets.get(name);
      if (list) list.push(f);
      else streets.set(name, [f]);
    }
    if (p.twin !== null && p.twin !== undefined && p.twin < p.edge) continue;
    const latlngs = f.geometry.coordinates.map((c) => L.latLng(c[1], c[0]));
    const key = `${p.osm_way_id}|${p.class}`;
    const list = ways.get(key);
    if (list) list.push({ feature: f, latlngs });
    else ways.set(key, [{ feature: f, latlngs }]);
  }
  // Thin roads first, so main roads are drawn over them.
  const entries = [...ways.values()].sort((a, b) => roadStyle(a[0].feature.properties.class).weight - roadStyle(b[0].feature.properties.class).weight);
  for (const wayParts of entries) {
    const style = roadStyle(wayParts[0].feature.properties.class);
    const line = L.polyline(
      wayParts.map((w) => w.latlngs),
      { renderer, color: style.color, weight: style.weight, opacity: 1, lineCap: 'round', lineJoin: 'round', interactive: true, bubblingMouseEvents: true },
    );
    parts.set(line, wayParts);
    layer.addLayer(line);
  }

  const hover = L.tooltip({ sticky: true, direction: 'top', offset: L.point(0, -6), className: 'road-tooltip' });
  const hitAt = (line: L.Polyline, latlng: L.LatLng): RoadHit | null => {
    const list = parts.get(line);
    if (!list) return null;
    const p = map.latLngToLayerPoint(latlng);
    let best: WayPart | null = null;
    let bestD = Infinity;
    for (const w of list) {
      for (let i = 1; i < w.latlngs.length; i++) {
        const d = L.LineUtil.pointToSegmentDistance(p, map.latLngToLayerPoint(w.latlngs[i - 1]), map.latLngToLayerPoint(w.latlngs[i]));
        if (d < bestD) {
          bestD = d;
          best = w;
        }
      }
    }
    if (!best) return null;
    const q = best.feature.properties;
    return { edge: q.edge, twin: q.twin ?? null, name: q.name, ref: q.ref, cls: q.class, latlng };
  };
  layer.on('mousemove', (e: L.LeafletMouseEvent) => {
    const hit = hitAt(e.propagatedFrom as L.Polyline, e.latlng);
    if (!hit) return;
    const text = [hit.name || hit.ref || 'unnamed', hit.cls, `edge ${hit.edge}`].join(' · ');
    hover.setLatLng(e.latlng).setContent(escapeHtml(text));
    if (!map.hasLayer(hover)) hover.addTo(map);
  });
  layer.on('mouseout', () => hover.remove());

  const clickHandlers: ((hit: RoadHit) => void)[] = [];
  layer.on('click', (e: L.LeafletMouseEvent) => {
    const hit = hitAt(e.propagatedFrom as L.Polyline, e.latlng);
    if (hit) for (const h of clickHandlers) h(hit);
  });

  layer.addTo(map);
  const attribution = typeof fc.attribution === 'string' ? fc.attribution : '© OpenStreetMap contributors';

  return {
    layer,
    names: [...streets.keys()].sort((a, b) => a.localeCompare(b)),
    byEdge,
    attribution,
    onRoadClick: (h) => clickHandlers.push(h),
    findStreet(name: string) {
      const wanted = name.trim().toLowerCase();
      let list = streets.get(name.trim());
      if (!list) {
        const key = [...streets.keys()].find((k) => k.toLowerCase() === wanted) ?? [...streets.keys()].find((k) => k.toLowerCase().includes(wanted));
        list = key ? streets.get(key) : undefined;
      }
      if (!list || list.length === 0) return null;
      const bounds = L.latLngBounds([]);
      let longest = list[0];
      for (const f of list) {
        for (const c of f.geometry.coordinates) bounds.extend([c[1], c[0]]);
        if (f.properties.length_m > longest.properties.length_m) longest = f;
      }
      const cs = longest.geometry.coordinates;
      const mid = cs[Math.floor(cs.length / 2)];
      const at = cs.length === 2 ? L.latLng((cs[0][1] + cs[1][1]) / 2, (cs[0][0] + cs[1][0]) / 2) : L.latLng(mid[1], mid[0]);
      return { at, bounds };
    },
  };
}

export function escapeHtml(s: string): string {
  return s.replace(/[&<>"']/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;', "'": '&#39;' })[c] as string);
}
