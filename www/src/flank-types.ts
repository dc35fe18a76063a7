// Types of the flank strategy (seed 002, issue 35: 5-axis flank milling with a conical tool) as the
// core's facade `planFlank` takes and returns them. Types only; core.ts calls the core.

import type { Vec3 } from "./core";

/**
 * Options of a flank plan; every field optional, defaults equal the core's `FlankOptions::default()`
 * (the CLI `slitpath flank` asks for the tool and the direction explicitly). Unknown fields are an
 * error.
 */
export interface FlankOptions {
  /** Radius of the flute at the tool's tip, mm. Default 1.5. */
  tipRadiusMm?: number;
  /** Radius of the flute at its top (towards the shank), mm. Default 2.5. */
  topRadiusMm?: number;
  /** Length of the flute along the tool axis, mm. Default 20. */
  fluteLengthMm?: number;
  /** Machining direction (any length): the strips run along it. Default [1, 0, 0]. */
  direction?: Vec3;
  /** Number of strips. Default: as many as fit across the surface. */
  strips?: number;
  /** Spacing of the poses along the guiding curves, mm. Default: 1/100 of the part's diagonal. */
  poseStepMm?: number;
  /** Samples per tool axis (seed 002 eq. 11). Default 30. */
  samplesPerAxis?: number;
  /**
   * "accuracy" (w₂ = 1, w₃ = 10⁻³, default), "g1" (w₂ = 10⁻⁴, w₃ = 1: smoother strip boundaries)
   * or [w₂, w₃].
   */
  weights?: "accuracy" | "g1" | [number, number];
  /** "ac" (5-axis table-table A/C with TCP, default) or "cl" (APT CL data). */
  post?: "ac" | "cl";
  chordToleranceMm?: number;
  angleToleranceDeg?: number;
  /** Radius of the shank (or neck) above the flutes, mm. Default: the top radius. */
  shankRadiusMm?: number;
  /** Gauge length, from the tool tip to the holder's face, mm. Default: 3 × the flute length. */
  gaugeLengthMm?: number;
  /** Radius of the holder, mm. Default: twice the shank radius. */
  holderRadiusMm?: number;
  /** Length of the holder along the axis from its face, mm. Default 40. */
  holderLengthMm?: number;
  /** Clearance wanted from the holder and, on rapids, the flutes, mm. Default 1. */
  collisionMarginMm?: number;
  retractMm?: number;
  /** Every other strip backwards (short links). Default true. */
  zigzag?: boolean;
  feedMmMin?: number;
  plungeFeedMmMin?: number;
  spindleRpm?: number;
  decimals?: number;
  /** Flank verifier samples (0 skips the verification). Default 20 000. */
  verifySamples?: number;
  /** Name in the program header (the CLI uses the file name without extension). Default "part". */
  partName?: string;
}

/** The tool above the flutes as the collision check sees it (Rust `slitpath::flank::collision::ToolBody`). */
export interface FlankToolBody {
  shank_radius_mm: number;
  /** From the tool tip to the holder's face. */
  gauge_length_mm: number;
  holder_radius_mm: number;
  holder_length_mm: number;
  margin_mm: number;
}

/** Deviation figures of one strip, mm (positive: material left, negative: gouge). */
export interface FlankStripDeviation {
  strip: number;
  moves: [number, number];
  samples: number;
  mean_abs_mm: number;
  rms_mm: number;
  p95_abs_mm: number;
  p99_abs_mm: number;
  max_abs_mm: number;
  max_mm: number;
  min_mm: number;
}

/** Figures at the boundary between two adjacent strips. */
export interface FlankSeam {
  strips: [number, number];
  envelope_points: number;
  envelope_not_real: number;
  envelope_max_kink_deg: number;
  envelope_mean_kink_deg: number;
  envelope_max_gap_mm: number;
  envelope_mean_gap_mm: number;
  seam_samples: number;
  sample_max_kink_deg: number;
  sample_max_gap_mm: number;
}

