// slitpath for web CAM portals: a worker-based planner (load an STL, plan with progress, cancel,
// results as typed arrays). See the README section "Embedding in a web CAM portal".
//
// Two strategies: `plan()` (spiral finishing with a ball-end tool, seeds 000/003) and
// `planFlank()` (5-axis flank milling with a conical tool, seed 002):
//
//   const flank = await planner.planFlank(
//     { tipRadiusMm: 3, topRadiusMm: 10, fluteLengthMm: 23.85, direction: [0, -1, 0], weights: "g1" },
//     { onProgress },
//   );
//   flank.report.verify?.max_gouge_mm; // the verifier's figures (the CLI's `--report`)
//   flank.tips, flank.axes;            // Float64Array, xyz per move
//   flank.stripMoves;                  // Uint32Array, [first, end) per strip
//   flank.vertexDeviation;             // Float64Array per vertex of flank.positions / triangles
//   flank.gcode;                       // A/C G-code (post "ac") or CL data (post "cl")

//
// STEP input (issue 36): `load()` takes STEP bytes too (its faces in `part.step`); `selectFaces()`
// chooses the faces to machine and `planCoons(faces)` plans seed 004's spiral over a closed band
// of four-sided faces.

export { SlitpathPlanner, CancelledError, StepSelectionError } from "./client";
export type { PlannerOptions, LoadOptions, PlanCallbacks } from "./client";
export type { CoonsResult, FlankResult, LoadedPart, PartDrawing, PlanDrawing, PlanResult, StepPart } from "./protocol";
export type { CoonsDrawing } from "./coons-drawing";
export type { StepDrawing } from "./step-drawing";
export type { FlankDrawing } from "./flank-drawing";
export type { Polyline } from "./drawing";
export type { PointGrid } from "./point-grid";
export type { MeshOptions, MeshReport, PlanOptions, PlanReport, PlanOutput, OriginOption, Vec2, Vec3 } from "../core";
export type { FlankOptions, FlankOutput, FlankReport, FlankVerification, FlankSeam, FlankStripDeviation, FlankGridFigures } from "../core";
export type { CoonsOptions, CoonsOutput, CoonsReport, CoonsJumps, StepFace, StepOptions } from "../core";
export { DEFAULT_PLAN_OPTIONS, DEFAULT_FLANK_OPTIONS, flankOptions } from "./defaults";
export type { FlankFormOptions } from "./defaults";
