// Mesh helpers shared by the worker and the views: boundary loops, point location in a planar
// image of the mesh (slit domain → flattened domain), and the path-point → toolpath-move match.

/** Boundary loops as vertex index lists (edges used by one triangle, chained), longest first. */
export function boundaryLoops(triangles: Uint32Array): Uint32Array[] {
  const key = (a: number, b: number) => a * 0x100000000 + b;
  const directed = new Set<number>();
  for (let t = 0; t < triangles.length; t += 3) {
    for (let k = 0; k < 3; k++) directed.add(key(triangles[t + k]!, triangles[t + ((k + 1) % 3)]!));
  }
  // A boundary edge a→b has no twin b→a; follow them head to tail.
  const next = new Map<number, number>();
  for (const e of directed) {
    const a = Math.floor(e / 0x100000000);
    const b = e - a * 0x100000000;
    if (!directed.has(key(b, a))) next.set(a, b);
  }
  const loops: Uint32Array[] = [];
  const seen = new Set<number>();
  for (const start of [...next.keys()].sort((x, y) => x - y)) {
    if (seen.has(start)) continue;
    const loop: number[] = [];
    let v: number | undefined = start;
    while (v !== undefined && !seen.has(v)) {
      seen.add(v);
      loop.push(v);
      v = next.get(v);
    }
    loops.push(Uint32Array.from(loop));
  }
  return loops.sort((a, b) => b.length - a.length);
}

/** Point location in a planar image of the mesh (`xy` per vertex), by a uniform grid of triangles. */
export class PlanarLocator {
  private readonly cells: Uint32Array;
  private readonly starts: Uint32Array;
  private readonly n: number;
  private readonly minX: number;
  private readonly minY: number;
  private readonly size: number;

  constructor(
    private readonly xy: Float64Array,
    private readonly triangles: Uint32Array,
  ) {
    let [minX, minY, maxX, maxY] = [Infinity, Infinity, -Infinity, -Infinity];
    for (let i = 0; i < xy.length; i += 2) {
      minX = Math.min(minX, xy[i]!);
      maxX = Math.max(maxX, xy[i]!);
      minY = Math.min(minY, xy[i + 1]!);
      maxY = Math.max(maxY, xy[i + 1]!);
    }
    const faces = triangles.length / 3;
    this.n = Math.max(1, Math.ceil(Math.sqrt(faces / 2)));
    this.minX = minX;
    this.minY = minY;
    this.size = Math.max(maxX - minX, maxY - minY, 1e-300) / this.n;
    // Two passes (count, fill) into one flat array: no per-cell arrays for big meshes.
    const counts = new Uint32Array(this.n * this.n + 1);
    this.forEachCell((cell) => counts[cell + 1]!++);
    for (let c = 1; c < counts.length; c++) counts[c]! += counts[c - 1]!;
    this.starts = counts.slice();
    this.cells = new Uint32Array(counts[counts.length - 1]!);
    const fill = counts.slice();
    this.forEachCell((cell, face) => (this.cells[fill[cell]!++] = face));
  }

  private cellOf(v: number, min: number): number {
    return Math.min(this.n - 1, Math.max(0, Math.floor((v - min) / this.size)));
  }

  private forEachCell(visit: (cell: number, face: number) => void): void {
    const { xy, triangles } = this;
    for (let f = 0; f < triangles.length / 3; f++) {
      let [x0, y0, x1, y1] = [Infinity, Infinity, -Infinity, -Infinity];
      for (let k = 0; k < 3; k++) {
        const v = triangles[3 * f + k]!;
        x0 = Math.min(x0, xy[2 * v]!);
        x1 = Math.max(x1, xy[2 * v]!);
        y0 = Math.min(y0, xy[2 * v + 1]!);
        y1 = Math.max(y1, xy[2 * v + 1]!);
      }
      const [i0, i1, j0, j1] = [this.cellOf(x0, this.minX), this.cellOf(x1, this.minX), this.cellOf(y0, this.minY), this.cellOf(y1, this.minY)];
      for (let j = j0; j <= j1; j++) for (let i = i0; i <= i1; i++) visit(j * this.n + i, f);
    }
  }

