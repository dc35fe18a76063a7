// What the 3D view draws of a Coons band plan (built in the planner worker): the path at full
// detail and decimated (like the spiral's), and the toolpath move of every path point.

import type { CoonsOutput } from "../core";
import { extent, pathPolyline, type Polyline } from "./drawing";
import { matchMoves } from "./geometry";

export interface CoonsDrawing {
  path: Polyline;
  pathCoarse: Polyline;
  /** For each path point, the index of its toolpath move (tips/axes). */
  moveOfPoint: Uint32Array;
}

/** `coarseTolerance`: the decimation as a fraction of the path's extent. */
export function coonsDrawing(plan: CoonsOutput, radiusMm: number, coarseTolerance: number): CoonsDrawing {
  return {
    path: pathPolyline(plan.pathContacts, 3, 0),
    pathCoarse: pathPolyline(plan.pathContacts, 3, coarseTolerance * extent(plan.pathContacts, 3)),
    moveOfPoint: matchMoves(plan.pathContacts, plan.pathNormals, plan.pathTips, plan.pathAxes, radiusMm),
  };
}
