// The 2D view (three.js, WebGL, in the render worker): left the flattened domain S^F, right the
// slit domain (unit disk or annulus with arc slits), each with the spiral; the slit domain also
// shows the rings. Hovering
// either pane highlights the nearest path point in both (and reports it, for the 3D tool);
// clicking sets the pole by hand.
//
// The panes change only with the part, the plan or the size: they are rendered once into a
// texture, and every frame after that (hover, scrub) draws that texture and the markers only.
// Everything big arrives from the worker as typed arrays (decimated paths, hover grids), so
// nothing here walks the mesh or the whole path.

import * as THREE from "three";
import { nearestPoint } from "../lib/point-grid";
import { around, drawIn, type Rect } from "./dirty-rects";
import type { ElementProxy } from "./element-proxy";
import { dot, ring, star } from "./markers";
import { Pane2d } from "./pane2d";
import { rawColour } from "./raw-colour";
import type { PartView, PlanView } from "./render-protocol";
import { readPixels } from "./read-pixels";

export type Pane = "flat" | "slit";
const PANES: Pane[] = ["flat", "slit"];

/** A pane's square on screen (CSS pixels, y down) and its domain → pixel scale and centre. */
interface Frame {
  x: number;
  y: number;
  size: number;
  scale: number;
  cx: number;
  cy: number;
}

const MARGIN = 14;
const TITLE = 22;
/** Hover reach, CSS pixels. */
const REACH = 24;
/** Half the side of the square a cursor dot is drawn in (its radius is 6.25 px), CSS pixels. */
const DOT_REACH = 10;
const BACKGROUND = 0xf7f8fa;

export class View2d {
  private readonly renderer: THREE.WebGLRenderer;
  /** Pixel space (CSS pixels, y up), shared by the panes' scene and the overlay. */
  private readonly camera = new THREE.OrthographicCamera(0, 1, 1, 0, -100, 100);
  private readonly panesScene = new THREE.Scene();
  private readonly overlay = new THREE.Scene();
  private readonly panes: Record<Pane, Pane2d> = { flat: new Pane2d(), slit: new Pane2d() };
  private target: THREE.WebGLRenderTarget | null = null;
  private readonly layer = new THREE.Mesh(new THREE.PlaneGeometry(1, 1), new THREE.MeshBasicMaterial({ depthTest: false, depthWrite: false }));
  private readonly markers = {
    pole: [star(0xb42318), star(0xb42318)],
    picked: ring(0xe8590c),
    cursor: [dot(0x1d2330), dot(0x1d2330)],
  };
  private part: PartView | null = null;
  /** The flattened domain's bounding box (computed once per part). */
  private flatBox: [number, number, number, number] = [-1, -1, 1, 1];
  private plan: PlanView | null = null;
  private picked: [number, number] | null = null;
  private cursor = -1;
  private frames: Record<Pane, Frame> = { flat: emptyFrame(), slit: emptyFrame() };
  private size = { w: 1, h: 1 };
  private layerStale = true;
  private stale = true;
  /** Where the last frame drew the cursor dots; undefined: the next frame draws everything. */
  private cursorRects: Rect[] | undefined = undefined;

  /** Hover: the path point nearest the pointer. */
  onCursor: (index: number) => void = () => {};
  /** Click: a point of a pane's plane (the page maps a slit-domain point to the flattened plane). */
  onPick: (pane: Pane, x: number, y: number) => void = () => {};
  /** The panes' titles and where they start (CSS pixels from the left): the page shows them. */
  onTitles: (titles: { pane: Pane; left: number; text: string }[]) => void = () => {};

  constructor(
    canvas: OffscreenCanvas,
    private readonly element: ElementProxy,
    pixelRatio: number,
    private readonly requestRender: () => void,
  ) {
    // preserveDrawingBuffer: the tests read the pixels back.
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(pixelRatio);
    this.renderer.outputColorSpace = THREE.LinearSRGBColorSpace; // colours as given (raw-colour.ts)
    this.renderer.setClearColor(rawColour(BACKGROUND));
    this.camera.position.z = 50;
    for (const pane of PANES) this.panesScene.add(this.panes[pane].group);
    this.layer.renderOrder = -1;
    this.overlay.add(this.layer, ...this.markers.pole, this.markers.picked, ...this.markers.cursor);
    element.addEventListener("pointermove", (event) => this.hover(event as PointerEvent));
    element.addEventListener("click", (event) => this.click(event as PointerEvent));
  }

  setPart(part: PartView): void {
    this.part = part;
    this.flatBox = bounds(part.drawing.uv);
    this.plan = null;
    this.cursor = -1;
    const { drawing: d } = part;
    this.panes.flat.setDomain(d.uv, d.outerEdges, d.holeEdges);
    this.panes.slit.setDomain(d.previewW, d.outerEdges, d.holeEdges);
    for (const pane of PANES) {
      this.panes[pane].setRings(null);
      this.panes[pane].setPath(null);
    }
    this.restale();
  }

