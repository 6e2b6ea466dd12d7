import { describe, expect, it } from 'vitest';
import { bucketOf, routePieces } from '../src/map/congestion';
import { route } from './fixtures';

describe('route split by congestion', () => {
  const coords = [
    [0, 0],
    [1, 0],
    [2, 0],
    [3, 0],
    [4, 0],
    [5, 0],
  ];

  it('gives each edge its piece of the line and merges neighbours of one bucket', () => {
    // Edges start at coordinates 0, 2, 3, 4: the last edge runs to the end.
    const pieces = routePieces(route(coords, [1, 1.1, 50, null], [0, 2, 3, 4]));
    expect(pieces).toEqual([
      { bucket: 'free', coordinates: [[0, 0], [1, 0], [2, 0], [3, 0]] },
      { bucket: 'heavy', coordinates: [[3, 0], [4, 0]] },
      { bucket: 'closed', coordinates: [[4, 0], [5, 0]] },
    ]);
  });

  it('draws the whole line as free flow when the server sends no factors', () => {
    expect(routePieces(route(coords))).toEqual([{ bucket: 'free', coordinates: coords }]);
  });

  it('buckets factors', () => {
    expect([1, 1.25, 1.5, 2, 2.01, 999, 1000, Infinity, null].map(bucketOf)).toEqual([
      'free', 'free', 'slow', 'slow', 'heavy', 'heavy', 'closed', 'closed', 'closed',
    ]);
  });
});
