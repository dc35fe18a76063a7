// The plan options' defaults: the CLI's (`slitpath plan`), so the page writes the same G-code.

import type { PlanOptions } from "../core";

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
});
