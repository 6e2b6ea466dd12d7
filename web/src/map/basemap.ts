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
  ferry: { color: '#7fa8d8', weight: 1.5 },
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

export interface BaseMap {
  layer: L.FeatureGroup;
  /** Sorted unique street names (name, or ref when unnamed). */
  names: string[];
  /** A point in the middle of the longest piece of the named street, and the street's bounds. */
  findStreet(name: string): { at: L.LatLng; bounds: L.LatLngBounds } | null;
  /** The drawn road nearest to a point, within tolerancePx on screen. */
  roadAt(latlng: L.LatLng, tolerancePx?: number): RoadHit | null;
  onRoadClick(handler: (hit: RoadHit) => void): void;
  attribution: string;
}

function label(p: MapFeature['properties']): string {
  if (p.name && p.ref) return `${p.name} (${p.ref})`;
  return p.name || p.ref || '';
}

/** Grid cell size in degrees (~100 m of latitude) for the segment index. */
const CELL_DEG = 0.001;

/**
 * Segments of the drawn roads bucketed by grid cell, so a click or hover finds the nearest road
 * by looking at a few cells instead of asking the canvas renderer to test 15k paths.
 */
class SegmentIndex {
  private readonly cells = new Map<number, number[]>();
  /** Per segment: feature index and the index of its first coordinate, flattened. */
  private readonly segs: number[] = [];

  constructor(private readonly features: MapFeature[]) {
    features.forEach((f, fi) => {
      const cs = f.geometry.coordinates;
      for (let i = 1; i < cs.length; i++) {
        const seg = this.segs.length / 2;
        this.segs.push(fi, i - 1);
        const x0 = Math.floor(Math.min(cs[i - 1][0], cs[i][0]) / CELL_DEG);
        const x1 = Math.floor(Math.max(cs[i - 1][0], cs[i][0]) / CELL_DEG);
        const y0 = Math.floor(Math.min(cs[i - 1][1], cs[i][1]) / CELL_DEG);
        const y1 = Math.floor(Math.max(cs[i - 1][1], cs[i][1]) / CELL_DEG);
        for (let x = x0; x <= x1; x++) {
          for (let y = y0; y <= y1; y++) {
            const key = SegmentIndex.key(x, y);
            const list = this.cells.get(key);
            if (list) list.push(seg);
            else this.cells.set(key, [seg]);
          }
        }
      }
    });
  }

  private static key(x: number, y: number): number {
    // Cells of 0.001 degrees: x in [-180000, 180000], y in [-90000, 90000].
    return (x + 200_000) * 400_000 + (y + 200_000);
  }

  nearest(map: L.Map, latlng: L.LatLng, tolerancePx: number): MapFeature | null {
    const p = map.latLngToLayerPoint(latlng);
    const corner = map.layerPointToLatLng(p.add([tolerancePx, -tolerancePx]));
    const rx = Math.abs(corner.lng - latlng.lng);
    const ry = Math.abs(corner.lat - latlng.lat);
    const x0 = Math.floor((latlng.lng - rx) / CELL_DEG);
    const x1 = Math.floor((latlng.lng + rx) / CELL_DEG);
    const y0 = Math.floor((latlng.lat - ry) / CELL_DEG);
    const y1 = Math.floor((latlng.lat + ry) / CELL_DEG);
    if ((x1 - x0 + 1) * (y1 - y0 + 1) > 400) return null; // zoomed too far out to point at a road
    let best: MapFeature | null = null;
    let bestD = tolerancePx;
    const seen = new Set<number>();
    for (let x = x0; x <= x1; x++) {
      for (let y = y0; y <= y1; y++) {
        for (const seg of this.cells.get(SegmentIndex.key(x, y)) ?? []) {
          if (seen.has(seg)) continue;
          seen.add(seg);
          const f = this.features[this.segs[2 * seg]];
          const i = this.segs[2 * seg + 1];
          const a = f.geometry.coordinates[i];
          const b = f.geometry.coordinates[i + 1];
          const d = L.LineUtil.pointToSegmentDistance(p, map.latLngToLayerPoint([a[1], a[0]]), map.latLngToLayerPoint([b[1], b[0]]));
          if (d < bestD) {
            bestD = d;
            best = f;
          }
        }
      }
    }
    return best;
  }
}

