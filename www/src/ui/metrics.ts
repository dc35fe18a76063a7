// The metrics panel: the plan report as a machinist reads it (path, time, scallop against the
// limit h, uniformity, gouge risk, the optimised pole against the centroid pole, stage timings).

import type { PlanResult } from "../lib/index";
import { el } from "./dom";
import { metricsTable, timingLines, type Row } from "./metrics-table";

const n0 = new Intl.NumberFormat("en-US", { maximumFractionDigits: 0 });
const n1 = new Intl.NumberFormat("en-US", { maximumFractionDigits: 1 });
const n3 = new Intl.NumberFormat("en-US", { maximumSignificantDigits: 3 });
const mm = (v: number) => `${n3.format(v)} mm`;

function rows(plan: PlanResult, limit: number): Row[] {
  const { report } = plan;
  const { path, verify, origin } = report;
  const gain = origin.e_min_centroid > 0 ? 1 - origin.e_min / origin.e_min_centroid : 0;
  const minutes = path.time_min;
  const rejected = origin.rejected?.length ?? 0;
  const optimise = report.optimise;
  const retry = report.spacing_retries?.at(-1);
  const spread = report.spread;
  return [
    ["metric-rings", "Rings", n0.format(plan.ringRadii.length)],
    // Only when the first path's own verification left more than h (src/plan/paths.rs).
    ...(retry === undefined
      ? []
      : [
          [
            "metric-spacing-retry",
            "Rings spaced again",
            `the first path left ${n3.format(retry.max_over_h)} h; spaced for ${n3.format(retry.retry_target_fraction)} h` +
              (retry.retry_max_over_h === null ? `: ${retry.error ?? "failed"}` : `: ${n3.format(retry.retry_max_over_h)} h`) +
              (retry.kept ? "" : ", not kept"),
            !retry.kept,
          ] satisfies Row,
        ]),
    ["metric-length", "Path length", `${n1.format(path.length_mm)} mm (${n0.format(path.points)} points)`],
    // The flat-plate bound area / (2·√(2Rh)): evenly spaced passes on a gently curved part come
    // to about 1.05.
    ["metric-length-ideal", "Length / ideal", n3.format(path.length_over_ideal)],
    [
      "metric-field",
      "Ring field",
      optimise === undefined
        ? "conformal circles (seed 000)"
        : optimise.path_field === "tpsfo"
          ? `optimised (seed 003): ${n0.format(optimise.iterations ?? 0)} steps, uniformity ${n3.format(optimise.uniformity_before ?? 0)} → ${n3.format(optimise.uniformity_after ?? 0)}`
          : `conformal circles: ${optimise.fallback ?? "the optimised field was not used"}`,
      optimise !== undefined && optimise.path_field !== "tpsfo",
    ],
    // Only with `spread: "need"`: the spread path's length, the unspread one's when it was planned,
    // and which one was written.
    ...(spread === undefined
      ? []
      : [
          [
            "metric-spread",
            "Ring spread",
            spread.length_mm === null
              ? `not planned: ${spread.error ?? "failed"}`
              : spread.unspread_length_mm === null
                ? `kept: ${n1.format(spread.length_mm)} mm (${n3.format(spread.max_over_h ?? 0)} h); the unspread path was not needed`
                : `${spread.kept ? "kept" : "not kept"}: ${n1.format(spread.length_mm)} mm against ${n1.format(spread.unspread_length_mm)} mm` +
                  ` (${n3.format(spread.max_over_h ?? 0)} h against ${n3.format(spread.unspread_max_over_h ?? 0)} h)`,
            !spread.kept,
          ] satisfies Row,
        ]),
    ["metric-time", "Cutting time", minutes < 1 ? `${n0.format(minutes * 60)} s` : `${n1.format(minutes)} min`],
    ["metric-retractions", "Retractions", n0.format(path.retractions), path.retractions > 0],
    ["metric-max-turn", "Sharpest turn", `${n1.format(path.max_turn_deg)}°`],
    ["metric-max-scallop", "Max scallop", `${mm(verify.max_scallop_mm)} (h = ${mm(limit)})`, verify.max_scallop_mm > limit * 1.0001],
    [
      "metric-mean-scallop",
      "Median / mean / p95 / p99",
      `${mm(verify.median_scallop_mm)} / ${mm(verify.mean_scallop_mm)} / ${mm(verify.p95_scallop_mm)} / ${mm(verify.p99_scallop_mm)}`,
    ],
    ["metric-vmax", "V_max (uniformity)", `${n3.format(verify.v_max_mm2)} mm²`],
    ["metric-uncovered", "Uncovered", `${n3.format(100 * verify.uncovered_fraction)} % of samples`, verify.uncovered_fraction > 0],
    ["metric-gouges", "Gouges", n0.format(verify.gouges), verify.gouges > 0],
    [
      "metric-valleys",
      "Facet valleys (no ball leaves < 0.75 h)",
      // Where every ball touching the facets leaves more than 0.75 h whatever the path: the
      // scallop promise is for the rest.
      `${n3.format(verify.valley_area_mm2)} mm²; max scallop elsewhere ${mm(verify.max_scallop_outside_valleys_mm)}`,
      verify.valley_area_mm2 > 0 || verify.max_scallop_outside_valleys_mm > limit * 1.0001,
    ],
    [
      "metric-clearance",
      "Ball lifted off facets",
      `${n0.format(path.clearance.moved)} centres, up to ${mm(path.clearance.max_move_mm)}`,
      // Lifted by more than h/2 the ball leaves visible cusps where facets meet: the STL is
      // coarse for this h (facets "smooth" follows the vertex normals instead, and is lifted
      // only out of creases sharper than the facets' own deviation from them).
      path.clearance.max_move_mm > 0.5 * limit || path.clearance.unresolved > 0,
    ],
    ["metric-gouge-risk", "Gouge-risk area", `${n3.format(report.gouge_risk_area_mm2)} mm²`, report.gouge_risk_area_mm2 > 0],
    [
      "metric-compromises",
      "Rings not proven (folds / sharp creases / gate)",
      `${n0.format(report.fold_compromises)} / ${n0.format(report.crease_compromises)} / ${n0.format(report.gate_compromises)}`,
      report.fold_compromises + report.crease_compromises + report.gate_compromises > 0,
    ],
    [
      "metric-origin",
      "Origin",
      `${origin.mode}, pole (${origin.pole_uv.map((v) => n3.format(v)).join(", ")})` +
        (rejected > 0 ? ` — ${rejected} pole${rejected > 1 ? "s" : ""} tried first gave no path` : ""),
      rejected > 0,
    ],
    ["metric-energy", "E_min (this pole)", `${n3.format(origin.e_min)} (uniformity ${n3.format(origin.uniformity)})`],
    [
      "metric-centroid",
      "vs centroid pole",
      `${n3.format(origin.e_min_centroid)}: ${gain >= 0 ? "" : "+"}${n1.format(Math.abs(100 * gain))} % ${gain >= 0 ? "lower" : "higher"} here`,
      gain < 0,
    ],
  ];
}

/** Replaces the panel's content with the metrics of `plan` (scallop limit `limit`, mm). */
export function renderMetrics(container: HTMLElement, plan: PlanResult, limit: number): void {
  container.replaceChildren(
    ...plan.report.warnings.map((text) => el("p", { className: "plan-warning", testId: "plan-warning", text: `⚠ ${text}` })),
    metricsTable(rows(plan, limit)),
    ...timingLines(plan.report.timings_ms, plan.ms, plan.wasmMemoryBytes),
  );
}

export function renderNoPlan(container: HTMLElement, text: string): void {
  container.replaceChildren(el("p", { className: "empty", text }));
}
