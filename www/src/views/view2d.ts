// The 2D view (canvas): left the flattened domain S^F, right the slit domain (unit disk or
// annulus with arc slits), each with the spiral; the slit domain also shows the rings. Hovering
// either pane highlights the nearest path point in both (and reports it, for the 3D tool);
// clicking sets the pole by hand. The mesh and the path are drawn once into an offscreen layer;
// hovering only redraws the markers.

import type { LoadedPart, PlanResult } from "../lib/index";
import { PlanarLocator } from "../lib/geometry";
import { css, pathColour } from "./colors";

type Pane = "flat" | "slit";

interface Frame {
  x: number;
  y: number;
  size: number;
  /** Domain → pixel: scale and centre. */
  scale: number;
  cx: number;
  cy: number;
}

const MARGIN = 14;
const TITLE = 22;

export class View2d {
  private readonly ctx: CanvasRenderingContext2D;
  private readonly layer = document.createElement("canvas");
  private part: LoadedPart | null = null;
  private plan: PlanResult | null = null;
  private picked: [number, number] | null = null;
  private cursor = -1;
  private frames: Record<Pane, Frame> = { flat: emptyFrame(), slit: emptyFrame() };
  private slitLocator: PlanarLocator | null = null;

  /** Hover or scrub: the path point nearest the pointer. */
  onCursor: (index: number) => void = () => {};
  /** Click: a pole (x, y) of the flattened plane. */
  onPick: (x: number, y: number) => void = () => {};

  constructor(private readonly canvas: HTMLCanvasElement) {
    const ctx = canvas.getContext("2d");
    if (ctx === null) throw new Error("this browser has no 2D canvas");
    this.ctx = ctx;
    canvas.addEventListener("pointermove", (event) => this.hover(event));
    canvas.addEventListener("click", (event) => this.click(event));
    new ResizeObserver(() => this.resize()).observe(canvas);
  }

  setPart(part: LoadedPart): void {
    this.part = part;
    this.plan = null;
    this.cursor = -1;
    this.slitLocator = null;
    this.redrawLayer();
  }

  setPlan(plan: PlanResult): void {
    this.plan = plan;
    this.slitLocator = null;
    this.redrawLayer();
  }

  /** The pole picked by hand (flattened plane), or null for an automatic origin. */
  setPicked(pole: [number, number] | null): void {
    this.picked = pole;
    this.draw();
  }

  setCursor(index: number): void {
    this.cursor = index;
    this.draw();
  }

  private resize(): void {
    const ratio = Math.min(2, window.devicePixelRatio);
    const { clientWidth: w, clientHeight: h } = this.canvas;
    if (w === 0 || h === 0) return;
    this.canvas.width = this.layer.width = Math.round(w * ratio);
    this.canvas.height = this.layer.height = Math.round(h * ratio);
    this.redrawLayer();
  }

  /** Pane squares side by side (CSS pixels). */
  private layout(): void {
    const ratio = this.canvas.width / Math.max(1, this.canvas.clientWidth);
    const w = this.canvas.width / ratio;
    const h = this.canvas.height / ratio;
    const size = Math.max(10, Math.min(w / 2 - 1.5 * MARGIN, h - TITLE - 2 * MARGIN));
    const top = TITLE + MARGIN;
    const gap = (w - 2 * size) / 3;
    this.frames.flat = this.fitFrame(gap, top, size, this.flatBounds());
    this.frames.slit = this.fitFrame(2 * gap + size, top, size, [-1.04, -1.04, 1.04, 1.04]);
  }

  private flatBounds(): [number, number, number, number] {
    const uv = this.part?.uv;
    if (!uv) return [-1, -1, 1, 1];
    let [x0, y0, x1, y1] = [Infinity, Infinity, -Infinity, -Infinity];
    for (let i = 0; i < uv.length; i += 2) {
      [x0, x1] = [Math.min(x0, uv[i]!), Math.max(x1, uv[i]!)];
      [y0, y1] = [Math.min(y0, uv[i + 1]!), Math.max(y1, uv[i + 1]!)];
    }
    return [x0, y0, x1, y1];
  }

  private fitFrame(x: number, y: number, size: number, [x0, y0, x1, y1]: [number, number, number, number]): Frame {
    const scale = size / Math.max(x1 - x0, y1 - y0, 1e-12);
    return { x, y, size, scale, cx: (x0 + x1) / 2, cy: (y0 + y1) / 2 };
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
    for (const pane of ["flat", "slit"] as const) {
      const f = this.frames[pane];
      if (px >= f.x - MARGIN && px <= f.x + f.size + MARGIN && py >= f.y - MARGIN && py <= f.y + f.size + MARGIN) return pane;
    }
    return null;
  }

