// Mesh helpers of the worker: point location in a planar image of the mesh (slit domain →
// flattened domain), path points carried to the flattened plane through their faces,
// and the path-point → toolpath-move match.

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

/**
 * The per-vertex 2-vector `field` (e.g. uv) at each path point: `contacts` (xyz) lie on their
 * faces `faces` of the surface (`positions`, `triangles`), so barycentric coordinates in the face
 * carry them over. O(1) per point, no point location.
 */
export function pathField(
  contacts: Float64Array,
  faces: Uint32Array,
  positions: Float32Array,
  triangles: Uint32Array,
  field: Float64Array,
): Float64Array {
  const out = new Float64Array((contacts.length / 3) * 2);
  for (let i = 0; i < faces.length; i++) {
    const f = 3 * faces[i]!;
    const [a, b, c] = [triangles[f]!, triangles[f + 1]!, triangles[f + 2]!];
    const [ax, ay, az] = [positions[3 * a]!, positions[3 * a + 1]!, positions[3 * a + 2]!];
    // Barycentric coordinates of the contact projected onto the face's plane.
    const [e1x, e1y, e1z] = [positions[3 * b]! - ax, positions[3 * b + 1]! - ay, positions[3 * b + 2]! - az];
    const [e2x, e2y, e2z] = [positions[3 * c]! - ax, positions[3 * c + 1]! - ay, positions[3 * c + 2]! - az];
    const [qx, qy, qz] = [contacts[3 * i]! - ax, contacts[3 * i + 1]! - ay, contacts[3 * i + 2]! - az];
    const d11 = e1x * e1x + e1y * e1y + e1z * e1z;
    const d12 = e1x * e2x + e1y * e2y + e1z * e2z;
    const d22 = e2x * e2x + e2y * e2y + e2z * e2z;
    const q1 = qx * e1x + qy * e1y + qz * e1z;
    const q2 = qx * e2x + qy * e2y + qz * e2z;
    const det = d11 * d22 - d12 * d12;
    if (!(det > 0)) {
      out[2 * i] = out[2 * i + 1] = NaN;
      continue;
    }
    const l1 = (d22 * q1 - d12 * q2) / det;
    const l2 = (d11 * q2 - d12 * q1) / det;
    const l0 = 1 - l1 - l2;
    out[2 * i] = l0 * field[2 * a]! + l1 * field[2 * b]! + l2 * field[2 * c]!;
    out[2 * i + 1] = l0 * field[2 * a + 1]! + l1 * field[2 * b + 1]! + l2 * field[2 * c + 1]!;
  }
  return out;
}

/** How far ahead of the last match a path point's move may lie (moves split to clear a facet). */
const MATCH_LOOKAHEAD = 64;
/** A centre this near (mm²) is the point's own move: clearing moves centres by microns. */
const MATCH_CLOSE2 = 1e-4;

/**
 * For each path point, its toolpath move: the one whose ball centre (tip + R·axis) is nearest the
 * point's designed centre (contact + R·normal), matched in order. Clearing the facets moves a
 * centre by far less than the spacing of the points and adds a few moves between them, so the
 * nearest of the next moves is the point's own (and one within 0.01 mm ends the search).
 * (Matching contacts to tips instead jumps between rings where the surface slopes: a tip lies up
 * to R·|n − z| from its contact.)
 */
export function matchMoves(
  contacts: Float64Array,
  normals: Float64Array,
  tips: Float64Array,
  axes: Float64Array,
  radius: number,
): Uint32Array {
  const points = contacts.length / 3;
  const moves = tips.length / 3;
  const out = new Uint32Array(points);
  if (moves === 0) return out;
  // The first point: any of the moves that can be lead-in (at most moves − points of them) or just after.
  let j = 0;
  let reach = Math.max(1, moves - points + MATCH_LOOKAHEAD);
  for (let i = 0; i < points; i++) {
    const x = contacts[3 * i]! + radius * normals[3 * i]!;
    const y = contacts[3 * i + 1]! + radius * normals[3 * i + 1]!;
    const z = contacts[3 * i + 2]! + radius * normals[3 * i + 2]!;
    let [best, bestD] = [j, Infinity];
    for (let m = j; m < Math.min(moves, j + 1 + reach); m++) {
      const dx = tips[3 * m]! + radius * axes[3 * m]! - x;
      const dy = tips[3 * m + 1]! + radius * axes[3 * m + 1]! - y;
      const dz = tips[3 * m + 2]! + radius * axes[3 * m + 2]! - z;
      const d = dx * dx + dy * dy + dz * dz;
      if (d < bestD) [best, bestD] = [m, d];
      if (d < MATCH_CLOSE2) break;
    }
    out[i] = j = best;
    reach = MATCH_LOOKAHEAD;
  }
  return out;
}
