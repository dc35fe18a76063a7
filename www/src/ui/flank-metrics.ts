// The metrics panel of a flank plan: the verifier's figures as a machinist reads them (gouge,
// material left, RMS, coverage, the kink at every strip boundary), the optimiser's rigidity,
// the tool body and the collisions flagged, A/C flips, the program's length and time, stage timings.

import type { FlankResult } from "../lib/index";
import { metricsTable, timingLines, type Row } from "./metrics-table";

const n0 = new Intl.NumberFormat("en-US", { maximumFractionDigits: 0 });
const n1 = new Intl.NumberFormat("en-US", { maximumFractionDigits: 1 });
const n3 = new Intl.NumberFormat("en-US", { maximumSignificantDigits: 3 });
const mm = (v: number) => `${n3.format(v)} mm`;

/** RMS over every machined sample, from the strips' own RMS and sample counts. */
function rms(strips: { samples: number; rms_mm: number }[]): number {
  const n = strips.reduce((s, x) => s + x.samples, 0);
  return n > 0 ? Math.sqrt(strips.reduce((s, x) => s + x.samples * x.rms_mm ** 2, 0) / n) : NaN;
}

/** How many moves are flagged, and the worst one: its kind, the tool part and where. */
function flagged(collisions: FlankResult["report"]["collisions"]): string {
  const f = collisions.flagged;
  if (f.length === 0) return "0";
  const worst = f.reduce((a, b) => (b.clearance_mm < a.clearance_mm ? b : a));
  const at = worst.at.map((x) => n1.format(x)).join(", ");
  return `${n0.format(f.length)} of ${n0.format(collisions.checked_moves)} moves; worst: ${worst.what} on ${worst.kind} move ${worst.move_index}, ${mm(worst.clearance_mm)} at (${at})`;
}

function rows(plan: FlankResult): Row[] {
  const { report } = plan;
  const v = report.verify;
  const { spheres, optimise, output, collisions, guide } = report;
  const rigidity = optimise.final_figures.max_rigidity_error_mm;
  const tolerance = report.options.rigidity_tolerance_rel * spheres.length_mm;
  const time = output.estimated_time_s;
  const common: Row[] = [
    ["metric-flank-strips", "Strips", `${n0.format(guide.strips)} (${guide.poses_per_strip.map((p) => n0.format(p)).join(", ")} poses)`],
    ["metric-flank-tool", "Sphere family r₁ / r₂ / L", `${mm(spheres.r1_mm)} / ${mm(spheres.r2_mm)} / ${mm(spheres.length_mm)}`],
    ["metric-flank-moves", "Program", `${n0.format(output.moves)} moves, cut ${n1.format(output.cut_length_mm)} mm, links ${n1.format(output.link_length_mm)} mm`],
    ["metric-flank-time", "Cutting time", time < 60 ? `${n0.format(time)} s` : `${n1.format(time / 60)} min`],
    ["metric-flank-rigidity", "Rigidity | |b − a| − L |", `${mm(rigidity)} (tolerance ${mm(tolerance)})`, rigidity > tolerance],
    ["metric-flank-body", "Shank r / gauge / holder r", `${mm(collisions.tool.shank_radius_mm)} / ${mm(collisions.tool.gauge_length_mm)} / ${mm(collisions.tool.holder_radius_mm)}`],
    ["metric-flank-collisions", "Collisions flagged (shank, holder, rapids)", flagged(collisions), collisions.flagged.length > 0],
  ];
  if (v === null) return [...common, ["metric-flank-verify", "Verification", "skipped (0 verifier samples)", true]];
  const kinks = v.seams.map((s) => `${s.strips[0]}|${s.strips[1]} ${n3.format(s.envelope_max_kink_deg)}°`);
  const k = v.kinematics;
  return [
    ["metric-flank-gouge", "Max gouge", `${mm(v.max_gouge_mm)} (${n0.format(v.gouges)} samples beyond ${mm(v.tolerance_mm)})`, v.gouges > 0],
    ["metric-flank-undercut", "Max material left", mm(v.max_undercut_mm)],
    ["metric-flank-rms", "RMS deviation", mm(rms(v.strips))],
    [
      "metric-flank-coverage",
      "Within ±tolerance",
      `${n1.format(100 * v.coverage_within_tolerance)} % of the surface (machined ${n1.format(100 * v.machined_fraction)} %)`,
      v.machined_fraction < 1,
    ],
    ["metric-flank-kinks", "Kink at strip boundaries", kinks.length > 0 ? kinks.join(", ") : "one strip: no boundary"],
    ["metric-flank-flips", "A/C: C flips / A sign changes", `${n0.format(k.c_flips)} / ${n0.format(k.a_sign_changes)}`, k.c_flips + k.a_sign_changes > 0],
    ...common,
  ];
}

/** Replaces the panel's content with the metrics of a flank plan. */
export function renderFlankMetrics(container: HTMLElement, plan: FlankResult): void {
  container.replaceChildren(metricsTable(rows(plan)), ...timingLines(plan.report.timings_ms, plan.ms, plan.wasmMemoryBytes));
}
