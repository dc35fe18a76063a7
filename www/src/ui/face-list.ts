// The STEP faces panel: one row per face (id, surface type, area) with a checkbox that selects it
// for machining, and "all" / "none". Clicking a face in the 3D view toggles the same selection.

import type { StepFace } from "../lib/index";
import { el } from "./dom";

const n1 = new Intl.NumberFormat("en-US", { maximumFractionDigits: 1 });

export class FaceList {
  private boxes = new Map<number, HTMLInputElement>();

  /** Called with the selected face ids (list order) after every change by the user. */
  onChange: (selected: number[]) => void = () => {};

  constructor(private readonly container: HTMLElement) {}

  /** Shows `faces` (none: hides the panel) with `selected` ticked. */
  show(faces: StepFace[] | null, selected: Set<number>): void {
    this.boxes.clear();
    const panel = this.container.closest<HTMLElement>(".panel");
    if (panel) panel.hidden = faces === null;
    if (faces === null) return this.container.replaceChildren();
    const body = el("tbody");
    for (const face of faces) {
      const box = el("input");
      box.type = "checkbox";
      box.checked = selected.has(face.id);
      box.dataset["testid"] = `face-${face.id}`;
      box.addEventListener("change", () => this.onChange(this.selected()));
      this.boxes.set(face.id, box);
      const label = el("label", {}, box, ` #${face.id}`);
      body.append(el("tr", {}, el("td", {}, label), el("td", { text: face.surface }), el("td", { text: `${n1.format(face.area_mm2)} mm²` })));
    }
    const all = el("button", { text: "all", className: "button small", testId: "faces-all" });
    const none = el("button", { text: "none", className: "button small", testId: "faces-none" });
    all.type = none.type = "button";
    all.addEventListener("click", () => this.setAll(true));
    none.addEventListener("click", () => this.setAll(false));
    const head = el("thead", {}, el("tr", {}, el("th", { text: "face" }), el("th", { text: "surface" }), el("th", { text: "area" })));
    this.container.replaceChildren(el("div", { className: "controls" }, all, none), el("table", { className: "metrics-table faces-table" }, head, body));
  }

  /** Ticks exactly `selected` (without calling onChange). */
  set(selected: Set<number>): void {
    for (const [id, box] of this.boxes) box.checked = selected.has(id);
  }

  selected(): number[] {
    return [...this.boxes].filter(([, box]) => box.checked).map(([id]) => id);
  }

  private setAll(on: boolean): void {
    for (const box of this.boxes.values()) box.checked = on;
    this.onChange(this.selected());
  }
}
