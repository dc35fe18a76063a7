// The ONE module that loads the WebAssembly planner core (wasm-pack output in ../pkg).
// Everything else imports the types and helpers it needs from here, never from ../pkg, so the
// rest of the page does not depend on how the core is built. It runs inside the worker.

import init, { type CoonsPlan as CoreCoonsPlan, type FlankPlan as CoreFlankPlan, Planner, StepFile as CoreStepFile, isStep as coreIsStep, planCoons as corePlanCoons, planFlank as corePlanFlank, planFlankOnStepFile as corePlanFlankOnStepFile, version } from "../pkg/slitpath.js";
import type { FlankOptions, FlankOutput, FlankReport } from "./flank-types";
import type { CoonsOptions, CoonsOutput, CoonsReport, StepFace, StepFacesOutput, StepOptions } from "./step-types";

export type * from "./flank-types";
export type * from "./step-types";

/** Options of the mesh stage; every field is optional (defaults live in the Rust core). */
export interface MeshOptions {
  /** Direction the tool comes from, towards the tool. Default [0, 0, 1]. */
  toolAxis?: [number, number, number];
  /** Closed solids: faces within this angle of the tool axis are the machined top. Default 80. */
  wallAngleDeg?: number;
  /** Weld tolerance as a fraction of the bounding-box diagonal. Default 1e-6. */
  weldToleranceRel?: number;
  /** Inputs with more triangles are refused. Default 5 000 000. */
  maxTriangles?: number;
}

export type Vec3 = [number, number, number];
export type Vec2 = [number, number];

/** One handle's cut (mesh::handles::HandleCut). */
export interface HandleCut {
  /** Length of what is cut (the loop's edges off the rims), mm. */
  length_mm: number;
  /** What the handle's shortest loop would cut, mm. */
  shortest_mm: number;
  loop_length_mm: number;
  /** Distance from the cut to the nearer end of the handle's neck (about the overhangs' length), mm. */
  depth_mm: number;
  /** Whether the cut crosses the shortest loop (across the plate between a bridge's feet). */
  crossing: boolean;
  cut_edges: number;
  rim_edges: number;
  vertex_ids: number[];
  polyline_mm: [number, number, number][];
}

/** The mesh stage's report (Rust `slitpath::mesh::MeshReport`, as `slitpath info --json`). */
export interface MeshReport {
  vertices: number;
  faces: number;
  edges: number;
  components: number;
  boundary_loops: number;
  /** Vertex count of each boundary loop, outer loop first. */
  loop_vertex_counts: number[];
  euler_characteristic: number;
  genus: number;
  closed: boolean;
  /** The loops a surface of genus > 0 was cut along to plan it, one per handle (absent for genus 0). */
  handle_cuts?: HandleCut[];
  degenerate_faces_dropped: number;
  duplicate_faces_dropped: number;
  pinch_vertices_split: number;
  faces_reoriented: number;
  faces_in_other_components: number;
  area_mm2: number;
  /** [[min x, min y, min z], [max x, max y, max z]], millimetres. */
  bbox: [Vec3, Vec3];
  /** Closed solids: the same figures for the extracted machinable top surface. */
  machined?: MeshReport;
}

/** The surface to machine as flat arrays, ready for WebGL. */
export interface SurfaceMesh {
  /** xyz per vertex. */
  positions: Float32Array;
  /** Three vertex indices per triangle. */
  triangles: Uint32Array;
  /** Unit vertex normals, xyz per vertex. */
  normals: Float32Array;
  /** Boundary loops (vertex indices): the outer loop, then the holes in the order `hole:N` counts them. */
  loops: Uint32Array[];
}

/** Where the spiral is centred: see the CLI's `--origin`. */
export type OriginOption =
  | "auto"
  | "centroid"
  | `hole:${number}`
  /** A pole in the flattened plane. */
  | { x: number; y: number }
  /** A 3D point near the surface. */
  | { x: number; y: number; z: number };

