// Splits a route into pieces by congestion: per edge, the piece of the route's LineString that
// edge covers (edge_coordinate_index) and how congested it is (congestion_factors). Pure, so the
// split is unit-tested without a map.
import type { RouteFeature } from '../api/types';

export type CongestionBucket = 'free' | 'slow' | 'heavy' | 'closed';

export const BUCKET_COLOR: Record<CongestionBucket, string> = {
  free: '#2e9d4f',
  slow: '#f4b400',
  heavy: '#e53935',
  closed: '#4a0010',
};

/** Free flow up to 1.25x, slow to 2x, heavy to 1000x; beyond that (or null) the edge is closed. */
export function bucketOf(factor: number | null | undefined): CongestionBucket {
  if (factor === null || factor === undefined || !Number.isFinite(factor) || factor >= 1000) return 'closed';
  if (factor <= 1.25) return 'free';
  if (factor <= 2) return 'slow';
  return 'heavy';
}

export interface RoutePiece {
  bucket: CongestionBucket;
  /** [lon, lat] pairs; consecutive edges of one bucket are merged into one piece. */
  coordinates: number[][];
}

export function routePieces(route: RouteFeature): RoutePiece[] {
  const coords = route.geometry.coordinates;
  const index = route.properties.edge_coordinate_index;
  const factors = route.properties.congestion_factors;
  if (coords.length < 2) return [];
  if (!index || !factors || index.length === 0 || index.length !== factors.length) {
    return [{ bucket: 'free', coordinates: coords }];
  }
  const pieces: RoutePiece[] = [];
  for (let i = 0; i < index.length; i++) {
    const start = Math.max(0, Math.min(index[i], coords.length - 1));
    const end = i + 1 < index.length ? Math.max(start, Math.min(index[i + 1], coords.length - 1)) : coords.length - 1;
    const bucket = bucketOf(factors[i]);
    const slice = coords.slice(start, end + 1);
    if (slice.length < 2) continue;
    const last = pieces[pieces.length - 1];
    if (last && last.bucket === bucket) last.coordinates.push(...slice.slice(1));
    else pieces.push({ bucket, coordinates: slice });
  }
  return pieces;
}
