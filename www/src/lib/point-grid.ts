// Nearest point of a big planar point set (the path in a 2D pane) under the pointer: a uniform
// grid built once per plan in the worker (flat arrays), queried on the main thread per hover in
// a few cells instead of a pass over every point.

export interface PointGrid {
  minX: number;
  minY: number;
  /** Cell side, in the points' units. */
  cell: number;
  nx: number;
  ny: number;
  /** Cell c holds the points order[starts[c] .. starts[c + 1]]. */
  starts: Uint32Array;
  order: Uint32Array;
}

/** A grid of about `perCell` points per occupied cell over the finite points of `xy` (pairs). */
export function buildPointGrid(xy: Float64Array, perCell = 4): PointGrid {
  let [minX, minY, maxX, maxY, count] = [Infinity, Infinity, -Infinity, -Infinity, 0];
  for (let i = 0; i < xy.length; i += 2) {
    const [x, y] = [xy[i]!, xy[i + 1]!];
    if (Number.isNaN(x) || Number.isNaN(y)) continue;
    [minX, maxX, minY, maxY] = [Math.min(minX, x), Math.max(maxX, x), Math.min(minY, y), Math.max(maxY, y)];
    count++;
  }
  if (count === 0) return { minX: 0, minY: 0, cell: 1, nx: 1, ny: 1, starts: new Uint32Array(2), order: new Uint32Array(0) };
  const [w, h] = [Math.max(maxX - minX, 1e-12), Math.max(maxY - minY, 1e-12)];
  const cell = Math.max(Math.sqrt((w * h * perCell) / count), Math.max(w, h) / 4096);
  const [nx, ny] = [Math.floor(w / cell) + 1, Math.floor(h / cell) + 1];
  // Counting sort of the points by cell: the cells once, then two passes, no per-cell arrays.
  const n = xy.length / 2;
  const cells = new Int32Array(n);
  const starts = new Uint32Array(nx * ny + 1);
  for (let i = 0; i < n; i++) {
    const [x, y] = [xy[2 * i]!, xy[2 * i + 1]!];
    const c = Number.isNaN(x) || Number.isNaN(y) ? -1 : Math.floor((y - minY) / cell) * nx + Math.floor((x - minX) / cell);
    cells[i] = c;
    if (c >= 0) starts[c + 1]!++;
  }
  for (let c = 1; c < starts.length; c++) starts[c]! += starts[c - 1]!;
  const fill = starts.slice(0, -1);
  const order = new Uint32Array(count);
  for (let i = 0; i < n; i++) if (cells[i]! >= 0) order[fill[cells[i]!]!++] = i;
  return { minX, minY, cell, nx, ny, starts, order };
}

/** The index of the point of `xy` nearest (x, y) within `radius`, or -1. */
export function nearestPoint(grid: PointGrid, xy: Float64Array, x: number, y: number, radius: number): number {
  const { minX, minY, cell, nx, ny, starts, order } = grid;
  const clamp = (v: number, n: number) => Math.min(n - 1, Math.max(0, v));
  const [i0, i1] = [clamp(Math.floor((x - radius - minX) / cell), nx), clamp(Math.floor((x + radius - minX) / cell), nx)];
  const [j0, j1] = [clamp(Math.floor((y - radius - minY) / cell), ny), clamp(Math.floor((y + radius - minY) / cell), ny)];
  let [best, bestD] = [-1, radius * radius];
  for (let j = j0; j <= j1; j++) {
    for (let i = i0; i <= i1; i++) {
      const c = j * nx + i;
      for (let k = starts[c]!; k < starts[c + 1]!; k++) {
        const p = order[k]!;
        const d = (xy[2 * p]! - x) ** 2 + (xy[2 * p + 1]! - y) ** 2;
        if (d < bestD || (d === bestD && p < best)) [best, bestD] = [p, d];
      }
    }
  }
  return best;
}