export function createBaseMap(map: L.Map, fc: MapFeatureCollection): BaseMap {
  // Not interactive: the canvas renderer would hit-test every road on each mouse move. The
  // segment index answers "which road is here" instead.
  const renderer = L.canvas({ padding: 0.3 });
  const layer = L.featureGroup();
  const streets = new Map<string, MapFeature[]>();
  const drawn: MapFeature[] = [];

  // Group by (way, class) so a way whose class changes midway keeps both colours.
  const ways = new Map<string, L.LatLngExpression[][]>();
  const wayClass = new Map<string, string>();
  for (const f of fc.features) {
    const p = f.properties;
    const name = label(p);
    if (name) {
      const list = streets.get(name);
      if (list) list.push(f);
      else streets.set(name, [f]);
    }
    // One direction of a two-way road is drawn (and picked; the form offers both directions).
    if (p.twin !== null && p.twin !== undefined && p.twin < p.edge) continue;
    drawn.push(f);
    const latlngs = f.geometry.coordinates.map((c) => [c[1], c[0]] as L.LatLngTuple);
    const key = `${p.osm_way_id}|${p.class}`;
    const list = ways.get(key);
    if (list) list.push(latlngs);
    else {
      ways.set(key, [latlngs]);
      wayClass.set(key, p.class);
    }
  }
  // Thin roads first, so main roads are drawn over them.
  const keys = [...ways.keys()].sort((a, b) => roadStyle(wayClass.get(a) as string).weight - roadStyle(wayClass.get(b) as string).weight);
  for (const key of keys) {
    const style = roadStyle(wayClass.get(key) as string);
    layer.addLayer(L.polyline(ways.get(key) as L.LatLngExpression[][], { renderer, color: style.color, weight: style.weight, opacity: 1, lineCap: 'round', lineJoin: 'round', interactive: false }));
  }
  const index = new SegmentIndex(drawn);
  const roadAt = (latlng: L.LatLng, tolerancePx = 8): RoadHit | null => {
    const f = index.nearest(map, latlng, tolerancePx);
    if (!f) return null;
    const q = f.properties;
    return { edge: q.edge, twin: q.twin ?? null, name: q.name, ref: q.ref, cls: q.class, latlng };
  };

  // Street name under the mouse, looked up at most once per frame.
  const hover = L.tooltip({ sticky: true, direction: 'top', offset: L.point(0, -6), className: 'road-tooltip' });
  let pending: L.LatLng | null = null;
  map.on('mousemove', (e: L.LeafletMouseEvent) => {
    if (pending) {
      pending = e.latlng;
      return;
    }
    pending = e.latlng;
    requestAnimationFrame(() => {
      const at = pending as L.LatLng;
      pending = null;
      const hit = roadAt(at, 6);
      if (!hit) {
        hover.remove();
        return;
      }
      hover.setLatLng(at).setContent(escapeHtml([hit.name || hit.ref || 'unnamed', hit.cls, `edge ${hit.edge}`].join(' · ')));
      if (!map.hasLayer(hover)) hover.addTo(map);
    });
  });
  map.on('mouseout', () => hover.remove());

  const clickHandlers: ((hit: RoadHit) => void)[] = [];
  map.on('click', (e: L.LeafletMouseEvent) => {
    if (clickHandlers.length === 0) return;
    const hit = roadAt(e.latlng, 10);
    if (hit) for (const h of clickHandlers) h(hit);
  });

  layer.addTo(map);
  const attribution = typeof fc.attribution === 'string' ? fc.attribution : '© OpenStreetMap contributors';

  return {
    layer,
    names: [...streets.keys()].sort((a, b) => a.localeCompare(b)),
    attribution,
    roadAt,
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
