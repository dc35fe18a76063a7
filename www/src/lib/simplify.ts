// Level of detail for drawing a long polyline: the indices of the points to keep so that the kept
// polyline stays within `tolerance` of every point left out. What is planned and downloaded is
// never decimated: only what is drawn.

/** Pieces simplified one at a time: Douglas–Peucker is quadratic at worst (a spiral seen whole). */
const PIECE = 512;

/**
 * Douglas–Peucker simplification of a polyline of `dim`-dimensional points (flat array), in
 * pieces of at most PIECE points: NaN points split it and are never kept, the ends of every piece
 * are. A tolerance of 0 keeps every point. Iterative (an explicit stack).
 */
export function simplify(points: Float64Array, dim: 2 | 3, tolerance: number): Uint32Array {
  const n = points.length / dim;
  const keep = new Uint8Array(n);
  const t2 = tolerance * tolerance;
  const stack: number[] = [];
  for (let start = 0; start < n; ) {
    if (Number.isNaN(points[dim * start]!)) {
      start++;
      continue;
    }
    let end = start;
    while (end + 1 < n && end + 1 - start < PIECE && !Number.isNaN(points[dim * (end + 1)]!)) end++;
    keep[start] = keep[end] = 1;
    if (tolerance <= 0) keep.fill(1, start, end + 1);
    else stack.push(start, end);
    while (stack.length > 0) {
      const b = stack.pop()!;
      const a = stack.pop()!;
      let [worst, worstD] = [-1, t2];
      for (let i = a + 1; i < b; i++) {
        const d = segmentDistance2(points, dim, i, a, b);
        if (d > worstD) [worst, worstD] = [i, d];
      }
      if (worst < 0) continue;
      keep[worst] = 1;
      stack.push(a, worst, worst, b);
    }
    // The next piece starts where this one ended (a run goes on), or after it (a NaN follows).
    start = end + 1 < n && !Number.isNaN(points[dim * (end + 1)]!) && end > start ? end : end + 1;
  }
  let count = 0;
  for (let i = 0; i < n; i++) count += keep[i]!;
  const kept = new Uint32Array(count);
  for (let i = 0, k = 0; i < n; i++) if (keep[i]) kept[k++] = i;
  return kept;
}

/** Squared distance from point i to the segment from point a to point b (2D or 3D). */
function segmentDistance2(p: Float64Array, dim: number, i: number, a: number, b: number): number {
  const ia = dim * a;
  const ib = dim * b;
  const ii = dim * i;
  const abx = p[ib]! - p[ia]!;
  const aby = p[ib + 1]! - p[ia + 1]!;
  const abz = dim === 3 ? p[ib + 2]! - p[ia + 2]! : 0;
  const aix = p[ii]! - p[ia]!;
  const aiy = p[ii + 1]! - p[ia + 1]!;
  const aiz = dim === 3 ? p[ii + 2]! - p[ia + 2]! : 0;
  const ab2 = abx * abx + aby * aby + abz * abz;
  const t = ab2 > 0 ? Math.min(1, Math.max(0, (aix * abx + aiy * aby + aiz * abz) / ab2)) : 0;
  const dx = aix - t * abx;
  const dy = aiy - t * aby;
  const dz = aiz - t * abz;
  return dx * dx + dy * dy + dz * dz;
}