  /** The face containing (x, y) and its barycentric coordinates, or null outside the image. */
  locate(x: number, y: number): { face: number; bary: [number, number, number] } | null {
    const cell = this.cellOf(y, this.minY) * this.n + this.cellOf(x, this.minX);
    let best: { face: number; bary: [number, number, number] } | null = null;
    let bestMin = -Infinity;
    for (let c = this.starts[cell]!; c < this.starts[cell + 1]!; c++) {
      const f = this.cells[c]!;
      const bary = this.barycentric(f, x, y);
      const least = Math.min(...bary);
      if (least > bestMin) [best, bestMin] = [{ face: f, bary }, least];
    }
    // Tolerate points on an edge or a hair outside (rounding), not far outside.
    return best !== null && bestMin > -1e-6 ? best : null;
  }

  private barycentric(f: number, x: number, y: number): [number, number, number] {
    const { xy, triangles } = this;
    const [a, b, c] = [triangles[3 * f]!, triangles[3 * f + 1]!, triangles[3 * f + 2]!];
    const [ax, ay, bx, by, cx, cy] = [xy[2 * a]!, xy[2 * a + 1]!, xy[2 * b]!, xy[2 * b + 1]!, xy[2 * c]!, xy[2 * c + 1]!];
    const det = (bx - ax) * (cy - ay) - (cx - ax) * (by - ay);
    if (det === 0) return [-Infinity, -Infinity, -Infinity];
    const l1 = ((x - ax) * (cy - ay) - (cx - ax) * (y - ay)) / det;
    const l2 = ((bx - ax) * (y - ay) - (x - ax) * (by - ay)) / det;
    return [1 - l1 - l2, l1, l2];
  }

  /** Interpolates a per-vertex 2-vector field (e.g. uv) at (x, y); null outside the image. */
  map(x: number, y: number, field: Float64Array): [number, number] | null {
    const hit = this.locate(x, y);
    if (hit === null) return null;
    let [u, v] = [0, 0];
    for (let k = 0; k < 3; k++) {
      const vert = this.triangles[3 * hit.face + k]!;
      u += hit.bary[k]! * field[2 * vert]!;
      v += hit.bary[k]! * field[2 * vert + 1]!;
    }
    return [u, v];
  }
}

/** Maps every point of `points` (xy pairs, in the image `xy`) to `field` (NaN where not located). */
export function mapPoints(locator: PlanarLocator, points: Float64Array, field: Float64Array): Float64Array {
  const out = new Float64Array(points.length);
  for (let i = 0; i < points.length; i += 2) {
    const p = locator.map(points[i]!, points[i + 1]!, field);
    out[i] = p?.[0] ?? NaN;
    out[i + 1] = p?.[1] ?? NaN;
  }
  return out;
}

/**
 * For each path point (cutter contact), the toolpath move nearest to it, matched monotonically:
 * the moves follow the path in order (with lead-in/out moves before and after).
 */
export function matchMoves(contacts: Float64Array, tips: Float64Array): Uint32Array {
  const points = contacts.length / 3;
  const moves = tips.length / 3;
  const out = new Uint32Array(points);
  if (moves === 0) return out;
  const d2 = (i: number, j: number) =>
    (contacts[3 * i]! - tips[3 * j]!) ** 2 + (contacts[3 * i + 1]! - tips[3 * j + 1]!) ** 2 + (contacts[3 * i + 2]! - tips[3 * j + 2]!) ** 2;
  let j = 0;
  // The first contact: the nearest of the moves that can be lead-in (at most moves − points of them).
  const leadIn = Math.max(1, moves - points + 1);
  for (let k = 1; k < Math.min(moves, leadIn); k++) if (d2(0, k) < d2(0, j)) j = k;
  for (let i = 0; i < points; i++) {
    while (j + 1 < moves && d2(i, j + 1) <= d2(i, j)) j++;
    out[i] = j;
  }
  return out;
}
