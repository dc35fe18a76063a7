// The plan options' defaults: the CLI's (`slitpath plan`), so the page writes the same G-code.

import type { FlankOptions, PlanOptions, Vec3 } from "../core";

export type FullPlanOptions = Required<Omit<PlanOptions, "partName">>;

export const DEFAULT_PLAN_OPTIONS: Readonly<FullPlanOptions> = Object.freeze({
  radiusMm: 3,
  scallopMm: 0.02,
  axes: 3,
  leadDeg: 15,
  tiltDeg: 0,
  direction: "inward",
  cut: "climb",
  origin: "auto",
  post: "linuxcnc",
  feedMmMin: 1000,
  plungeFeedMmMin: 300,
  spindleRpm: 12000,
  safeZMm: null,
  verifySamples: 100000,
  facets: "exact",
  optimise: "tpsfo",
  alpha: 10,
  spread: "none",
});

/**
 * The flank options a machinist sets on the page (the rest keep the core's defaults). Defaults:
 * the core's `FlankOptions::default()`; `strips: null` lets the planner fit as many as the
 * surface needs.
 */
export interface FlankFormOptions {
  tipRadiusMm: number;
  topRadiusMm: number;
  fluteLengthMm: number;
  /** The tool above the flutes; null: the core's default (shank = top radius, gauge = 3 × flute, holder = 2 × shank). */
  shankRadiusMm: number | null;
  gaugeLengthMm: number | null;
  holderRadiusMm: number | null;
  direction: Vec3;
  strips: number | null;
  weights: "accuracy" | "g1";
  post: "ac" | "cl";
  feedMmMin: number;
  spindleRpm: number;
}

export const DEFAULT_FLANK_OPTIONS: Readonly<FlankFormOptions> = Object.freeze({
  tipRadiusMm: 1.5,
  topRadiusMm: 2.5,
  fluteLengthMm: 20,
  shankRadiusMm: null,
  gaugeLengthMm: null,
  holderRadiusMm: null,
  direction: [1, 0, 0] as Vec3,
  strips: null,
  weights: "accuracy",
  post: "ac",
  feedMmMin: 1000,
  spindleRpm: 12000,
});

/** The core's options of `form` (an automatic strip count and default tool body values are left out). */
export function flankOptions(form: FlankFormOptions): FlankOptions {
  const out: Record<string, unknown> = { ...form, direction: [...form.direction] };
  for (const key of ["strips", "shankRadiusMm", "gaugeLengthMm", "holderRadiusMm"] as const) {
    if (form[key] === null) delete out[key];
  }
  return out as FlankOptions;
}
