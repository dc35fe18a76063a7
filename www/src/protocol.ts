// Messages between the page (main thread) and the planner worker. Types only.

import type { MeshOptions, MeshReport, SurfaceMesh } from "./core";

export type WorkerRequest = {
  type: "load";
  id: number;
  name: string;
  /** The STL file, transferred (not copied) to the worker. */
  bytes: ArrayBuffer;
  options?: MeshOptions;
};

export type WorkerResponse =
  | { type: "ready"; version: string }
  | ({ type: "loaded"; id: number; name: string; report: MeshReport; ms: number } & SurfaceMesh)
  | { type: "error"; id: number | null; message: string; fatal: boolean };

export type LoadedPart = Extract<WorkerResponse, { type: "loaded" }>;
