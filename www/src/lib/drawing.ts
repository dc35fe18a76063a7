// Arrays ready for WebGL, built in the worker so the page's main thread only hands them to the
// GPU: polylines with a colour per vertex, the slit domain's rings, the heat map, loop edges.

import { heatColour, pathColour, type Rgb } from "./colors";
import { simplify } from "./simplify";

/** A polyline ready to draw as line segments. */
export interface Polyline {
  /** xyz per vertex (z = 0 in the plane). */
  positions: Float32Array;
  /** rgb per vertex: the path colour of its point. */
  colours: Float32Array;
  /** Pairs of vertex indices, one per segment (runs split at points that are not drawn). */
  segments: Uint32Array;
  /** The path point each vertex stands for. */
  points: Uint32Array;
}

/** Colour scales sampled once (a colour per point of a long path allocated arrays by the million). */
const LUT_SIZE = 1024;
function table(colour: (t: number) => Rgb): Float32Array {
  const lut = new Float32Array(3 * LUT_SIZE);
  for (let i = 0; i < LUT_SIZE; i++) lut.set(colour(i / (LUT_SIZE - 1)), 3 * i);
  return lut;
}
const PATH_LUT = table(pathColour);

/**
 * The path points `kept` (indices into `points`, `dim` values each) as a polyline coloured along
 * the whole path (`total` points). Consecutive kept points are joined unless a NaN point lies
 * between them.
 */
export function polyline(points: Float64Array, dim: 2 | 3, kept: Uint32Array, total: number): Polyline {
  const n = kept.length;
  const positions = new Float32Array(3 * n);
  const colours = new Float32Array(3 * n);
  const segments = new Uint32Array(2 * Math.max(0, n - 1));
  let s = 0;
  // The prefix count of NaN points tells whether a gap lies between two kept points.
  const gaps = new Uint32Array(total + 1);
  for (let i = 0; i < total; i++) gaps[i + 1] = gaps[i]! + (Number.isNaN(points[dim * i]!) ? 1 : 0);
  for (let k = 0; k < n; k++) {
    const i = kept[k]!;
    for (let c = 0; c < dim; c++) positions[3 * k + c] = points[dim * i + c]!;
    const lut = 3 * Math.round((total > 1 ? i / (total - 1) : 0) * (LUT_SIZE - 1));
    colours[3 * k] = PATH_LUT[lut]!;
    colours[3 * k + 1] = PATH_LUT[lut + 1]!;
    colours[3 * k + 2] = PATH_LUT[lut + 2]!;
    if (k > 0 && gaps[i] === gaps[kept[k - 1]! + 1]) {
      segments[s++] = k - 1;
      segments[s++] = k;
    }
  }
  return { positions, colours, segments: segments.slice(0, s), points: kept };
}

/** A polyline of the path points drawn within `tolerance` (see simplify). */
export function pathPolyline(points: Float64Array, dim: 2 | 3, tolerance: number): Polyline {
  return polyline(points, dim, simplify(points, dim, tolerance), points.length / dim);
}

/** Diagonal of the bounding box of the finite points (`dim` values each). */
export function extent(points: Float64Array, dim: 2 | 3): number {
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < points.length; i += dim) {
    if (Number.isNaN(points[i]!)) continue;
    for (let c = 0; c < dim; c++) {
      lo[c] = Math.min(lo[c]!, points[i + c]!);
      hi[c] = Math.max(hi[c]!, points[i + c]!);
    }
  }
  let d2 = 0;
  for (let c = 0; c < dim; c++) if (hi[c]! >= lo[c]!) d2 += (hi[c]! - lo[c]!) ** 2;
  return Math.sqrt(d2);
}

/** Plane points (xy pairs) as xyz with z = 0, for WebGL. */
export function planar(xy: Float64Array): Float32Array {
  const out = new Float32Array((xy.length / 2) * 3);
  for (let i = 0, j = 0; i < xy.length; i += 2, j += 3) {
    out[j] = xy[i]!;
    out[j + 1] = xy[i + 1]!;
  }
  return out;
}

/**
 * Circles of the given radii about the origin as line segments (xyz pairs), each with as many
 * sides as keep its chords within `tolerance` of it (8 at least).
 */
export function circles(radii: Float64Array, tolerance: number): Float32Array {
  const sides = [...radii].map((r) => (r > tolerance ? Math.max(8, Math.ceil(Math.PI / Math.acos(1 - tolerance / r))) : 8));
  const out = new Float32Array(sides.reduce((n, k) => n + 6 * k, 0));
  let o = 0;
  radii.forEach((r, i) => {
    const k = sides[i]!;
    for (let j = 0; j < k; j++) {
      const [a, b] = [(2 * Math.PI * j) / k, (2 * Math.PI * (j + 1)) / k];
      out.set([r * Math.cos(a), r * Math.sin(a), 0, r * Math.cos(b), r * Math.sin(b), 0], o);
      o += 6;
    }
  });
  return out;
}

/** rgb per vertex of the verifier's scallop heat map, scaled to the limit h. */
export function heatColours(scallop: Float64Array, limit: number): Float32Array {
  const out = new Float32Array(scallop.length * 3);
  // Within the limit the scale is sampled; beyond it (and uncovered) its own colours.
  const lut = table((t) => heatColour(t * limit, limit));
  for (let v = 0; v < scallop.length; v++) {
    const s = scallop[v]!;
    if (!(s >= 0 && s <= limit)) {
      out.set(heatColour(s, limit), 3 * v);
      continue;
    }
    const i = 3 * Math.round((s / limit) * (LUT_SIZE - 1));
    out[3 * v] = lut[i]!;
    out[3 * v + 1] = lut[i + 1]!;
    out[3 * v + 2] = lut[i + 2]!;
  }
  return out;
}

/** The edges of boundary loops as vertex index pairs (each loop closed). */
export function loopEdges(loops: Uint32Array[]): Uint32Array {
  const out = new Uint32Array(2 * loops.reduce((n, loop) => n + loop.length, 0));
  let o = 0;
  for (const loop of loops) {
    for (let k = 0; k < loop.length; k++) {
      out[o++] = loop[k]!;
      out[o++] = loop[(k + 1) % loop.length]!;
    }
  }
  return out;
}
