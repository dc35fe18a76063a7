// The render worker: owns the 3D and the 2D view's WebGL canvases (OffscreenCanvas), so drawing
// never blocks the page's main thread, however big the part (measured: a 300k-triangle frame
// held the main thread 0.5–0.8 s in software WebGL, the worker none). The page forwards events,
// sizes and data; both views render together, once per animation frame, when one changed.

import { ElementProxy } from "./element-proxy";
import type { CursorAt, RenderRequest, RenderResponse, ViewName } from "./render-protocol";
import { View2d } from "./view2d";
import { View3d } from "./view3d";

let views: { "3d": View3d; "2d": View2d } | null = null;
const elements = { "3d": new ElementProxy(), "2d": new ElementProxy() };
let frame = 0;
let scheduled = 0;
/** The cursor the page (or a hover) asked for last, and the frame count when it did. */
let cursor = { index: -1, askedAt: 0 };
let at: CursorAt = {};
/** The plan the views show (its request id). */
let planId = 0;
/** The plan of the last frame reported. */
let reportedPlan = 0;

function post(message: RenderResponse, transfer: Transferable[] = []): void {
  self.postMessage(message, { transfer });
}

function requestRender(): void {
  if (scheduled !== 0) return;
  scheduled = self.requestAnimationFrame(render);
}

function render(): void {
  scheduled = 0;
  if (views === null) return;
  const at3d = views["3d"].render();
  const at2d = views["2d"].render();
  if (at3d === undefined && at2d === undefined) return;
  frame++;
  // Where the cursor is now drawn in each view (a view not drawn in this frame keeps its place).
  if (at2d !== undefined) at = { ...(at["3d"] ? { "3d": at["3d"] } : {}), ...at2d };
  if (at3d !== undefined) {
    const { "3d": _, ...rest } = at;
    at = at3d ? { ...rest, "3d": at3d } : rest;
  }
  // A frame with a new plan is reported once the GPU has drawn it (the page then says "planned"):
  // reading a pixel back waits for it. Other frames are not waited for.
  if (planId !== reportedPlan) {
    views["3d"].pixels(0, 0, 1, 1);
    views["2d"].pixels(0, 0, 1, 1);
    reportedPlan = planId;
  }
  post({ type: "frame", frame, plan: planId, cursor: cursor.index, cursorAskedAt: cursor.askedAt, at });
}

function setCursor(index: number): void {
  cursor = { index, askedAt: frame };
  views?.["3d"].setCursor(index);
  views?.["2d"].setCursor(index);
}

function init(request: Extract<RenderRequest, { type: "init" }>): void {
  const view3d = new View3d(request.canvas3d, elements["3d"], request.pixelRatio, requestRender);
  const view2d = new View2d(request.canvas2d, elements["2d"], request.pixelRatio, requestRender);
  // A hover in either view moves the cursor in both, and the page's scrub bar.
  view3d.onCursor = view2d.onCursor = (index) => {
    setCursor(index);
    post({ type: "cursor", index });
  };
  view2d.onPick = (pane, x, y) => post({ type: "pick", pane, x, y });
  view3d.onFacePick = (face) => post({ type: "face", face });
  view2d.onTitles = (titles) => post({ type: "titles", titles });
  views = { "3d": view3d, "2d": view2d };
}

function handle(request: RenderRequest): void {
  if (request.type === "init") return init(request);
  if (views === null) return;
  switch (request.type) {
    case "resize":
      if (request.width > 0 && request.height > 0) views[request.view].resize(request.width, request.height);
      return;
    case "part":
      cursor = { index: -1, askedAt: frame };
      planId = 0;
      views["3d"].setPart(request.part);
      views["2d"].setPart(request.part);
      return;
    case "plan":
      planId = request.id;
      views["3d"].setPlan(request.plan);
      views["2d"].setPlan(request.plan);
      return setCursor(0);
    case "coons":
      planId = request.id;
      views["3d"].setPlan(request.plan);
      views["2d"].clearPlan();
      return setCursor(0);
    case "faces":
      return views["3d"].setFaces(request.faces);
    case "faceState":
      return views["3d"].setFaceState(request.state);
    case "facePoint":
      return post({ type: "facePoint", id: request.id, point: views["3d"].facePoint(request.face) });
    case "flank":
      planId = request.id;
      cursor = { index: -1, askedAt: frame };
      views["3d"].setFlank(request.flank);
      return views["2d"].clearPlan();
    case "cursor":
      return setCursor(request.index);
    case "picked":
      return views["2d"].setPicked(request.pole);
    case "layers":
      return views["3d"].setLayers(request.layers);
    case "fit":
      return views["3d"].fit();
    case "event":
      return elements[request.view].replay(request.event);
    case "pixels": {
      const view: ViewName = request.view;
      const { width, height, data } = views[view].pixels(request.x, request.y, request.width, request.height);
      return post({ type: "pixels", id: request.id, width, height, data }, [data.buffer]);
    }
  }
}

self.addEventListener("message", (event: MessageEvent<RenderRequest>) => {
  try {
    handle(event.data);
  } catch (error) {
    post({ type: "error", message: error instanceof Error ? error.message : String(error) });
  }
});
