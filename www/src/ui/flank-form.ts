// The flank options form (strategy "flank"): the conical tool (flutes, shank, gauge length,
// holder; empty fields keep the core's defaults), the machining direction, the
// strips, the priority (the CLI's weights presets), the post, feed and spindle. Inputs have the
// data-testid `opt-flank-<name>`; a field that does not parse is marked and reported instead of
// planned. Values the core refuses (a negative radius, a zero flute) reach it: its message
// names the option.

import type { FlankFormOptions } from "../lib/defaults";
import { formatFlank, parseFlank } from "../flank-options";
import { el } from "./dom";
import { fieldRow, readFields, type FieldInput, type FieldSpec } from "./fields";

type Key = keyof FlankFormOptions;

type Field = FieldSpec & { key: Key };

const TOOL: Field[] = [
  { key: "tipRadiusMm", id: "tip", label: "Tip radius", unit: "mm" },
  { key: "topRadiusMm", id: "top", label: "Top radius", unit: "mm" },
  { key: "fluteLengthMm", id: "flute", label: "Flute length", unit: "mm" },
  { key: "shankRadiusMm", id: "shank", label: "Shank radius", unit: "mm", placeholder: "top radius", hint: "the shank or neck above the flutes" },
  { key: "gaugeLengthMm", id: "gauge", label: "Gauge length", unit: "mm", placeholder: "3 × flute", hint: "from the tool tip to the holder's face" },
  { key: "holderRadiusMm", id: "holder", label: "Holder radius", unit: "mm", placeholder: "2 × shank" },
];
const PATH: Field[] = [
  { key: "direction", id: "direction", label: "Direction X,Y,Z", inputMode: "text", hint: "the strips run along it; the shank points along n × direction" },
  { key: "strips", id: "strips", label: "Strips", placeholder: "auto" },
  {
    key: "weights",
    id: "priority",
    label: "Priority",
    choices: [
      ["accuracy", "accuracy (w₂ = 1, w₃ = 10⁻³)"],
      ["g1", "G¹ strip boundaries (w₂ = 10⁻⁴, w₃ = 1)"],
    ],
  },
];
const MACHINE: Field[] = [
  { key: "post", id: "post", label: "Post", choices: [["ac", "5-axis AC table-table (TCP)"], ["cl", "CL data (APT)"]] },
  { key: "feedMmMin", id: "feed", label: "Feed", unit: "mm/min" },
  { key: "spindleRpm", id: "spindle", label: "Spindle", unit: "rpm" },
];

export class FlankForm {
  private readonly inputs = new Map<Key, FieldInput>();

  /** Called with valid options after every edit. */
  onChange: (options: FlankFormOptions) => void = () => {};
  /** Called with a message when a field does not parse. */
  onInvalid: (message: string) => void = () => {};

  constructor(container: HTMLElement, private current: FlankFormOptions) {
    container.replaceChildren(
      this.group("Conical tool", TOOL),
      this.group("Strips", PATH),
      this.group("Machine", MACHINE),
    );
    this.set(current);
    container.addEventListener("change", () => this.edited());
    container.addEventListener("input", (event) => {
      if (event.target instanceof HTMLInputElement) this.edited();
    });
  }

  private group(title: string, fields: Field[]): HTMLElement {
    const box = el("fieldset", { className: "options" }, el("legend", { text: title }));
    for (const field of fields) {
      const { row, input } = fieldRow("opt-flank-", field);
      this.inputs.set(field.key, input);
      box.append(row);
    }
    return box;
  }

  /** Shows `options` in the inputs (without calling onChange). */
  set(options: FlankFormOptions): void {
    this.current = options;
    for (const [key, input] of this.inputs) {
      input.value = formatFlank(key, options[key]);
      input.removeAttribute("aria-invalid");
    }
  }

  private edited(): void {
    const out: Record<string, unknown> = { ...this.current };
    const bad = readFields(this.inputs, out, (key, input) => parseFlank(key, input.value.trim()));
    if (bad.length > 0) return this.onInvalid(`${bad.join(", ")}: enter ${bad.length === 1 ? "a valid value" : "valid values"} (numbers; direction as X,Y,Z; strips a whole number or empty)`);
    this.current = out as unknown as FlankFormOptions;
    this.onChange(this.current);
  }
}
