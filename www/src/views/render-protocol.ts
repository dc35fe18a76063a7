// Messages between the page (Views) and the render worker that owns the two WebGL canvases.
// Types only. Big arrays cross by transfer.

import type { CoonsDrawing, PartDrawing, PlanDrawing, Polyline, StepDrawing, Vec2 } from "../lib/index";
import type { ForwardedEvent } from "./element-proxy";

export type ViewName = "3d" | "2d";

/** What the views draw of a part (arrays transferred from the page). */
export interface PartView {
  positions: Float32Array;
  triangles: Uint32Array;
  normals: Float32Array;
  drawing: PartDrawing;
  /** Why there is no flattening, or null. */
  conformalError: string | null;
}

/** What the 3D view needs of any path plan (the spiral's or the Coons band's): path, tool, needles. */
export interface PathView {
  pathContacts: Float64Array;
  pathTips: Float64Array;
  pathAxes: Float64Array;
  moveOfPoint: Uint32Array;
  drawing: { path: Polyline; pathCoarse: Polyline; heat?: Float32Array };
  radiusMm: number;
  fiveAxis: boolean;
}

/** What the 3D view draws of a Coons band plan (arrays transferred from the page). */
export interface CoonsView extends PathView {
  drawing: CoonsDrawing;
}

/** Which STEP faces are selected and which the part's surface covers: 1 or 0 per face (list order). */
export interface FaceState {
  selected: Uint8Array;
  covered: Uint8Array;
  /** Hide the part's surface (a Coons plan is drawn on the faces). */
  hideSurface: boolean;
}

/** What the views draw of a plan (arrays transferred from the page). */
export interface PlanView {
  pathContacts: Float64Array;
  pathTips: Float64Array;
  pathAxes: Float64Array;
  moveOfPoint: Uint32Array;
  pathUv: Float64Array;
  pathW: Float64Array;
  drawing: PlanDrawing;
  origin: { mode: string; pole_uv: Vec2 };
  radiusMm: number;
  fiveAxis: boolean;
}

/** What the 3D view draws of a flank plan (arrays transferred from the page): the planned surface coloured by deviation, tips, axes and contact curves per strip. */
export interface FlankView {
  positions: Float32Array;
  triangles: Uint32Array;
  normals: Float32Array;
  heat: Float32Array;
  axisLines: Float32Array;
  axisColours: Float32Array;
  tipLines: Float32Array;
  tipColours: Float32Array;
  envelopeLines: Float32Array;
  envelopeColours: Float32Array;
}

export interface Layers {
  heatMap: boolean;
  path: boolean;
  needles: boolean;
}

export type RenderRequest =
  | { type: "init"; canvas3d: OffscreenCanvas; canvas2d: OffscreenCanvas; pixelRatio: number }
  | { type: "resize"; view: ViewName; width: number; height: number }
  | { type: "part"; part: PartView }
  | { type: "plan"; id: number; plan: PlanView }
  | { type: "flank"; id: number; flank: FlankView }
  | { type: "coons"; id: number; plan: CoonsView }
  | { type: "faces"; faces: StepDrawing | null }
  | { type: "faceState"; state: FaceState }
  | { type: "facePoint"; id: number; face: number }
  | { type: "cursor"; index: number }
  | { type: "picked"; pole: Vec2 | null }
  | { type: "layers"; layers: Layers }
  | { type: "fit" }
  | { type: "event"; view: ViewName; event: ForwardedEvent }
  | { type: "pixels"; id: number; view: ViewName; x: number; y: number; width: number; height: number };

/** Where the cursor was drawn in a frame (CSS pixels from the canvas's top left), per view and pane. */
export type CursorAt = Partial<Record<"3d" | "flat" | "slit", Vec2>>;

export type RenderResponse =
  | { type: "cursor"; index: number }
  | { type: "pick"; pane: "flat" | "slit"; x: number; y: number }
  /** A click on a STEP face in the 3D view (its index in the face list). */
  | { type: "face"; face: number }
  /** Where face `face` can be clicked (CSS pixels), or null when hidden from this view. */
  | { type: "facePoint"; id: number; point: Vec2 | null }
  | { type: "titles"; titles: { pane: "flat" | "slit"; left: number; text: string }[] }
  /**
   * A frame was drawn: its number, the plan in it (the id of its "plan" request, 0 for none), the
   * cursor in it and the frame count when that cursor was asked for.
   */
  | { type: "frame"; frame: number; plan: number; cursor: number; cursorAskedAt: number; at: CursorAt }
  /** RGBA, rows top first. */
  | { type: "pixels"; id: number; width: number; height: number; data: Uint8Array }
  | { type: "error"; message: string };
