// The plan options form: one labelled input per option, each with a data-testid `opt-<name>`.
// Every edit is parsed; a field that does not parse is marked and reported instead of planned.

import type { OriginOption } from "../core";
import type { FullPlanOptions } from "../lib/defaults";
import { originFromText, originToText } from "../options";
import { el } from "./dom";
import { fieldRow, readFields, type FieldInput } from "./fields";

type NumberKey = "radiusMm" | "scallopMm" | "leadDeg" | "tiltDeg" | "feedMmMin" | "plungeFeedMmMin" | "spindleRpm" | "safeZMm" | "verifySamples" | "alpha";
type ChoiceKey = "axes" | "direction" | "cut" | "post" | "facets" | "optimise" | "spread";

interface NumberField { key: NumberKey; id: string; label: string; unit: string; step: string; optional?: boolean; fiveAxis?: boolean }
interface ChoiceField { key: ChoiceKey; id: string; label: string; choices: [string, string][] }

const TOOL: (NumberField | ChoiceField)[] = [
  { key: "radiusMm", id: "radius", label: "Ball radius", unit: "mm", step: "0.1" },
  { key: "scallopMm", id: "scallop", label: "Scallop height h", unit: "mm", step: "0.001" },
  { key: "axes", id: "axes", label: "Axes", choices: [["3", "3-axis"], ["5", "5-axis (lead/tilt)"]] },
  { key: "leadDeg", id: "lead", label: "Lead", unit: "°", step: "1", fiveAxis: true },
  { key: "tiltDeg", id: "tilt", label: "Tilt", unit: "°", step: "1", fiveAxis: true },
  { key: "direction", id: "direction", label: "Direction", choices: [["inward", "inward (boundary → centre)"], ["outward", "outward"]] },
  { key: "cut", id: "cut", label: "Cut", choices: [["climb", "climb"], ["conventional", "conventional"]] },
  { key: "facets", id: "facets", label: "Facets", choices: [["exact", "exact (the STL is the part)"], ["smooth", "smooth (a tessellated smooth surface)"]] },
  { key: "optimise", id: "optimise", label: "Rings", choices: [["tpsfo", "optimised field (seed 003, shorter)"], ["none", "conformal circles (seed 000)"]] },
  { key: "alpha", id: "alpha", label: "Smoothness α", unit: "", step: "1" },
  { key: "spread", id: "spread", label: "Ring spread", choices: [["none", "as the field's levels"], ["need", "by each meridian's need (also plans that, keeps the shorter)"]] },
];
const MACHINE: (NumberField | ChoiceField)[] = [
  { key: "post", id: "post", label: "Post", choices: [["linuxcnc", "LinuxCNC (3-axis)"], ["grbl", "GRBL (3-axis)"], ["ac", "5-axis AC table-table (TCP)"], ["cl", "CL data (APT)"]] },
  { key: "feedMmMin", id: "feed", label: "Feed", unit: "mm/min", step: "50" },
  { key: "plungeFeedMmMin", id: "plunge", label: "Plunge feed", unit: "mm/min", step: "10" },
  { key: "spindleRpm", id: "spindle", label: "Spindle", unit: "rpm", step: "500" },
  { key: "safeZMm", id: "safez", label: "Safe height", unit: "mm", step: "1", optional: true },
  { key: "verifySamples", id: "samples", label: "Verifier samples", unit: "", step: "10000" },
];

export class OptionsForm {
  private readonly inputs = new Map<string, FieldInput>();
  private readonly origin: HTMLSelectElement;
  private picked: OriginOption | null = null;
  private holes = 0;

  /** Called with valid options after every edit. */
  onChange: (options: FullPlanOptions) => void = () => {};
  /** Called with a message when a field does not parse. */
  onInvalid: (message: string) => void = () => {};

  constructor(container: HTMLElement, private current: FullPlanOptions) {
    this.origin = el("select", { testId: "opt-origin" });
    this.origin.id = "opt-origin";
    const originRow = el("label", { className: "field" }, el("span", { text: "Origin (pole)" }), this.origin);
    container.replaceChildren(
      this.group("Tool & path", TOOL, originRow),
      this.group("Machine", MACHINE),
    );
    this.set(current);
    container.addEventListener("change", () => this.edited());
    container.addEventListener("input", (event) => {
      if (event.target instanceof HTMLInputElement) this.edited();
    });
  }

  private group(title: string, fields: (NumberField | ChoiceField)[], ...extra: HTMLElement[]): HTMLElement {
    const box = el("fieldset", { className: "options" }, el("legend", { text: title }));
    for (const field of fields) box.append(this.row(field));
    box.append(...extra);
    return box;
  }

  private row(field: NumberField | ChoiceField): HTMLElement {
    const { row, input } = fieldRow("opt-", "optional" in field && field.optional ? { ...field, placeholder: "auto" } : field);
    this.inputs.set(field.key, input);
    if ("fiveAxis" in field && field.fiveAxis) row.classList.add("five-axis");
    return row;
  }

  /** Origin choices: auto, centroid, each hole (annulus map), and a pole picked in the 2D view. */
  setHoles(count: number): void {
    this.holes = count;
    this.renderOrigin();
  }

  private renderOrigin(): void {
    const choices: [string, string][] = [["auto", "auto (optimal pole)"], ["centroid", "centroid"]];
    for (let h = 1; h <= this.holes; h++) choices.push([`hole:${h}`, `hole ${h} (annulus)`]);
    const origin = this.current.origin;
    if (typeof origin === "object") this.picked = origin;
    if (this.picked !== null) choices.push([originToText(this.picked), `picked ${describe(this.picked)}`]);
    const text = originToText(origin);
    if (!choices.some(([value]) => value === text)) choices.push([text, text]);
    this.origin.replaceChildren(...choices.map(([value, label]) => new Option(label, value)));
    this.origin.value = text;
  }

  /** Shows `options` in the inputs (without calling onChange). */
  set(options: FullPlanOptions): void {
    this.current = options;
    for (const [key, input] of this.inputs) {
      const value = options[key as keyof FullPlanOptions];
      input.value = value === null ? "" : String(value);
      input.removeAttribute("aria-invalid");
    }
    this.renderOrigin();
    document.body.classList.toggle("five-axis-on", options.axes === 5);
  }

  private edited(): void {
    const out: Record<string, unknown> = { ...this.current };
    const bad = readFields(this.inputs, out, (key, input) => {
      const text = input.value.trim();
      if (key === "axes") return Number(text);
      if (!(input instanceof HTMLInputElement)) return text;
      return text === "" && key === "safeZMm" ? null : text !== "" && Number.isFinite(Number(text)) ? Number(text) : undefined;
    });
    const origin = originFromText(this.origin.value);
    if (origin !== null) out["origin"] = origin;
    if (bad.length > 0) return this.onInvalid(`${bad.join(", ")}: enter a number`);
    this.current = out as unknown as FullPlanOptions;
    document.body.classList.toggle("five-axis-on", this.current.axes === 5);
    this.onChange(this.current);
  }
}

function describe(origin: OriginOption): string {
  if (typeof origin === "string") return origin;
  const f = (v: number) => v.toFixed(3);
  return "z" in origin ? `(${f(origin.x)}, ${f(origin.y)}, ${f(origin.z)})` : `(${f(origin.x)}, ${f(origin.y)})`;
}