/** Options of one plan; every field optional, defaults equal the CLI's. Unknown fields are an error. */
export interface PlanOptions {
  radiusMm?: number;
  scallopMm?: number;
  axes?: 3 | 5;
  leadDeg?: number;
  tiltDeg?: number;
  direction?: "inward" | "outward";
  cut?: "climb" | "conventional";
  origin?: OriginOption;
  post?: "linuxcnc" | "grbl" | "ac" | "cl";
  feedMmMin?: number;
  plungeFeedMmMin?: number;
  spindleRpm?: number;
  /** `null`: automatic. */
  safeZMm?: number | null;
  verifySamples?: number;
  /** Name in the G-code header (the CLI uses the file name without extension). Default "part". */
  partName?: string;
  /**
   * "exact" (default): the STL is the part, the ball never enters a facet. "smooth": the STL
   * tessellates a smooth surface, the ball follows the vertex normals and dips into the facets
   * no deeper than they deviate from them.
   */
  facets?: "exact" | "smooth";
  /**
   * "tpsfo" (default): seed 003's scalar-field optimisation, rings that follow the surface
   * (shorter paths); "none": the conformal slit map's circles (seed 000).
   */
  optimise?: "tpsfo" | "none";
  /** Seed 003's α on the paper's scale: larger gives smoother, longer paths. Default 10. */
  alpha?: number;
  /**
   * "none" (default): every meridian of the field gets the rings its worst one needs. "need":
   * a path whose rings are spread by each meridian's own need is planned first, and written when
   * it keeps h (planning takes about 1.6 times as long).
   */
  spread?: "none" | "need";
}

/** What seed 003's optimisation did (the report's `optimise` section). */
export interface OptimiseReport {
  /** "tpsfo" when the path follows the optimised field, "conformal" when the planner kept the slit map's own. */
  path_field: "tpsfo" | "conformal";
  /** Why the conformal map's path was written instead. */
  fallback?: string;
  /** The optimised path's length when it was not kept, mm. */
  optimised_length_mm?: number;
  iterations?: number;
  stop?: string;
  /** E_w over twice the area at the start and the end (1 = the predicted scallop uniform along every level). */
  uniformity_before?: number;
  uniformity_after?: number;
  before?: { e_w: number; e_n: number; e_g: number; total: number };
  after?: { e_w: number; e_n: number; e_g: number; total: number };
}

/** A path spaced again because its verification left more than h (Rust `slitpath::plan::SpacingRetry`). */
export interface SpacingRetry {
  field: "tpsfo" | "conformal";
  /** The first path's target (fraction of h), what it left outside the facet valleys over h, its length. */
  target_fraction: number;
  max_over_h: number;
  length_mm: number;
  /** The same for the path spaced again (null when its plan failed: see `error`). */
  retry_target_fraction: number;
  retry_max_over_h: number | null;
  retry_length_mm: number | null;
  error?: string;
  /** Whether the path spaced again was kept. */
  kept: boolean;
}

/** With `spread: "need"`: the spread field's path against the other (the report's `spread`). */
export interface SpreadSummary {
  /** Whether the spread field's path was written (it keeps h as first spaced; else it is the shorter within h, or leaves less). */
  kept: boolean;
  /** The spread field's path: length and largest scallop over h (null when its plan failed: see `error`). */
  length_mm: number | null;
  max_over_h: number | null;
  /** The path without the spread: planned only when the spread one left more than h as first spaced (else null). */
  unspread_length_mm: number | null;
  unspread_max_over_h: number | null;
  error?: string;
}

