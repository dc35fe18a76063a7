// slitpath for web CAM portals: a worker-based planner (load an STL, plan with progress, cancel,
// results as typed arrays). See the README section "Embedding in a web CAM portal".

export { SlitpathPlanner, CancelledError } from "./client";
export type { PlannerOptions, LoadOptions, PlanCallbacks } from "./client";
export type { LoadedPart, PartDrawing, PlanDrawing, PlanResult } from "./protocol";
export type { Polyline } from "./drawing";
export type { PointGrid } from "./point-grid";
export type { MeshOptions, MeshReport, PlanOptions, PlanReport, PlanOutput, OriginOption, Vec2, Vec3 } from "../core";
export { DEFAULT_PLAN_OPTIONS } from "./defaults";