  setPlan(plan: PlanView): void {
    const part = this.part;
    if (part === null) return;
    this.plan = plan;
    const { drawing: d } = plan;
    this.panes.slit.setDomain(d.w, part.drawing.outerEdges, part.drawing.holeEdges);
    this.panes.slit.setRings(d.rings);
    this.panes.flat.setPath(d.flatPath);
    this.panes.slit.setPath(d.slitPath);
    this.restale();
  }

  /** Forgets the plan (a flank plan has no slit map): the part's domains and preview again. */
  clearPlan(): void {
    if (this.part === null) return;
    this.plan = null;
    this.cursor = -1;
    const { drawing: d } = this.part;
    this.panes.slit.setDomain(d.previewW, d.outerEdges, d.holeEdges);
    for (const pane of PANES) {
      this.panes[pane].setRings(null);
      this.panes[pane].setPath(null);
    }
    this.restale();
  }

  /** The pole picked by hand (flattened plane), or null for an automatic origin. */
  setPicked(pole: [number, number] | null): void {
    this.picked = pole;
    this.cursorRects = undefined;
    this.invalidate();
  }

  setCursor(index: number): void {
    this.cursor = index;
    this.invalidate();
  }

  private invalidate(): void {
    this.stale = true;
    this.requestRender();
  }

  /** The layout, the titles and the panes' placement changed: render the panes again. */
  private restale(): void {
    this.layout();
    this.layerStale = true;
    this.cursorRects = undefined;
    this.invalidate();
  }

  resize(w: number, h: number): void {
    this.element.clientWidth = w;
    this.element.clientHeight = h;
    this.size = { w, h };
    this.renderer.setSize(w, h, false);
    Object.assign(this.camera, { left: 0, right: w, top: h, bottom: 0 });
    this.camera.updateProjectionMatrix();
    this.layer.scale.set(w, h, 1);
    this.layer.position.set(w / 2, h / 2, 0);
    const buffer = this.renderer.getDrawingBufferSize(new THREE.Vector2());
    this.target?.dispose();
    this.target = new THREE.WebGLRenderTarget(buffer.x, buffer.y, { samples: 4, stencilBuffer: true });
    this.layer.material.map = this.target.texture;
    this.layer.material.needsUpdate = true;
    this.restale();
  }

  /** Pane squares side by side, their titles, and each pane's group placed on them. */
  private layout(): void {
    const { w, h } = this.size;
    const size = Math.max(10, Math.min(w / 2 - 1.5 * MARGIN, h - TITLE - 2 * MARGIN));
    const top = TITLE + MARGIN;
    const gap = (w - 2 * size) / 3;
    this.frames.flat = fitFrame(gap, top, size, this.flatBox);
    this.frames.slit = fitFrame(2 * gap + size, top, size, [-1.04, -1.04, 1.04, 1.04]);
    for (const pane of PANES) {
      const f = this.frames[pane];
      // Domain (u, v) → pixel (x, y up): the group's scale and offset.
      this.panes[pane].group.scale.set(f.scale, f.scale, 1);
      this.panes[pane].group.position.set(f.x + f.size / 2 - f.cx * f.scale, h - (f.y + f.size / 2) - f.cy * f.scale, 0);
    }
    const mode = this.plan?.origin.mode ?? (this.part?.drawing.previewW ? "preview" : "");
    const flat =
      this.part !== null && this.part.drawing.uv === null ? `Flattened domain: ${this.part.conformalError ?? "no flattening"}` : "Flattened domain";
    this.onTitles([
      { pane: "flat", left: this.frames.flat.x, text: flat },
      { pane: "slit", left: this.frames.slit.x, text: mode === "preview" ? "Slit domain (centroid pole, preview)" : `Slit domain (${mode || "—"})` },
    ]);
  }

  private toPixel(pane: Pane, u: number, v: number): [number, number] {
    const f = this.frames[pane];
    return [f.x + f.size / 2 + (u - f.cx) * f.scale, f.y + f.size / 2 - (v - f.cy) * f.scale];
  }

  private fromPixel(pane: Pane, px: number, py: number): [number, number] {
    const f = this.frames[pane];
    return [f.cx + (px - f.x - f.size / 2) / f.scale, f.cy - (py - f.y - f.size / 2) / f.scale];
  }

  private paneAt(px: number, py: number): Pane | null {
    for (const pane of PANES) {
      const f = this.frames[pane];
      if (px >= f.x - MARGIN && px <= f.x + f.size + MARGIN && py >= f.y - MARGIN && py <= f.y + f.size + MARGIN) return pane;
    }
    return null;
  }

