// The page's strategy (spiral, flank or Coons band) and flank options in the URL query and localStorage,
// beside the spiral's (options.ts): `strategy=flank` and `flank-*` parameters, only what differs
// from the defaults. Also the CLI arguments of a flank plan (shown on the page, used by the tests).

import type { Vec3 } from "./core";
import { DEFAULT_FLANK_OPTIONS, type FlankFormOptions } from "./lib/defaults";

export type Strategy = "spiral" | "flank" | "coons";

type Key = keyof FlankFormOptions;

const PARAM: Record<Key, string> = {
  tipRadiusMm: "flank-tip",
  topRadiusMm: "flank-top",
  fluteLengthMm: "flank-flute",
  shankRadiusMm: "flank-shank",
  gaugeLengthMm: "flank-gauge",
  holderRadiusMm: "flank-holder",
  direction: "flank-direction",
  strips: "flank-strips",
  weights: "flank-priority",
  post: "flank-post",
  feedMmMin: "flank-feed",
  spindleRpm: "flank-spindle",
};

/** "x,y,z" → a vector; null unless three finite numbers. */
export function directionFromText(text: string): Vec3 | null {
  const parts = text.split(",").map((p) => (p.trim() === "" ? NaN : Number(p)));
  return parts.length === 3 && parts.every(Number.isFinite) ? (parts as Vec3) : null;
}

export const directionToText = (v: Vec3): string => v.join(",");

/** "" → null (automatic); a whole number ≥ 1; undefined when invalid. */
export function stripsFromText(text: string): number | null | undefined {
  if (text.trim() === "" || text === "auto") return null;
  const n = Number(text);
  return Number.isInteger(n) && n >= 1 ? n : undefined;
}

/** One flank option's value from its text; undefined when it does not parse. */
export function parseFlank<K extends Key>(key: K, text: string): FlankFormOptions[K] | undefined {
  let value: unknown;
  switch (key) {
    case "direction":
      value = directionFromText(text) ?? undefined;
      break;
    case "strips":
      value = stripsFromText(text);
      break;
    case "shankRadiusMm":
    case "gaugeLengthMm":
    case "holderRadiusMm":
      value = text.trim() === "" || text === "auto" ? null : text.trim() !== "" && Number.isFinite(Number(text)) ? Number(text) : undefined;
      break;
    case "weights":
      value = text === "accuracy" || text === "g1" ? text : undefined;
      break;
    case "post":
      value = text === "ac" || text === "cl" ? text : undefined;
      break;
    default:
      value = text.trim() !== "" && Number.isFinite(Number(text)) ? Number(text) : undefined;
  }
  return value as FlankFormOptions[K] | undefined;
}

export function formatFlank(key: Key, value: FlankFormOptions[Key]): string {
  if (key === "direction") return directionToText(value as Vec3);
  return value === null ? "" : String(value);
}

const keys = () => Object.keys(DEFAULT_FLANK_OPTIONS) as Key[];

/** The strategy and flank options of a URL query (absent or invalid parameters keep `base`). */
export function flankFromQuery(search: string, base: { strategy: Strategy; flank: FlankFormOptions }): { strategy: Strategy; flank: FlankFormOptions } {
  const params = new URLSearchParams(search);
  const flank: Record<string, unknown> = { ...base.flank };
  for (const key of keys()) {
    const text = params.get(PARAM[key]);
    if (text === null) continue;
    const value = parseFlank(key, text);
    if (value !== undefined) flank[key] = value;
  }
  const s = params.get("strategy");
  return { strategy: s === "flank" || s === "spiral" || s === "coons" ? s : base.strategy, flank: flank as unknown as FlankFormOptions };
}

/** Query parameters of the strategy and flank options that differ from the defaults. */
export function flankQuery(strategy: Strategy, flank: FlankFormOptions): [string, string][] {
  const out: [string, string][] = strategy === "spiral" ? [] : [["strategy", strategy]];
  for (const key of keys()) {
    const text = formatFlank(key, flank[key]);
    if (text !== formatFlank(key, DEFAULT_FLANK_OPTIONS[key])) out.push([PARAM[key], text]);
  }
  return out;
}

/** The `slitpath flank` arguments that plan with `flank` (the CLI has no defaults for the tool and direction). */
export function flankCliArguments(flank: FlankFormOptions): string[] {
  const args = ["--tip-radius", String(flank.tipRadiusMm), "--top-radius", String(flank.topRadiusMm)];
  args.push("--flute-length", String(flank.fluteLengthMm));
  if (flank.shankRadiusMm !== null) args.push("--shank-radius", String(flank.shankRadiusMm));
  if (flank.gaugeLengthMm !== null) args.push("--gauge-length", String(flank.gaugeLengthMm));
  if (flank.holderRadiusMm !== null) args.push("--holder-radius", String(flank.holderRadiusMm));
  args.push("--direction", directionToText(flank.direction));
  if (flank.strips !== null) args.push("--strips", String(flank.strips));
  args.push("--weights", flank.weights, "--post", flank.post, "--feed", String(flank.feedMmMin), "--spindle", String(flank.spindleRpm));
  return args;
}
