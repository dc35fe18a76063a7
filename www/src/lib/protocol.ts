// Messages between the main thread (SlitpathPlanner) and the planner worker. Types only.

import type { CoonsOptions, CoonsOutput, FlankOptions, FlankOutput, MeshOptions, MeshReport, PlanOptions, PlanOutput, StepFace, StepOptions } from "../core";
import type { CoonsDrawing } from "./coons-drawing";
import type { Polyline } from "./drawing";
import type { FlankDrawing } from "./flank-drawing";
import type { StepDrawing } from "./step-drawing";
import type { PointGrid } from "./point-grid";

/** A part as loaded by the worker: its report, the surface to draw, and its conformal preview. */
export interface LoadedPart {
  name: string;
  report: MeshReport;
  /** xyz per vertex of the surface to machine. */
  positions: Float32Array;
  /** Three vertex indices per triangle. */
  triangles: Uint32Array;
  /** Unit vertex normals, xyz per vertex, for shading. */
  normals: Float32Array;
  /** Boundary loops (vertex indices): the outer loop, then the holes in the order `hole:N` counts them. */
  loops: Uint32Array[];
  /** Flattened uv per vertex; null when the surface cannot be flattened (see conformalError). */
  uv: Float64Array | null;
  /** Slit-map image w per vertex for the centroid of the flattened vertices (a preview before planning). */
  previewW: Float64Array | null;
  /** Why there is no flattening (closed solid, genus > 0, …); null when there is one. */
  conformalError: string | null;
  /** Ready-to-draw arrays of the 2D view. */
  drawing: PartDrawing;
  /** Time to read, check and flatten, ms. */
  ms: number;
  /** The core's linear memory after loading (its peak so far), bytes. */
  wasmMemoryBytes: number;
  /** A STEP file: the STEP ids of the faces this surface is made of (else null). */
  stepFaces: number[] | null;
  /** A STEP file just loaded: all its faces (else null; `selectFaces` leaves it null). */
  step: StepPart | null;
}

/** A STEP file's faces as read by the worker: the list and the 3D view's arrays to pick them. */
export interface StepPart {
  name: string;
  faces: StepFace[];
  drawing: StepDrawing;
  /** The tessellation's measured chordal error, mm; read and tessellation times, ms. */
  chordalErrorMm: number;
  readMs: number;
  tessellateMs: number;
}

/** A Coons band plan's outputs plus what the 3D view draws of it (computed in the worker). */
export interface CoonsResult extends CoonsOutput {
  /** The faces planned, in the order given. */
  faces: number[];
  drawing: CoonsDrawing;
  /** Wall time of the plan in the worker, ms. */
  ms: number;
  wasmMemoryBytes: number;
}

/** The 2D view's arrays of a part, for WebGL (built in the worker). */
export interface PartDrawing {
  /** uv as xyz (z = 0) per vertex; null without a flattening. */
  uv: Float32Array | null;
  /** previewW as xyz (z = 0) per vertex; null without a preview. */
  previewW: Float32Array | null;
  /** Vertex index pairs of the outer loop's edges, and of the holes' edges. */
  outerEdges: Uint32Array;
  holeEdges: Uint32Array;
}

/** A plan's outputs plus what the views derive from them (computed in the worker). */
export interface PlanResult extends PlanOutput {
  /** uv (flattened plane) per path point, NaN where a point could not be located. */
  pathUv: Float64Array;
  /** For each path point, the index of its toolpath move (tips/axes). */
  moveOfPoint: Uint32Array;
  /** Ready-to-draw arrays of the views, with levels of detail (what is planned is never decimated). */
  drawing: PlanDrawing;
  /** Wall time of the plan in the worker, ms. */
  ms: number;
  /** The core's linear memory after planning (its peak so far), bytes. */
  wasmMemoryBytes: number;
}

/** The views' arrays of a plan, for WebGL (built in the worker). */
export interface PlanDrawing {
  /** The scallop heat map, rgb per vertex, scaled to the plan's limit h. */
  heat: Float32Array;
  /** The 3D path at full detail, and decimated within a fraction of a pixel of the part seen whole. */
  path: Polyline;
  pathCoarse: Polyline;
  /** The path in the flattened and in the slit domain, decimated within a fraction of a pixel. */
  flatPath: Polyline;
  slitPath: Polyline;
  /** Hover look-ups of the path points in each domain. */
  flatGrid: PointGrid;
  slitGrid: PointGrid;
  /** w as xyz (z = 0) per vertex. */
  w: Float32Array;
  /** The rings |w| = r as line segments (xyz pairs). */
  rings: Float32Array;
}

/** A flank plan's outputs plus what the 3D view draws of it (computed in the worker). */
export interface FlankResult extends FlankOutput {
  drawing: FlankDrawing;
  /** Wall time of the plan in the worker, ms. */
  ms: number;
  /** The core's linear memory after planning (its peak so far), bytes. */
  wasmMemoryBytes: number;
}

export type WorkerRequest =
  | { type: "load"; id: number; name: string; bytes: ArrayBuffer; meshOptions?: MeshOptions; stepOptions?: StepOptions }
  | { type: "selectFaces"; id: number; faces: number[] }
  | { type: "coons"; id: number; faces: number[]; options: CoonsOptions }
  | { type: "plan"; id: number; options: PlanOptions }
  | { type: "flank"; id: number; options: FlankOptions }
  | { type: "energy"; id: number; x: number; y: number }
  | { type: "flatPoint"; id: number; x: number; y: number };

export type WorkerResponse =
  | { type: "ready"; version: string }
  | { type: "loaded"; id: number; part: LoadedPart }
  | { type: "progress"; id: number; stage: string; done: number; total: number }
  | { type: "planned"; id: number; plan: PlanResult }
  | { type: "flanked"; id: number; plan: FlankResult }
  | { type: "coonsPlanned"; id: number; plan: CoonsResult }
  | { type: "energy"; id: number; value: number }
  | { type: "flatPoint"; id: number; point: [number, number] | null }
  /** `step`: a STEP file was read but its faces could not be made the part (pick others with `selectFaces`). */
  | { type: "error"; id: number | null; message: string; fatal: boolean; step?: StepPart };
