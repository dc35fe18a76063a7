// The metrics panel of a Coons band plan (seed 004): the band, revolutions and spacing, the seams'
// tangent jumps before and after smoothing, the verifier's scallop figures, the path, timings.

import type { CoonsResult } from "../lib/index";
import { el } from "./dom";
import { metricsTable, timingLines, type Row } from "./metrics-table";

const n0 = new Intl.NumberFormat("en-US", { maximumFractionDigits: 0 });
const n3 = new Intl.NumberFormat("en-US", { maximumSignificantDigits: 3 });
const mm = (v: number) => `${n3.format(v)} mm`;
const deg = (v: number) => `${n3.format(v)}°`;

function rows(plan: CoonsResult): Row[] {
  const r = plan.report;
  const s = r.seams;
  const v = r.verify;
  const out: Row[] = [
    ["metric-coons-band", "Band", `${r.band.around} × ${r.band.across} faces (${plan.faces.map((f) => `#${f}`).join(" ")})`],
    ["metric-coons-revolutions", "Revolutions", `${n0.format(r.revolutions)} (${n0.format(r.levels)} levels)`],
    ["metric-coons-spacing", "Spacing", `${mm(r.min_spacing_mm)} – ${mm(r.max_spacing_mm)} (nominal ${mm(r.nominal_stepover_mm)})`],
    ["metric-coons-seams", `Seam jumps (${s.mode})`, `round the loop max ${deg(s.round_before.max_deg)} → ${deg(s.round_after.max_deg)}; rows ${deg(s.rows_before.max_deg)} → ${deg(s.rows_after.max_deg)}`],
    ["metric-coons-length", "Path", `${n0.format(r.length_mm)} mm, ${n0.format(r.points)} points, ${r.retractions} retractions, ${n3.format(r.time_min)} min`],
  ];
  if (v === null) return [...out, ["metric-coons-verify", "Verification", "skipped (0 verifier samples)", true]];
  return [
    ["metric-coons-scallop", "Max / p95 scallop", `${mm(v.max_scallop_mm)} / ${mm(v.p95_scallop_mm)} (h = ${mm(r.scallop_mm)})`, v.max_scallop_mm > r.scallop_mm],
    ["metric-coons-gouges", "Gouges / uncovered", `${n0.format(v.gouges)} / ${n3.format(100 * v.uncovered_fraction)} %`, v.gouges > 0],
    ...out,
  ];
}

/** Replaces the panel's content with the metrics of a Coons band plan. */
export function renderCoonsMetrics(container: HTMLElement, plan: CoonsResult): void {
  const note = plan.report.seams.note ? [el("p", { className: "hint", text: `Seams: ${plan.report.seams.note}` })] : [];
  container.replaceChildren(metricsTable(rows(plan)), ...note, ...timingLines(plan.report.timings, plan.ms, plan.wasmMemoryBytes));
}
