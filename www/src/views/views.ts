// The page's side of the render worker (render-worker.ts): hands it the two canvases, forwards
// their sizes and pointer events, sends it what to draw, and reports back hovers, picks, the 2D
// panes' titles and where each frame drew the cursor (data-frame and data-cursor on the canvases,
// which the tests read with the pixels they ask for).

import type { CoonsResult, FlankResult, LoadedPart, PlanResult, StepDrawing, Vec2 } from "../lib/index";
import type { ForwardedEvent } from "./element-proxy";
import type { CoonsView, FaceState, FlankView, Layers, PartView, PlanView, RenderRequest, RenderResponse, ViewName } from "./render-protocol";

const FORWARDED = ["pointerdown", "pointermove", "pointerup", "pointercancel", "wheel", "contextmenu", "click"] as const;

export class Views {
  private readonly worker = new Worker(new URL("./render-worker.ts", import.meta.url), { type: "module", name: "slitpath-views" });
  private readonly titles = new Map<string, HTMLElement>();
  private nextId = 1;
  private readonly pending = new Map<number, (pixels: { width: number; height: number; data: Uint8Array }) => void>();
  private readonly facePoints = new Map<number, (point: Vec2 | null) => void>();
  /** Plans sent and not drawn yet: resolved by the first frame that shows them (or a later plan). */
  private readonly drawing = new Map<number, () => void>();

  /** A hover in either view: the path point under the pointer. */
  onCursor: (index: number) => void = () => {};
  /** A click in a 2D pane: a point of its plane (uv, or w of the slit domain). */
  onPick: (pane: "flat" | "slit", x: number, y: number) => void = () => {};
  /** A click on a STEP face in the 3D view: its index in the face list. */
  onFacePick: (face: number) => void = () => {};

  constructor(private readonly canvases: Record<ViewName, HTMLCanvasElement>) {
    const canvas3d = canvases["3d"].transferControlToOffscreen();
    const canvas2d = canvases["2d"].transferControlToOffscreen();
    this.send({ type: "init", canvas3d, canvas2d, pixelRatio: Math.min(2, window.devicePixelRatio) }, [canvas3d, canvas2d]);
    this.worker.addEventListener("message", (event: MessageEvent<RenderResponse>) => this.receive(event.data));
    this.worker.addEventListener("error", (event) => console.error(`the render worker failed: ${event.message}`));
    for (const view of ["3d", "2d"] as const) {
      const canvas = canvases[view];
      new ResizeObserver(() => this.send({ type: "resize", view, width: canvas.clientWidth, height: canvas.clientHeight })).observe(canvas);
      for (const type of FORWARDED) canvas.addEventListener(type, (event) => this.forward(view, event as PointerEvent & WheelEvent), { passive: false });
    }
  }

  /** Shows a newly loaded part. Its arrays are transferred to the render worker (left empty here). */
  setPart(part: LoadedPart): void {
    const { positions, triangles, normals, drawing, conformalError } = part;
    const view: PartView = { positions, triangles, normals, drawing, conformalError };
    const { uv, previewW, outerEdges, holeEdges } = drawing;
    this.send({ type: "part", part: view }, buffers(positions, triangles, normals, uv, previewW, outerEdges, holeEdges));
  }

  /**
   * Shows a plan; resolves once a frame shows it. The arrays the views draw are transferred to the
   * render worker (left empty here).
   */
  setPlan(plan: PlanResult, radiusMm: number, fiveAxis: boolean): Promise<void> {
    const id = this.nextId++;
    const drawn = new Promise<void>((resolve) => this.drawing.set(id, resolve));
    const { pathContacts, pathTips, pathAxes, moveOfPoint, pathUv, pathW, drawing: d } = plan;
    const { mode, pole_uv } = plan.report.origin;
    const view: PlanView = { pathContacts, pathTips, pathAxes, moveOfPoint, pathUv, pathW, drawing: d, origin: { mode, pole_uv }, radiusMm, fiveAxis };
    const polylines = [d.path, d.pathCoarse, d.flatPath, d.slitPath].flatMap((p) => [p.positions, p.colours, p.segments, p.points]);
    const grids = [d.flatGrid, d.slitGrid].flatMap((g) => [g.starts, g.order]);
    this.send({ type: "plan", id, plan: view }, buffers(pathContacts, pathTips, pathAxes, moveOfPoint, pathUv, pathW, d.heat, d.w, d.rings, ...polylines, ...grids));
    return drawn;
  }

  /**
   * Shows a flank plan (the 3D view only: the slit map has no part in it); resolves once a frame
   * shows it. The arrays drawn are transferred to the render worker (left empty here).
   */
  setFlank(plan: FlankResult): Promise<void> {
    const id = this.nextId++;
    const drawn = new Promise<void>((resolve) => this.drawing.set(id, resolve));
    const { positions, triangles, drawing: d } = plan;
    const flank: FlankView = { positions, triangles, normals: d.normals, heat: d.heat, axisLines: d.axisLines, axisColours: d.axisColours, tipLines: d.tipLines, tipColours: d.tipColours, envelopeLines: d.envelopeLines, envelopeColours: d.envelopeColours };
    this.send({ type: "flank", id, flank }, buffers(positions, triangles, d.normals, d.heat, d.axisLines, d.axisColours, d.tipLines, d.tipColours, d.envelopeLines, d.envelopeColours));
    return drawn;
  }

  /** Shows a STEP file's faces (transferred), or none (null). */
  setFaces(faces: StepDrawing | null): void {
    const transfer = faces ? buffers(faces.positions, faces.normals, faces.triangles, faces.faceOfVertex, faces.faceOfTriangle) : [];
    this.send({ type: "faces", faces }, transfer);
  }

