// What the 3D view draws of a Coons band plan (built in the planner worker): the path at full
// detail and decimated (like the spiral's), the toolpath move of every path point, and the
// scallop heat map on the part's surface when the part is the band's faces.

import type { CoonsOutput } from "../core";
import { extent, heatColours, pathPolyline, type Polyline } from "./drawing";
import { matchMoves } from "./geometry";

export interface CoonsDrawing {
  path: Polyline;
  pathCoarse: Polyline;
  /** For each path point, the index of its toolpath move (tips/axes). */
  moveOfPoint: Uint32Array;
  /** rgb per vertex of the part's surface, scaled to h (the spiral's scale). */
  heat?: Float32Array;
}

/** `coarseTolerance`: the decimation as a fraction of the path's extent; `scallopMm`: h. */
export function coonsDrawing(plan: CoonsOutput, radiusMm: number, coarseTolerance: number, scallopMm: number): CoonsDrawing {
  return {
    path: pathPolyline(plan.pathContacts, 3, 0),
    pathCoarse: pathPolyline(plan.pathContacts, 3, coarseTolerance * extent(plan.pathContacts, 3)),
    moveOfPoint: matchMoves(plan.pathContacts, plan.pathNormals, plan.pathTips, plan.pathAxes, radiusMm),
    ...(plan.vertexScallop ? { heat: heatColours(plan.vertexScallop, scallopMm) } : {}),
  };
}