  /** The image per vertex drawn in a pane: uv, or w (planned, else the preview map). */
  private field(pane: Pane): Float64Array | null {
    if (pane === "flat") return this.part?.uv ?? null;
    return this.plan?.w ?? this.part?.previewW ?? null;
  }

  private pathIn(pane: Pane): Float64Array | null {
    if (this.plan === null) return null;
    return pane === "flat" ? this.plan.pathUv : this.plan.pathW;
  }

  private redrawLayer(): void {
    this.layout();
    const ratio = this.canvas.width / Math.max(1, this.canvas.clientWidth);
    const g = this.layer.getContext("2d");
    if (g === null) return;
    g.setTransform(ratio, 0, 0, ratio, 0, 0);
    g.fillStyle = "#f7f8fa";
    g.fillRect(0, 0, this.layer.width, this.layer.height);
    const mode = this.plan?.report.origin.mode ?? (this.part?.previewW ? "preview" : "");
    this.title(g, "flat", "Flattened domain");
    this.title(g, "slit", mode === "preview" ? "Slit domain (centroid pole, preview)" : `Slit domain (${mode || "—"})`);
    if (this.part === null) return;
    if (this.part.uv === null) {
      g.fillStyle = "#5d6677";
      g.font = "13px system-ui, sans-serif";
      g.fillText(this.part.conformalError ?? "no flattening", this.frames.flat.x, this.frames.flat.y + 20);
      return;
    }
    for (const pane of ["flat", "slit"] as const) {
      const field = this.field(pane);
      if (field === null) continue;
      this.mesh(g, pane, field);
      if (pane === "slit") this.rings(g);
      this.spiral(g, pane);
    }
    this.draw();
  }

  private title(g: CanvasRenderingContext2D, pane: Pane, text: string): void {
    const f = this.frames[pane];
    g.fillStyle = "#1d2330";
    g.font = "600 13px system-ui, sans-serif";
    g.fillText(text, f.x, TITLE - 4);
  }

  /** The triangles filled in one path, the boundary loops (outer circle, hole slits) stroked. */
  private mesh(g: CanvasRenderingContext2D, pane: Pane, field: Float64Array): void {
    const part = this.part!;
    const t = part.triangles;
    g.beginPath();
    for (let f = 0; f < t.length; f += 3) {
      const [a, b, c] = [t[f]!, t[f + 1]!, t[f + 2]!];
      g.moveTo(...this.toPixel(pane, field[2 * a]!, field[2 * a + 1]!));
      g.lineTo(...this.toPixel(pane, field[2 * b]!, field[2 * b + 1]!));
      g.lineTo(...this.toPixel(pane, field[2 * c]!, field[2 * c + 1]!));
      g.closePath();
    }
    g.fillStyle = "#dde3ec";
    g.fill();
    part.loops.forEach((loop, i) => {
      g.beginPath();
      loop.forEach((v, k) => {
        const p = this.toPixel(pane, field[2 * v]!, field[2 * v + 1]!);
        if (k === 0) g.moveTo(...p);
        else g.lineTo(...p);
      });
      g.closePath();
      g.strokeStyle = i === 0 ? "#1d2330" : "#b42318";
      g.lineWidth = i === 0 ? 1.2 : 2;
      g.stroke();
    });
  }

  private rings(g: CanvasRenderingContext2D): void {
    const radii = this.plan?.ringRadii;
    if (!radii) return;
    g.strokeStyle = "rgb(31 111 235 / 0.35)";
    g.lineWidth = 0.7;
    const f = this.frames.slit;
    const [cx, cy] = this.toPixel("slit", 0, 0);
    for (const r of radii) {
      g.beginPath();
      g.arc(cx, cy, r * f.scale, 0, 2 * Math.PI);
      g.stroke();
    }
  }

  /** The path as short polylines, coloured from start to end. */
  private spiral(g: CanvasRenderingContext2D, pane: Pane): void {
    const path = this.pathIn(pane);
    if (path === null) return;
    const n = path.length / 2;
    const chunks = Math.min(64, Math.max(1, n - 1));
    g.lineWidth = 1.3;
    for (let c = 0; c < chunks; c++) {
      const [i0, i1] = [Math.floor((c * (n - 1)) / chunks), Math.floor(((c + 1) * (n - 1)) / chunks)];
      g.beginPath();
      let open = false;
      for (let i = i0; i <= i1; i++) {
        const [u, v] = [path[2 * i]!, path[2 * i + 1]!];
        if (Number.isNaN(u)) {
          open = false;
          continue;
        }
        const p = this.toPixel(pane, u, v);
        if (open) g.lineTo(...p);
        else g.moveTo(...p);
        open = true;
      }
      g.strokeStyle = css(pathColour(c / Math.max(1, chunks - 1)));
      g.stroke();
    }
  }