  setFaceState(state: FaceState): void {
    this.send({ type: "faceState", state });
  }

  /** Shows a Coons band plan in the 3D view; resolves once a frame shows it (arrays transferred). */
  setCoons(plan: CoonsResult, radiusMm: number, fiveAxis: boolean): Promise<void> {
    const id = this.nextId++;
    const drawn = new Promise<void>((resolve) => this.drawing.set(id, resolve));
    const { pathContacts, pathTips, pathAxes, drawing: d } = plan;
    const view: CoonsView = { pathContacts, pathTips, pathAxes, moveOfPoint: d.moveOfPoint, drawing: d, radiusMm, fiveAxis };
    const polylines = [d.path, d.pathCoarse].flatMap((p) => [p.positions, p.colours, p.segments, p.points]);
    this.send({ type: "coons", id, plan: view }, buffers(pathContacts, pathTips, pathAxes, d.moveOfPoint, d.heat ?? null, ...polylines));
    return drawn;
  }

  /** Where STEP face `face` (list index) can be clicked in the 3D view, CSS pixels (the tests click there). */
  facePoint(face: number): Promise<Vec2 | null> {
    const id = this.nextId++;
    return new Promise((resolve) => {
      this.facePoints.set(id, resolve);
      this.send({ type: "facePoint", id, face });
    });
  }

  setCursor(index: number): void {
    this.send({ type: "cursor", index });
  }

  /** The pole picked by hand (flattened plane), or null for an automatic origin. */
  setPicked(pole: Vec2 | null): void {
    this.send({ type: "picked", pole });
  }

  setLayers(layers: Layers): void {
    this.send({ type: "layers", layers });
  }

  fit(): void {
    this.send({ type: "fit" });
  }

  /** RGBA of a region of a view's last frame (CSS pixels, rows top first): what the tests read back. */
  pixels(view: ViewName, x: number, y: number, width: number, height: number): Promise<{ width: number; height: number; data: Uint8Array }> {
    const id = this.nextId++;
    return new Promise((resolve) => {
      this.pending.set(id, resolve);
      this.send({ type: "pixels", id, view, x, y, width, height });
    });
  }

  private send(request: RenderRequest, transfer: Transferable[] = []): void {
    this.worker.postMessage(request, transfer);
  }

  private forward(view: ViewName, event: PointerEvent & WheelEvent): void {
    const canvas = this.canvases[view];
    if (event.type === "wheel" || event.type === "contextmenu") event.preventDefault();
    if (event.type === "pointerdown") canvas.setPointerCapture(event.pointerId);
    const rect = canvas.getBoundingClientRect();
    const forwarded: ForwardedEvent = {
      type: event.type,
      pointerId: event.pointerId ?? 0,
      pointerType: event.pointerType ?? "mouse",
      button: event.button,
      buttons: event.buttons,
      clientX: event.clientX - rect.left,
      clientY: event.clientY - rect.top,
      deltaX: event.deltaX ?? 0,
      deltaY: event.deltaY ?? 0,
      deltaMode: event.deltaMode ?? 0,
      ctrlKey: event.ctrlKey,
      metaKey: event.metaKey,
      shiftKey: event.shiftKey,
    };
    this.send({ type: "event", view, event: forwarded });
  }

  private receive(message: RenderResponse): void {
    switch (message.type) {
      case "cursor":
        return this.onCursor(message.index);
      case "pick":
        return this.onPick(message.pane, message.x, message.y);
      case "face":
        return this.onFacePick(message.face);
      case "facePoint":
        this.facePoints.get(message.id)?.(message.point);
        this.facePoints.delete(message.id);
        return;
      case "titles":
        for (const { pane, left, text } of message.titles) {
          const title = this.title(pane);
          title.style.left = `${left}px`;
          title.textContent = text;
        }
        return;
      case "frame": {
        const { frame, cursor, cursorAskedAt, at } = message;
        for (const [id, resolve] of this.drawing) {
          if (id > message.plan) continue;
          resolve();
          this.drawing.delete(id);
        }
        for (const view of ["3d", "2d"] as const) {
          const data = this.canvases[view].dataset;
          Object.assign(data, { frame: String(frame), cursorIndex: String(cursor), cursorAskedAt: String(cursorAskedAt) });
        }
        const xy = (key: keyof typeof at) => (at[key] ? `${key}:${at[key][0].toFixed(1)},${at[key][1].toFixed(1)}` : "");
        this.canvases["3d"].dataset["cursor"] = xy("3d");
        this.canvases["2d"].dataset["cursor"] = [xy("flat"), xy("slit")].filter((s) => s !== "").join(" ");
        return;
      }
      case "pixels":
        this.pending.get(message.id)?.(message);
        this.pending.delete(message.id);
        return;
      case "error":
        console.error(`the render worker: ${message.message}`);
        // Whatever failed, the page goes on (a plan that could not be drawn still planned).
        for (const resolve of this.drawing.values()) resolve();
        this.drawing.clear();
        return;
    }
  }

  private title(pane: string): HTMLElement {
    let title = this.titles.get(pane);
    if (title === undefined) {
      title = document.createElement("p");
      title.className = "pane-title";
      title.dataset["pane"] = pane;
      this.canvases["2d"].parentElement?.append(title);
      this.titles.set(pane, title);
    }
    return title;
  }
}

const buffers = (...arrays: (ArrayBufferView | null)[]): ArrayBuffer[] =>
  arrays.filter((a): a is ArrayBufferView => a !== null).map((a) => a.buffer as ArrayBuffer);
