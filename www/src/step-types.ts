// Types of the STEP entries of the core (issue 36): the faces of a file and seed 004's Coons
// band spiral (`planCoons`). Plain data; the Rust structs they mirror are named.

import type { Vec3 } from "./core";

/** Options of the STEP stage (Rust `slitpath::step::StepOptions`); every field optional. */
export interface StepOptions {
  /** Largest distance between a facet and the exact surface, mm. Default 0.01. */
  chordalTolMm?: number;
  /** Longest facet edge, mm. Default 1/50 of the model's diagonal. */
  maxEdgeMm?: number;
  /** Faces to use, by STEP id. Default all (when they form one open surface). */
  faces?: number[];
  /** Refused above this many triangles. Default 2 000 000. */
  maxTriangles?: number;
}

/** One face of a STEP file (Rust `slitpath::step::FaceInfo`, as `slitpath faces --json`). */
export interface StepFace {
  /** The ADVANCED_FACE's `#id`. */
  id: number;
  /** plane, cylinder, cone, sphere, torus, b-spline or rational b-spline. */
  surface: string;
  surface_id: number;
  /** Edge loops: 1 + holes. */
  loops: number;
  area_mm2: number;
  triangles: number;
  /** The largest facet-to-surface distance measured on it, mm. */
  chordal_error_mm: number;
  /** Edge uses of its loops whose parameters came from a PCURVE (the others were projected). */
  pcurve_edges: number;
  /** Edge uses whose pcurves lay off the edge (beyond a tenth of the chordal tolerance): projected instead. */
  pcurves_off_surface: number;
  /** Faces sharing an edge with it. */
  adjacent: number[];
}

/** The faces of a STEP file, tessellated (the facade's `stepFaces`; plain arrays, as the core serialises them). */
export interface StepFacesOutput {
  faces: StepFace[];
  /** xyz per vertex (welded: faces share their edges' vertices). */
  positions: number[];
  triangles: number[];
  /** STEP id of each triangle's face. */
  faceOfTriangle: number[];
  chordalErrorMm: number;
  readMs: number;
  tessellateMs: number;
}

/** Options of the Coons band spiral (the CLI's `slitpath coons`); every field optional. */
export interface CoonsOptions {
  radiusMm?: number;
  scallopMm?: number;
  /** 5 (default: a band faces every way round its loop) or 3. */
  axes?: 3 | 5;
  leadDeg?: number;
  tiltDeg?: number;
  /** ac (default), cl, linuxcnc or grbl. */
  post?: "ac" | "cl" | "linuxcnc" | "grbl";
  /** Composite-C¹ smoothing of the seams round the loop. Default true. */
  smooth?: boolean;
  feedMmMin?: number;
  plungeFeedMmMin?: number;
  spindleRpm?: number;
  /** Verifier samples (0 skips the verification). Default 100 000. */
  verifySamples?: number;
  partName?: string;
}

export interface CoonsJumps {
  crossings: number;
  max_deg: number;
  mean_deg: number;
}

/** The Coons plan's report (Rust `slitpath::coons::CoonsReport`, the CLI's `--report`). */
export interface CoonsReport {
  strategy: string;
  radius_mm: number;
  scallop_mm: number;
  chord_tolerance_mm: number;
  band: { around: number; across: number; rows: number[][] };
  levels: number;
  revolutions: number;
  nominal_stepover_mm: number;
  step_scale: number;
  min_spacing_mm: number;
  max_spacing_mm: number;
  seams: {
    mode: string;
    round_before: CoonsJumps;
    round_after: CoonsJumps;
    rows_before: CoonsJumps;
    rows_after: CoonsJumps;
    det_j_min_rel: number;
    seam_gap_mm: number;
    note?: string;
  };
  length_mm: number;
  points: number;
  retractions: number;
  max_turn_deg: number;
  time_min: number;
  verify_triangles: number;
  verify_chordal_error_mm: number;
  verify: { samples: number; max_scallop_mm: number; p95_scallop_mm: number; mean_scallop_mm: number; gouges: number; uncovered_fraction: number } | null;
  timings: Record<string, number>;
}

/** Everything a Coons plan produces, as plain data and typed arrays. */
export interface CoonsOutput {
  report: CoonsReport;
  gcode: string;
  /** xyz per path point (cutter contact), its unit normal, its STEP face. */
  pathContacts: Float64Array;
  pathNormals: Float64Array;
  pathFaces: Float64Array;
  /** xyz tool tip and unit axis per move. */
  pathTips: Float64Array;
  pathAxes: Float64Array;
  /** The scallop at each vertex of the part's surface under the path, mm (NaN: no pass over it), when the part is the band's faces. */
  vertexScallop?: Float64Array;
}

export type { Vec3 };