  private pathIn(pane: Pane): Float64Array | null {
    if (this.plan === null) return null;
    return pane === "flat" ? this.plan.pathUv : this.plan.pathW;
  }

  /** Puts a marker at a pane point (CSS pixels, y down), or hides it. */
  private place(marker: THREE.Object3D, at: [number, number] | null): void {
    marker.visible = at !== null;
    if (at !== null) marker.position.set(at[0], this.size.h - at[1], marker.position.z);
  }

  /** Places the markers; where the cursor is in each pane. */
  private placeMarkers(): Partial<Record<Pane, [number, number]>> {
    const origin = this.plan?.origin ?? null;
    this.place(this.markers.pole[0]!, origin && this.toPixel("flat", origin.pole_uv[0], origin.pole_uv[1]));
    this.place(this.markers.pole[1]!, origin?.mode === "disk" ? this.toPixel("slit", 0, 0) : null);
    this.place(this.markers.picked, this.picked && this.toPixel("flat", ...this.picked));
    const cursors: Partial<Record<Pane, [number, number]>> = {};
    PANES.forEach((pane, k) => {
      const path = this.pathIn(pane);
      const [u, v] = [path?.[2 * this.cursor], path?.[2 * this.cursor + 1]];
      const at = this.cursor >= 0 && u !== undefined && v !== undefined && !Number.isNaN(u) ? this.toPixel(pane, u, v) : null;
      this.place(this.markers.cursor[k]!, at);
      if (at) cursors[pane] = at;
    });
    return cursors;
  }

  /** Renders when something changed (the panes only when they did); where the cursor was drawn. */
  render(): Partial<Record<Pane, [number, number]>> | undefined {
    if (this.target === null || !this.stale) return undefined;
    this.stale = false;
    if (this.layerStale) {
      this.renderer.setRenderTarget(this.target);
      this.renderer.render(this.panesScene, this.camera);
      this.renderer.setRenderTarget(null);
      this.layerStale = false;
    }
    const cursors = this.placeMarkers();
    const rects = Object.values(cursors).map((at) => around(at, DOT_REACH));
    const draw = () => this.renderer.render(this.overlay, this.camera);
    if (this.cursorRects === undefined) draw();
    else drawIn(this.renderer, [...this.cursorRects, ...rects], this.size.w, this.size.h, draw);
    this.cursorRects = rects;
    return cursors;
  }

  /** RGBA of a region of the last frame (CSS pixels, rows top first). */
  pixels(x: number, y: number, width: number, height: number): { width: number; height: number; data: Uint8Array } {
    return readPixels(this.renderer, x, y, width, height);
  }

  private hover(event: PointerEvent): void {
    const [px, py] = [event.clientX, event.clientY];
    const pane = this.paneAt(px, py);
    const path = pane && this.pathIn(pane);
    if (!pane || !path || !this.plan) return;
    const [x, y] = this.fromPixel(pane, px, py);
    const grid = pane === "flat" ? this.plan.drawing.flatGrid : this.plan.drawing.slitGrid;
    const best = nearestPoint(grid, path, x, y, REACH / this.frames[pane].scale);
    if (best >= 0 && best !== this.cursor) {
      this.setCursor(best);
      this.onCursor(best);
    }
  }

  private click(event: PointerEvent): void {
    const [px, py] = [event.clientX, event.clientY];
    const pane = this.paneAt(px, py);
    if (pane === null || this.part?.drawing.uv == null) return;
    this.onPick(pane, ...this.fromPixel(pane, px, py));
  }

}

function emptyFrame(): Frame {
  return { x: 0, y: 0, size: 1, scale: 1, cx: 0, cy: 0 };
}

function fitFrame(x: number, y: number, size: number, [x0, y0, x1, y1]: [number, number, number, number]): Frame {
  const scale = size / Math.max(x1 - x0, y1 - y0, 1e-12);
  return { x, y, size, scale, cx: (x0 + x1) / 2, cy: (y0 + y1) / 2 };
}

/** Bounding box of plane points (xyz, z = 0); the unit square for none. */
function bounds(xyz: Float32Array | null): [number, number, number, number] {
  if (!xyz || xyz.length === 0) return [-1, -1, 1, 1];
  let [x0, y0, x1, y1] = [Infinity, Infinity, -Infinity, -Infinity];
  for (let i = 0; i < xyz.length; i += 3) {
    [x0, x1] = [Math.min(x0, xyz[i]!), Math.max(x1, xyz[i]!)];
    [y0, y1] = [Math.min(y0, xyz[i + 1]!), Math.max(y1, xyz[i + 1]!)];
  }
  return [x0, y0, x1, y1];
}
