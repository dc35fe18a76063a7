// The Coons band options form (strategy "coons"): ball, scallop limit, axes, lead/tilt, post,
// seam smoothing, feed, spindle and verifier samples. Inputs have the data-testid
// `opt-coons-<name>`; a field that does not parse is marked and reported instead of planned.

import { parseCoons, type CoonsFormOptions } from "../coons-options";
import { el } from "./dom";
import { fieldRow, readFields, type FieldInput, type FieldSpec } from "./fields";

type Key = keyof CoonsFormOptions;

const FIELDS: (FieldSpec & { key: Key })[] = [
  { key: "radiusMm", id: "radius", label: "Ball radius R", unit: "mm" },
  { key: "scallopMm", id: "scallop", label: "Scallop h", unit: "mm" },
  { key: "axes", id: "axes", label: "Axes", choices: [["5", "5-axis (lead/tilt)"], ["3", "3-axis"]] },
  { key: "leadDeg", id: "lead", label: "Lead", unit: "°" },
  { key: "tiltDeg", id: "tilt", label: "Tilt", unit: "°" },
  { key: "post", id: "post", label: "Post", choices: [["ac", "5-axis AC table-table (TCP)"], ["cl", "CL data (APT)"], ["linuxcnc", "LinuxCNC (3-axis)"], ["grbl", "GRBL (3-axis)"]] },
  { key: "smooth", id: "smooth", label: "Seams", choices: [["true", "composite C¹ smoothing"], ["false", "raw Coons map"]] },
  { key: "feedMmMin", id: "feed", label: "Feed", unit: "mm/min" },
  { key: "spindleRpm", id: "spindle", label: "Spindle", unit: "rpm" },
  { key: "verifySamples", id: "samples", label: "Verifier samples" },
];

export class CoonsForm {
  private readonly inputs = new Map<Key, FieldInput>();

  onChange: (options: CoonsFormOptions) => void = () => {};
  onInvalid: (message: string) => void = () => {};

  constructor(container: HTMLElement, private current: CoonsFormOptions) {
    const box = el("fieldset", { className: "options" }, el("legend", { text: "Coons band spiral (seed 004)" }));
    for (const field of FIELDS) {
      const { row, input } = fieldRow("opt-coons-", field);
      this.inputs.set(field.key, input);
      box.append(row);
    }
    container.replaceChildren(box);
    this.set(current);
    container.addEventListener("change", () => this.edited());
  }

  set(options: CoonsFormOptions): void {
    this.current = options;
    for (const [key, input] of this.inputs) {
      input.value = String(options[key]);
      input.removeAttribute("aria-invalid");
    }
  }

  private edited(): void {
    const out: Record<string, unknown> = { ...this.current };
    const bad = readFields(this.inputs, out, (key, input) => parseCoons(key, input.value));
    if (bad.length > 0) return this.onInvalid(`${bad.join(", ")}: enter valid numbers`);
    this.current = out as unknown as CoonsFormOptions;
    this.onChange(this.current);
  }
}