  /** The static layer, then the poles and the cursor. */
  private draw(): void {
    const ratio = this.canvas.width / Math.max(1, this.canvas.clientWidth);
    const g = this.ctx;
    g.setTransform(1, 0, 0, 1, 0, 0);
    g.drawImage(this.layer, 0, 0);
    g.setTransform(ratio, 0, 0, ratio, 0, 0);
    const origin = this.plan?.report.origin;
    if (origin) {
      marker(g, this.toPixel("flat", origin.pole_uv[0], origin.pole_uv[1]), "#b42318", "star");
      if (origin.mode === "disk") marker(g, this.toPixel("slit", 0, 0), "#b42318", "star");
    }
    if (this.picked) marker(g, this.toPixel("flat", ...this.picked), "#e8590c", "ring");
    if (this.plan && this.cursor >= 0) {
      for (const pane of ["flat", "slit"] as const) {
        const path = this.pathIn(pane)!;
        const [u, v] = [path[2 * this.cursor], path[2 * this.cursor + 1]];
        if (u === undefined || v === undefined || Number.isNaN(u)) continue;
        marker(g, this.toPixel(pane, u, v), "#1d2330", "dot");
      }
    }
  }

  private pointer(event: MouseEvent): [number, number] {
    const rect = this.canvas.getBoundingClientRect();
    return [event.clientX - rect.left, event.clientY - rect.top];
  }

  private hover(event: PointerEvent): void {
    const [px, py] = this.pointer(event);
    const pane = this.paneAt(px, py);
    const path = pane && this.pathIn(pane);
    if (!pane || !path) return;
    // Nearest path point on screen (brute force: a pass over ≤ 10^5 points is well under a frame).
    let [best, bestD] = [-1, 24 * 24];
    for (let i = 0; i < path.length / 2; i++) {
      const [x, y] = this.toPixel(pane, path[2 * i]!, path[2 * i + 1]!);
      const d = (x - px) ** 2 + (y - py) ** 2;
      if (d < bestD) [best, bestD] = [i, d];
    }
    if (best >= 0 && best !== this.cursor) {
      this.setCursor(best);
      this.onCursor(best);
    }
  }

  private click(event: MouseEvent): void {
    const [px, py] = this.pointer(event);
    const pane = this.paneAt(px, py);
    if (pane === null || this.part?.uv == null) return;
    const [x, y] = this.fromPixel(pane, px, py);
    if (pane === "flat") return this.onPick(x, y);
    // Slit domain: back to the flattened plane through the image triangles.
    const w = this.field("slit");
    if (w === null) return;
    this.slitLocator ??= new PlanarLocator(w, this.part.triangles);
    const uv = this.slitLocator.map(x, y, this.part.uv);
    if (uv !== null) this.onPick(uv[0], uv[1]);
  }
}

function emptyFrame(): Frame {
  return { x: 0, y: 0, size: 1, scale: 1, cx: 0, cy: 0 };
}

function marker(g: CanvasRenderingContext2D, [x, y]: [number, number], colour: string, kind: "star" | "ring" | "dot"): void {
  g.beginPath();
  if (kind === "dot") {
    g.arc(x, y, 5, 0, 2 * Math.PI);
    g.fillStyle = "#ffffff";
    g.fill();
    g.lineWidth = 2.5;
    g.strokeStyle = colour;
    g.stroke();
    return;
  }
  if (kind === "ring") {
    g.arc(x, y, 7, 0, 2 * Math.PI);
    g.lineWidth = 2.5;
    g.strokeStyle = colour;
    g.stroke();
    return;
  }
  for (let k = 0; k < 10; k++) {
    const r = k % 2 === 0 ? 8 : 3.5;
    const a = -Math.PI / 2 + (k * Math.PI) / 5;
    const p: [number, number] = [x + r * Math.cos(a), y + r * Math.sin(a)];
    if (k === 0) g.moveTo(...p);
    else g.lineTo(...p);
  }
  g.closePath();
  g.fillStyle = colour;
  g.fill();
}