/** The plan report: the CLI's `--report` JSON. */
export interface PlanReport {
  options: Record<string, unknown>;
  mesh: MeshReport;
  origin: {
    mode: string;
    pole_uv: Vec2;
    pole_3d: Vec3;
    e_min: number;
    e_min_centroid: number;
    uniformity: number;
    evaluations: number;
    /** Poles `auto` or `centroid` chose first but could not plan from (the next one was used). */
    rejected?: { pole_uv: Vec2; e_min: number; reason: string }[];
  };
  rings: unknown;
  /** Absent with `optimise: "none"`. */
  optimise?: OptimiseReport;
  /** Paths whose own verification left more than h outside the facet valleys, spaced again for a smaller cusp (absent when the first kept h). */
  spacing_retries?: SpacingRetry[];
  /** Present with `spread: "need"`. */
  spread?: SpreadSummary;
  path: {
    length_mm: number;
    /** The length over the flat-plate bound area / (2·√(2Rh)). */
    length_over_ideal: number;
    points: number;
    retractions: number;
    max_turn_deg: number;
    rho2: number;
    time_min: number;
    /** Ball centres moved off the facets (with `facets: "smooth"`, only those dipping deeper than the facets' own deviation from their normals). */
    clearance: { moved: number; max_move_mm: number; inserted: number; unresolved: number; merged: number };
  };
  verify: {
    max_scallop_mm: number;
    mean_scallop_mm: number;
    median_scallop_mm: number;
    p95_scallop_mm: number;
    p99_scallop_mm: number;
    v_max_mm2: number;
    uncovered_fraction: number;
    gouges: number;
    /** Faces where a ball riding the facets lifts more than 0.75 h (exact facets), mm². */
    valley_area_mm2: number;
    max_scallop_outside_valleys_mm: number;
    ct2: number;
    max_ct: number;
  };
  gouge_risk_area_mm2: number;
  /** With exact facets: the concave creases and pits where the facets alone leave more than h. */
  facet_valleys?: { edges: number; length_mm: number; max_depth_mm: number; pits: number };
  /** What to know before trusting the G-code, in words (e.g. facets too coarse for this h). */
  warnings: string[];
  /**
   * Rings the spacing could not prove everywhere: at P1 folds by slit tips, at concave creases
   * sharper than the ball, and where the gate still found a point of the band uncut.
   */
  fold_compromises: number;
  crease_compromises: number;
  gate_compromises: number;
  timings_ms: Record<string, number>;
}

/** Everything a plan produces, as plain data and typed arrays. */
export interface PlanOutput {
  report: PlanReport;
  gcode: string;
  /** Slit-map image w per vertex (re, im) for the chosen pole. */
  w: Float64Array;
  /** |w| of each ring. */
  ringRadii: Float64Array;
  /** xyz per path point (cutter contact). */
  pathContacts: Float64Array;
  /** w (re, im) per path point. */
  pathW: Float64Array;
  /** Surface face (index into the triangles) of each path point. */
  pathFaces: Uint32Array;
  /** Unit surface normal (towards the tool) per path point, xyz. */
  pathNormals: Float64Array;
  /** xyz tool tip per toolpath move (incl. lead-in/out). */
  pathTips: Float64Array;
  /** Unit tool axis per toolpath move. */
  pathAxes: Float64Array;
  /** Scallop height (mm) per surface vertex, NaN where uncovered. */
  vertexScallop: Float64Array;
}

export type ProgressCallback = (stage: string, done: number, total: number) => void;

/** The planning methods the facade adds to `Planner` (typed here so the page builds with either core). */
interface PlanningMethods {
  plan(options: object, onProgress?: ProgressCallback): unknown;
  planW(): Float64Array;
  pathFaces(): Uint32Array;
  pathNormals(): Float64Array;
  ringRadii(): Float64Array;
  pathContacts(): Float64Array;
  pathW(): Float64Array;
  pathTips(): Float64Array;
  pathAxes(): Float64Array;
  vertexScallop(): Float64Array;
  gcode(): string;
  energy(x: number, y: number): number;
}

let ready: Promise<void> | undefined;
let memory: WebAssembly.Memory | undefined;

/** Instantiates the wasm module once; later calls share the same promise. */
export function initCore(): Promise<void> {
  ready ??= init().then((core) => {
    memory = core.memory;
  });
  return ready;
}

/** Size of the core's linear memory, bytes: it never shrinks, so this is its peak so far. */
export function coreMemoryBytes(): number {
  return memory?.buffer.byteLength ?? 0;
}

/** The core's version, e.g. "0.1.0" (after initCore()). */
export function coreVersion(): string {
  return version();
}

/** One loaded part: owns the wasm-side Planner (free() it when replaced). */
export class Part {
  private constructor(private readonly planner: Planner) {}

  /** Reads and validates an STL; throws an Error whose message names the fault. */
  static async open(stl: Uint8Array, options?: MeshOptions, onProgress?: ProgressCallback): Promise<Part> {
    await initCore();
    return new Part(new Planner(stl, options, onProgress));
  }

  /** Reads the faces `stepOptions.faces` (default all) of a STEP file as the part; throws naming the `#id` at fault. */
  static async openStep(step: Uint8Array, options?: MeshOptions, stepOptions?: StepOptions): Promise<Part> {
    await initCore();
    return new Part(Planner.fromStep(step, options, stepOptions));
  }

