// The flank sample (written by `slitpath fixture blade` in scripts/start.sh and scripts/test.sh)
// and the options it is planned with: the tool of seed 002 Fig. 17 (its sphere family r₁ 3,
// r₂ 10, L 23.85 mm is the cone 2.87 / 9.56 / 21.8 mm) on a Ø19 mm shank with 70 mm gauge length
// in a Ø40 mm shrink-fit holder, 11 strips. Its concave side faces −X:
// along −Y the tool's shank points up (n × D = +Z).

import type { Vec3 } from "./core";
import type { FlankFormOptions } from "./lib/defaults";
import { DEFAULT_FLANK_OPTIONS } from "./lib/defaults";

export const BLADE_SAMPLE = "blade.stl";

/** The STEP sample (`slitpath fixture step:blade_band`): seed 004's blade over its fillet, 4 × 2 B-spline faces. */
export const STEP_SAMPLE = "blade_band.step";

export const BLADE_PRESET: Readonly<FlankFormOptions> = Object.freeze({
  ...DEFAULT_FLANK_OPTIONS,
  tipRadiusMm: 2.87,
  topRadiusMm: 9.56,
  fluteLengthMm: 21.8,
  shankRadiusMm: 9.5,
  gaugeLengthMm: 70,
  holderRadiusMm: 20,
  direction: [0, -1, 0] as Vec3,
  strips: 11,
});