/** The flank verifier's report (Rust `slitpath::verify::flank::FlankVerification`). */
export interface FlankVerification {
  samples: number;
  strips_found: number;
  segments: number;
  machined_samples: number;
  machined_fraction: number;
  uncovered_samples: number;
  max_gouge_mm: number;
  gouges: number;
  max_undercut_mm: number;
  coverage_within_tolerance: number;
  machined_within_tolerance: number;
  tolerance_mm: number;
  worst_gouge_at: Vec3 | null;
  worst_undercut_at: Vec3 | null;
  strips: FlankStripDeviation[];
  seams: FlankSeam[];
  max_axis_norm_error: number;
  kinematics: {
    max_a_step_deg: number;
    max_c_step_deg: number;
    c_flips: number;
    a_sign_changes: number;
    near_singular_moves: number;
    a_out_of_range: number | null;
  };
}

/** max | |b − a| − L |, the envelope misfit and the G¹ angle of the pose grid. */
export interface FlankGridFigures {
  max_rigidity_error_mm: number;
  max_distance_error_mm: number;
  min_distance_error_mm: number;
  max_g1_angle_deg: number;
}

/** The flank plan report: the CLI's `slitpath flank --report` JSON (Rust `slitpath::flank::FlankReport`). */
export interface FlankReport {
  strategy: string;
  options: {
    /** The flutes and the tool above them (defaults resolved). */
    tool: { tip_radius_mm: number; top_radius_mm: number; flute_length_mm: number } & FlankToolBody;
    direction: Vec3;
    strips: number | null;
    pose_step_mm: number;
    samples_per_axis: number;
    weights: { rigid: number; approx: number; g1: number; ini: number; fair: number };
    rigidity_tolerance_rel: number;
    chord_tolerance_mm: number;
    angle_tolerance_deg: number;
    post: string;
    decimals: number;
  };
  /** The seed's sphere family of the tool: r₁, r₂, L. */
  spheres: { r1_mm: number; r2_mm: number; length_mm: number; delta_r_mm: number };
  surface_vertices: number;
  surface_faces: number;
  surface_area_mm2: number;
  guide: { strips: number; poses_per_strip: number[]; field_rms_misfit: number };
  optimise: {
    outer_iterations: number;
    lbfgs_iterations: number;
    initial: FlankGridFigures;
    final_figures: FlankGridFigures;
    max_move_mm: number;
    rigid_projection_mm: number;
  };
  envelope: { contact_samples: number; not_real: number };
  output: {
    moves: number;
    cut_poses: number;
    cut_length_mm: number;
    link_length_mm: number;
    rapid_length_mm: number;
    max_axis_step_deg: number;
    estimated_time_s: number;
    safe_z_mm: number;
  };
  collisions: {
    /** The tool above the flutes, defaults resolved. */
    tool: FlankToolBody;
    checked_moves: number;
    /** One per flagged move: its kind, the tool part met, its clearance (negative: inside) and where. */
    flagged: {
      move_index: number;
      kind: "cut" | "approach" | "lead-out" | "rapid" | "retract";
      strip: number | null;
      what: "holder" | "shank" | "flute";
      clearance_mm: number;
      at: [number, number, number];
    }[];
    min_clearance_mm: number | null;
  };
  /** Absent (null) with `verifySamples: 0`. */
  verify: FlankVerification | null;
  timings_ms: Record<string, number>;
}

/** Everything a flank plan produces, as plain data and typed arrays. */
export interface FlankOutput {
  report: FlankReport;
  /** The program (A/C G-code or CL data, as asked). */
  gcode: string;
  /** xyz tool tip per move (approaches, links and retracts included). */
  tips: Float64Array;
  /** Unit tool axis per move, xyz. */
  axes: Float64Array;
  /** Each strip's cutting moves, [first, end) pairs (end exclusive): `[first0, end0, first1, …]`. */
  stripMoves: Uint32Array;
  /** The surface the plan was made on: xyz per vertex and three vertex indices per triangle. */
  positions: Float32Array;
  triangles: Uint32Array;
  /** The verifier's deviation per surface vertex, mm (positive: material left; NaN: uncovered). */
  vertexDeviation: Float64Array;
  /** The envelope's contact curves (seed 002 eqs. 5–6): `contactSamples` xyz points per optimised pose, strip after strip; NaN where the envelope is not real. */
  contactPoints: Float64Array;
  contactSamples: number;
  /** Optimised poses per strip (the contact curves' grouping). */
  posesPerStrip: Uint32Array;
}
