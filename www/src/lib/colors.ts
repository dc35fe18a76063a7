// Colour scales of the views (RGB components in 0..1): the worker colours the heat map and the
// path with them, the page its legend.

export type Rgb = [number, number, number];

const lerp = (a: Rgb, b: Rgb, t: number): Rgb => [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t];

function ramp(stops: Rgb[], t: number): Rgb {
  const x = Math.min(1, Math.max(0, t)) * (stops.length - 1);
  const i = Math.min(stops.length - 2, Math.floor(x));
  return lerp(stops[i]!, stops[i + 1]!, x - i);
}

/** Along the path: start (deep blue) → teal → purple → end (near black): the direction of travel reads at a glance. */
// Dark tones: the path must stand out on the light part and on the heat map alike.
const PATH: Rgb[] = [
  [0.05, 0.15, 0.6],
  [0.0, 0.42, 0.55],
  [0.38, 0.12, 0.55],
  [0.08, 0.06, 0.1],
];
export const pathColour = (t: number): Rgb => ramp(PATH, t);

/** Scallop height as a fraction of the limit h: 0 green → h red; beyond h magenta. */
const HEAT: Rgb[] = [
  [0.12, 0.55, 0.3],
  [0.6, 0.8, 0.25],
  [0.98, 0.85, 0.2],
  [0.95, 0.45, 0.15],
  [0.8, 0.1, 0.1],
];
export const OVER_LIMIT: Rgb = [0.85, 0.1, 0.75];
export const UNCOVERED: Rgb = [0.55, 0.57, 0.6];
export const SURFACE: Rgb = [0.72, 0.75, 0.8];

export function heatColour(scallop: number, limit: number): Rgb {
  if (Number.isNaN(scallop)) return UNCOVERED;
  if (scallop > limit) return OVER_LIMIT;
  return ramp(HEAT, scallop / limit);
}

/** CSS linear-gradient stops of the heat scale (for the legend). */
export function heatGradientCss(): string {
  const stops = HEAT.map((c, i) => `${css(c)} ${((100 * i) / (HEAT.length - 1)).toFixed(0)}%`);
  return `linear-gradient(to right, ${stops.join(", ")})`;
}

export function css(c: Rgb, alpha = 1): string {
  const [r, g, b] = c.map((v) => Math.round(v * 255));
  return alpha === 1 ? `rgb(${r} ${g} ${b})` : `rgb(${r} ${g} ${b} / ${alpha})`;
}

/**
 * The flank verifier's signed deviation as a fraction of the scale's limit: gouge (negative)
 * blue → on the surface green → material left (positive) red. Signed, because a gouge scraps the
 * part while material left can be cut again.
 */
const DEVIATION: Rgb[] = [
  [0.15, 0.2, 0.75],
  [0.2, 0.6, 0.85],
  [0.12, 0.55, 0.3],
  [0.98, 0.85, 0.2],
  [0.8, 0.1, 0.1],
];

export function deviationColour(deviation: number, limit: number): Rgb {
  if (Number.isNaN(deviation)) return UNCOVERED;
  return ramp(DEVIATION, 0.5 + 0.5 * (deviation / limit));
}

export function deviationGradientCss(): string {
  const stops = DEVIATION.map((c, i) => `${css(c)} ${((100 * i) / (DEVIATION.length - 1)).toFixed(0)}%`);
  return `linear-gradient(to right, ${stops.join(", ")})`;
}

/** Alternating strip colours of the flank plan's tool axes and tip paths. */
export const STRIP_COLOURS: Rgb[] = [
  [0.48, 0.31, 0.82],
  [0.05, 0.42, 0.55],
];
