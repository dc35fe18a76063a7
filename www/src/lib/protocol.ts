// Messages between the main thread (SlitpathPlanner) and the planner worker. Types only.

import type { MeshOptions, MeshReport, PlanOptions, PlanOutput } from "../core";

/** A part as loaded by the worker: its report, the surface to draw, and its conformal preview. */
export interface LoadedPart {
  name: string;
  report: MeshReport;
  /** xyz per vertex of the surface to machine. */
  positions: Float32Array;
  /** Three vertex indices per triangle. */
  triangles: Uint32Array;
  /** Boundary loops (vertex indices), the outer (longest) first. */
  loops: Uint32Array[];
  /** Flattened uv per vertex; null when the surface cannot be flattened (see conformalError). */
  uv: Float64Array | null;
  /** Slit-map image w per vertex for the centroid of the flattened vertices (a preview before planning). */
  previewW: Float64Array | null;
  /** Why there is no flattening (closed solid, genus > 0, …); null when there is one. */
  conformalError: string | null;
  /** Time to read, check and flatten, ms. */
  ms: number;
  /** The core's linear memory after loading (its peak so far), bytes. */
  wasmMemoryBytes: number;
}

/** A plan's outputs plus what the views derive from them (computed in the worker). */
export interface PlanResult extends PlanOutput {
  /** uv (flattened plane) per path point, NaN where a point could not be located. */
  pathUv: Float64Array;
  /** For each path point, the index of its toolpath move (tips/axes). */
  moveOfPoint: Uint32Array;
  /** Wall time of the plan in the worker, ms. */
  ms: number;
  /** The core's linear memory after planning (its peak so far), bytes. */
  wasmMemoryBytes: number;
}

export type WorkerRequest =
  | { type: "load"; id: number; name: string; bytes: ArrayBuffer; meshOptions?: MeshOptions }
  | { type: "plan"; id: number; options: PlanOptions }
  | { type: "energy"; id: number; x: number; y: number };

export type WorkerResponse =
  | { type: "ready"; version: string }
  | { type: "loaded"; id: number; part: LoadedPart }
  | { type: "progress"; id: number; stage: string; done: number; total: number }
  | { type: "planned"; id: number; plan: PlanResult }
  | { type: "energy"; id: number; value: number }
  | { type: "error"; id: number | null; message: string; fatal: boolean };