  /**
   * The part made of faces `faces` of a STEP file already read (default: those it was read with,
   * or a solid's top faces), without reading or tessellating it again; the same part as
   * `openStep` makes of that selection. Throws naming the `#id` at fault.
   */
  static async fromStepModel(model: StepModel, options?: MeshOptions, faces?: number[]): Promise<Part> {
    await initCore();
    return new Part(Planner.fromStepFile(model.file, options, faces === undefined ? undefined : Float64Array.from(faces)));
  }

  /**
   * Builds the planner now (rim refinement, flattening, slit-map factorisation, facet index),
   * reporting each step; throws for a surface that cannot be planned (closed, genus > 0).
   */
  prepare(onProgress?: ProgressCallback): void {
    this.planner.prepare(onProgress);
  }

  report(): MeshReport {
    return this.planner.report() as MeshReport;
  }

  /** The scallop under a Coons plan's path at each vertex of this part's surface (its heat map). */
  coonsScallop(plan: CoreCoonsPlan): Float64Array {
    return plan.vertexScallopOn(this.planner);
  }

  /** STEP input: the faces the part is made of (the selection, or the top of a solid opened without one); `null` for an STL. */
  stepFaces(): number[] | null {
    const ids = this.planner.stepFaceIds();
    return ids ? Array.from(ids) : null;
  }

  surface(): SurfaceMesh {
    const vertices = this.planner.loopVertices();
    let start = 0;
    const loops = [...this.planner.loopLengths()].map((n) => vertices.slice(start, (start += n)));
    return { positions: this.planner.positions(), triangles: this.planner.triangles(), normals: this.planner.normals(), loops };
  }

  /** Flattened uv per vertex; throws for a surface that cannot be planned. */
  flattened(): Float64Array {
    return this.planner.flattened();
  }

  /** The slit-map image w per vertex for a pole (x, y) of the flattened plane. */
  slitMap(x: number, y: number): Float64Array {
    return this.planner.slitMap(x, y);
  }

  /** Whether this build of the core has the planning methods. */
  canPlan(): boolean {
    return typeof (this.planner as unknown as Partial<PlanningMethods>).plan === "function";
  }

  private planning(): PlanningMethods {
    if (!this.canPlan()) throw new Error("this build of the core cannot plan yet (it only flattens and maps)");
    return this.planner as unknown as PlanningMethods;
  }

  /** Plans with `options`; throws an Error with a readable message. */
  plan(options: PlanOptions, onProgress?: ProgressCallback): PlanOutput {
    const p = this.planning();
    const report = p.plan(options, onProgress) as PlanReport;
    return {
      report,
      gcode: p.gcode(),
      w: p.planW(),
      ringRadii: p.ringRadii(),
      pathContacts: p.pathContacts(),
      pathW: p.pathW(),
      pathFaces: p.pathFaces(),
      pathNormals: p.pathNormals(),
      pathTips: p.pathTips(),
      pathAxes: p.pathAxes(),
      vertexScallop: p.vertexScallop(),
    };
  }

  /** E_min for a pole (x, y) of the flattened plane. */
  energy(x: number, y: number): number {
    return this.planning().energy(x, y);
  }

  free(): void {
    this.planner.free();
  }
}

/**
 * Plans flank strips (5-axis, conical tool, seed 002) for the STL `stl`, or (STEP bytes) the
 * file's faces `stepOptions.faces` (default all); throws an Error whose message names the fault
 * (bad tool, rigidity not reached, …). The flank planner needs only the mesh, not the slit map:
 * it reads the file itself (a STEP file already open: `planFlankOnStepModel`).
 */
export async function planFlank(stl: Uint8Array, meshOptions: MeshOptions | undefined, options: FlankOptions, onProgress?: ProgressCallback, stepOptions?: StepOptions): Promise<FlankOutput> {
  await initCore();
  return flankOutput(corePlanFlank(stl, meshOptions, options, onProgress, stepOptions));
}

/**
 * `planFlank` on the faces `faces` of a STEP file already read (default: those it was read
 * with, or a solid's top faces), without reading or tessellating it again: the part
 * `Part.fromStepModel` makes of them, and the same plan as `planFlank` of the file's bytes with
 * that selection.
 */
