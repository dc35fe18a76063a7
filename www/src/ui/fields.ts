// What the option forms (spiral, flank, Coons band) share: a labelled row per option, an input
// or a select, and reading the rows back, marking those that do not parse.

import { el } from "./dom";

export type FieldInput = HTMLInputElement | HTMLSelectElement;

export interface FieldSpec {
  /** The input's id and data-testid are the form's prefix and this. */
  id: string;
  label: string;
  /** Shown after the input (none when empty). */
  unit?: string;
  /** A select of [value, text] instead of a text input. */
  choices?: [string, string][];
  placeholder?: string;
  /** The input's tooltip. */
  hint?: string;
  /** Default "decimal". */
  inputMode?: string;
}

/** The labelled row of `field` and its input (id and data-testid `${prefix}${field.id}`). */
export function fieldRow(prefix: string, field: FieldSpec): { row: HTMLLabelElement; input: FieldInput } {
  let input: FieldInput;
  if (field.choices) {
    input = el("select");
    for (const [value, text] of field.choices) input.append(new Option(text, value));
  } else {
    input = el("input");
    input.type = "text";
    input.inputMode = field.inputMode ?? "decimal";
    input.autocomplete = "off";
    if (field.placeholder) input.placeholder = field.placeholder;
  }
  input.id = `${prefix}${field.id}`;
  input.dataset["testid"] = `${prefix}${field.id}`;
  if (field.hint) input.title = field.hint;
  const unit = field.unit ? el("span", { text: field.unit, className: "unit" }) : "";
  return { row: el("label", { className: "field" }, el("span", { text: field.label }), input, unit), input };
}

/**
 * Reads every input with `parse` (undefined: it does not parse) into `out`; an input that does not
 * parse is marked aria-invalid and left out. Returns the labels of those.
 */
export function readFields<K extends string>(inputs: Map<K, FieldInput>, out: Record<string, unknown>, parse: (key: K, input: FieldInput) => unknown): string[] {
  const bad: string[] = [];
  for (const [key, input] of inputs) {
    const value = parse(key, input);
    if (value === undefined) {
      input.setAttribute("aria-invalid", "true");
      bad.push(input.closest("label")?.firstChild?.textContent ?? key);
    } else {
      input.removeAttribute("aria-invalid");
      out[key] = value;
    }
  }
  return bad;
}
