// The ONE module that loads the WebAssembly planner core (wasm-pack output in ../pkg).
// Everything else imports the types and helpers it needs from here, never from ../pkg, so the
// rest of the page does not depend on how the core is built. It runs inside the worker.

import init, { Planner, version } from "../pkg/slitpath.js";

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
}

let ready: Promise<void> | undefined;

/** Instantiates the wasm module once; later calls share the same promise. */
export function initCore(): Promise<void> {
  ready ??= init().then(() => undefined);
  return ready;
}

/** The core's version, e.g. "0.1.0" (after initCore()). */
export function coreVersion(): string {
  return version();
}

/** One loaded part: owns the wasm-side Planner (free() it when replaced). */
export class Part {
  private constructor(private readonly planner: Planner) {}

  /** Reads and validates an STL; throws an Error whose message names the fault. */
  static async open(stl: Uint8Array, options?: MeshOptions): Promise<Part> {
    await initCore();
    return new Part(new Planner(stl, options));
  }

  report(): MeshReport {
    return this.planner.report() as MeshReport;
  }

  surface(): SurfaceMesh {
    return { positions: this.planner.positions(), triangles: this.planner.triangles() };
  }

  free(): void {
    this.planner.free();
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
