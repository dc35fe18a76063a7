// The 3D view's arrays of a flank plan, built in the planner worker: the planned surface with
// its normals and the verifier's deviation as colours, and per strip the tool tips' path and the
// tool axes (the flute from the tip up) and the envelope's contact curves, decimated so a long
// program draws as fast as a short one.

import { STRIP_COLOURS, deviationColour } from "./colors";
import type { FlankOutput } from "../core";

/** What the 3D view draws of a flank plan. */
export interface FlankDrawing {
  /** Unit vertex normals of the planned surface, xyz per vertex. */
  normals: Float32Array;
  /** Deviation colours, rgb per vertex (see deviationColour), scaled to ±`limitMm`. */
  heat: Float32Array;
  /** The deviation scale's end, mm (the verifier's largest gouge or material left, at least 1 µm). */
  limitMm: number;
  /** Tool axes as line segments (xyz pairs), a rgb colour per vertex (the strip's). */
  axisLines: Float32Array;
  axisColours: Float32Array;
  /** The tips' path of every strip as line segments (xyz pairs), a colour per vertex. */
  tipLines: Float32Array;
  tipColours: Float32Array;
  /** The contact curves (where the cone touches the surface) of every drawn pose, as line segments, a colour per vertex. */
  envelopeLines: Float32Array;
  envelopeColours: Float32Array;
}

/** At most this many tool axes per strip are drawn: more only darken the view. */
const AXES_PER_STRIP = 48;

/** Area-weighted vertex normals (the facet normals summed at each corner). */
export function vertexNormals(positions: Float32Array, triangles: Uint32Array): Float32Array {
  const normals = new Float32Array(positions.length);
  for (let t = 0; t < triangles.length; t += 3) {
    const [a, b, c] = [3 * triangles[t]!, 3 * triangles[t + 1]!, 3 * triangles[t + 2]!];
    const [ux, uy, uz] = [positions[b]! - positions[a]!, positions[b + 1]! - positions[a + 1]!, positions[b + 2]! - positions[a + 2]!];
    const [vx, vy, vz] = [positions[c]! - positions[a]!, positions[c + 1]! - positions[a + 1]!, positions[c + 2]! - positions[a + 2]!];
    const [nx, ny, nz] = [uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx];
    for (const v of [a, b, c]) {
      normals[v] = normals[v]! + nx;
      normals[v + 1] = normals[v + 1]! + ny;
      normals[v + 2] = normals[v + 2]! + nz;
    }
  }
  for (let i = 0; i < normals.length; i += 3) {
    const length = Math.hypot(normals[i]!, normals[i + 1]!, normals[i + 2]!) || 1;
    for (let k = 0; k < 3; k++) normals[i + k] = normals[i + k]! / length;
  }
  return normals;
}

export function flankDrawing(plan: FlankOutput): FlankDrawing {
  const deviation = plan.vertexDeviation;
  // The verifier's extremes over the machined region: vertices off it (a rim no strip reaches)
  // can lie millimetres away and would flatten the scale; they show at its end.
  const v = plan.report.verify;
  const limitMm = Math.max(1e-3, v ? Math.max(v.max_gouge_mm, v.max_undercut_mm) : 0);
  const heat = new Float32Array(3 * deviation.length);
  deviation.forEach((d, i) => heat.set(deviationColour(d, limitMm), 3 * i));
  // The tool's flute: from the tip up the axis, as long as the flute is.
  const flute = plan.report.options.tool.flute_length_mm;
  const axes: number[] = [];
  const axisColours: number[] = [];
  const tips: number[] = [];
  const tipColours: number[] = [];
  const { tips: t, axes: a, stripMoves } = plan;
  for (let s = 0; 2 * s + 1 < stripMoves.length; s++) {
    const [first, end] = [stripMoves[2 * s]!, stripMoves[2 * s + 1]!];
    const colour = STRIP_COLOURS[s % STRIP_COLOURS.length]!;
    const step = Math.max(1, Math.ceil((end - first) / AXES_PER_STRIP));
    for (let m = first; m < end; m++) {
      if ((m - first) % step === 0 || m === end - 1) {
        axes.push(t[3 * m]!, t[3 * m + 1]!, t[3 * m + 2]!);
        axes.push(t[3 * m]! + flute * a[3 * m]!, t[3 * m + 1]! + flute * a[3 * m + 1]!, t[3 * m + 2]! + flute * a[3 * m + 2]!);
        axisColours.push(...colour, ...colour);
      }
      if (m + 1 < end) {
        tips.push(t[3 * m]!, t[3 * m + 1]!, t[3 * m + 2]!, t[3 * m + 3]!, t[3 * m + 4]!, t[3 * m + 5]!);
        tipColours.push(...colour, ...colour);
      }
    }
  }
  const envelope: number[] = [];
  const envelopeColours: number[] = [];
  const [k, c] = [plan.contactSamples, plan.contactPoints];
  let pose = 0;
  plan.posesPerStrip.forEach((poses, s) => {
    // The strip's colour, lighter: the contact curves lie on the surface, under the tips' path.
    const colour = STRIP_COLOURS[s % STRIP_COLOURS.length]!.map((x) => 0.5 + 0.5 * x);
    const step = Math.max(1, Math.ceil(poses / AXES_PER_STRIP));
    for (let p = 0; p < poses; p++, pose++) {
      if (p % step !== 0 && p !== poses - 1) continue;
      for (let j = 0; j + 1 < k; j++) {
        const [a, b] = [3 * (pose * k + j), 3 * (pose * k + j + 1)];
        if (!Number.isFinite(c[a]!) || !Number.isFinite(c[b]!)) continue;
        envelope.push(c[a]!, c[a + 1]!, c[a + 2]!, c[b]!, c[b + 1]!, c[b + 2]!);
        envelopeColours.push(...colour, ...colour);
      }
    }
  });
  return {
    normals: vertexNormals(plan.positions, plan.triangles),
    heat,
    limitMm,
    axisLines: new Float32Array(axes),
    axisColours: new Float32Array(axisColours),
    tipLines: new Float32Array(tips),
    tipColours: new Float32Array(tipColours),
    envelopeLines: new Float32Array(envelope),
    envelopeColours: new Float32Array(envelopeColours),
  };
}
