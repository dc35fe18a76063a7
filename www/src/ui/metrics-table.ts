// What the metrics panels (spiral, flank, Coons band) share: the table of figures and the lines
// of stage timings and planner memory under it.

import { el } from "./dom";

const n0 = new Intl.NumberFormat("en-US", { maximumFractionDigits: 0 });

/** One figure: its data-testid, label and value; `warn` marks it. */
export type Row = [testId: string, label: string, value: string, warn?: boolean];

export function metricsTable(rows: Row[]): HTMLTableElement {
  const body = el("tbody");
  for (const [testId, label, value, warn] of rows) {
    const td = el("td", { text: value, testId });
    if (warn) td.classList.add("warn");
    body.append(el("tr", {}, el("th", { text: label }), td));
  }
  return el("table", { className: "metrics-table" }, body);
}

/** The stage timings (ms; their `total`, else `ms`) and the planner's memory. */
export function timingLines(timings: Record<string, number>, ms: number, wasmMemoryBytes: number): HTMLElement[] {
  const stages = Object.entries(timings)
    .filter(([stage]) => stage !== "total")
    .map(([stage, t]) => `${stage} ${n0.format(t)}`)
    .join(" · ");
  return [
    el("p", { className: "timings", testId: "metric-timings", text: `Stage timings (ms): ${stages} — total ${n0.format(timings["total"] ?? ms)}` }),
    // Linear memory never shrinks: this is the planner's peak so far (big parts need watching).
    el("p", { className: "timings", testId: "metric-memory", text: `Planner memory: ${n0.format(wasmMemoryBytes / 2 ** 20)} MiB` }),
  ];
}