export async function planFlankOnStepModel(model: StepModel, faces: number[] | undefined, meshOptions: MeshOptions | undefined, options: FlankOptions, onProgress?: ProgressCallback): Promise<FlankOutput> {
  await initCore();
  return flankOutput(corePlanFlankOnStepFile(model.file, faces === undefined ? undefined : Float64Array.from(faces), meshOptions, options, onProgress));
}

/** The plan's report and arrays; frees the core's plan. */
function flankOutput(plan: CoreFlankPlan): FlankOutput {
  try {
    return {
      report: plan.report() as FlankReport,
      gcode: plan.gcode(),
      tips: plan.tips(),
      axes: plan.axes(),
      stripMoves: plan.stripMoves(),
      positions: plan.positions(),
      triangles: plan.triangles(),
      vertexDeviation: plan.vertexDeviation(),
      contactPoints: plan.contactPoints(),
      contactSamples: plan.contactSamples(),
      posesPerStrip: plan.posesPerStrip(),
    };
  } finally {
    plan.free();
  }
}

/** Whether the bytes are a STEP file (by content: `ISO-10303-21;`). */
export async function isStep(bytes: Uint8Array): Promise<boolean> {
  await initCore();
  return coreIsStep(bytes);
}

/**
 * A STEP file read and tessellated once (all its faces, or `stepOptions.faces`): its faces for a
 * page to list and pick, and parts of any selection of them (`Part.fromStepModel`, and the flank
 * strategy's `planFlankOnStepModel`). Holds wasm
 * memory until `free()`.
 */
export class StepModel {
  /** The core's handle (for `Part.fromStepModel`, `planFlankOnStepModel` and `planCoons`). */
  private constructor(readonly file: CoreStepFile) {}

  /** Reads and tessellates `step`; throws an Error naming the `#id` at fault. */
  static async open(step: Uint8Array, stepOptions?: StepOptions, onProgress?: ProgressCallback): Promise<StepModel> {
    await initCore();
    return new StepModel(new CoreStepFile(step, stepOptions, onProgress));
  }

  /** The faces and their tessellation. */
  faces(): StepFacesOutput {
    const out = this.file.faces() as {
      faces: StepFace[];
      positions: number[];
      triangles: number[];
      face_of_triangle: number[];
      chordal_error_mm: number;
      read_ms: number;
      tessellate_ms: number;
    };
    // The arrays stay as the core serialised them: stepDrawing reads each once into its own.
    return {
      faces: out.faces,
      positions: out.positions,
      triangles: out.triangles,
      faceOfTriangle: out.face_of_triangle,
      chordalErrorMm: out.chordal_error_mm,
      readMs: out.read_ms,
      tessellateMs: out.tessellate_ms,
    };
  }

  free(): void {
    this.file.free();
  }
}

/** The faces of a STEP file, tessellated (all, or `stepOptions.faces`); throws naming the `#id` at fault. */
export async function stepFaces(step: Uint8Array, stepOptions?: StepOptions, onProgress?: ProgressCallback): Promise<StepFacesOutput> {
  const model = await StepModel.open(step, stepOptions, onProgress);
  try {
    return model.faces();
  } finally {
    model.free();
  }
}

/**
 * Plans seed 004's Coons spiral over the band of faces `faces` of a STEP file already open (not
 * read again); throws an Error whose message says why when the faces are not a closed band of
 * four-sided faces. With `part` (those faces made the part), the scallop at its vertices too.
 */
export async function planCoons(model: StepModel, faces: number[], options: CoonsOptions, part?: Part): Promise<CoonsOutput> {
  await initCore();
  const plan = corePlanCoons(model.file, Float64Array.from(faces), options);
  try {
    return {
      report: plan.report() as CoonsReport,
      gcode: plan.gcode(),
      pathContacts: plan.pathContacts(),
      pathNormals: plan.pathNormals(),
      pathFaces: plan.pathFaces(),
      pathTips: plan.tips(),
      pathAxes: plan.axes(),
      ...(part ? { vertexScallop: part.coonsScallop(plan) } : {}),
    };
  } finally {
    plan.free();
  }
}

/** The readable message of anything thrown by the core. */
export function errorMessage(error: unknown): string {
  if (error instanceof Error) return error.message;
  return String(error);
}

/** A trap (a panic in the core) leaves the wasm instance unusable: the worker must be replaced. */
export function isFatal(error: unknown): boolean {
  return error instanceof WebAssembly.RuntimeError;
}
