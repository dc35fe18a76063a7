// The page's plan options: kept in localStorage and in the URL query (shareable), URL first.
// Only options that differ from the defaults are written to the URL.

import type { OriginOption } from "./core";
import { DEFAULT_PLAN_OPTIONS, type FullPlanOptions } from "./lib/defaults";

const STORAGE_KEY = "slitpath.options.v1";

type Key = keyof FullPlanOptions;

/** URL parameter name of each option. */
const PARAM: Record<Key, string> = {
  radiusMm: "radius",
  scallopMm: "scallop",
  axes: "axes",
  leadDeg: "lead",
  tiltDeg: "tilt",
  direction: "direction",
  cut: "cut",
  origin: "origin",
  post: "post",
  feedMmMin: "feed",
  plungeFeedMmMin: "plunge",
  spindleRpm: "spindle",
  safeZMm: "safez",
  verifySamples: "samples",
  facets: "facets",
  optimise: "optimise",
  alpha: "alpha",
  spread: "spread",
};

const CHOICES = {
  axes: [3, 5],
  direction: ["inward", "outward"],
  cut: ["climb", "conventional"],
  post: ["linuxcnc", "grbl", "ac", "cl"],
  facets: ["exact", "smooth"],
  optimise: ["tpsfo", "none"],
  spread: ["none", "need"],
} as const;

/** "auto" | "centroid" | "hole:N" | "x,y" (flattened plane) | "x,y,z" (3D point). */
export function originToText(origin: OriginOption): string {
  if (typeof origin === "string") return origin;
  return "z" in origin ? `${origin.x},${origin.y},${origin.z}` : `${origin.x},${origin.y}`;
}

export function originFromText(text: string): OriginOption | null {
  if (text === "auto" || text === "centroid") return text;
  if (/^hole:\d+$/.test(text)) return text as `hole:${number}`;
  const parts = text.split(",").map(Number);
  if (parts.some((p) => !Number.isFinite(p)) || text.trim() === "") return null;
  const [x, y, z] = parts;
  if (parts.length === 2) return { x: x!, y: y! };
  if (parts.length === 3) return { x: x!, y: y!, z: z! };
  return null;
}

/** Parses one option's text; null when it is not valid for that option. */
function parse<K extends Key>(key: K, text: string): FullPlanOptions[K] | null {
  let value: unknown;
  switch (key) {
    case "origin":
      value = originFromText(text);
      break;
    case "axes":
      value = text === "3" ? 3 : text === "5" ? 5 : null;
      break;
    case "safeZMm":
      value = text === "" || text === "auto" ? null : Number.isFinite(Number(text)) ? Number(text) : undefined;
      if (value === undefined) return null;
      return value as FullPlanOptions[K];
    default:
      // Every other choice by its list (a choice missing here was read as a number, and lost:
      // `spread=need` was, in the URL and in localStorage).
      if (key in CHOICES) {
        value = (CHOICES[key as keyof typeof CHOICES] as readonly unknown[]).includes(text) ? text : null;
      } else {
        value = text.trim() !== "" && Number.isFinite(Number(text)) ? Number(text) : null;
      }
  }
  return value as FullPlanOptions[K] | null;
}

function format(key: Key, value: FullPlanOptions[Key]): string {
  if (key === "origin") return originToText(value as OriginOption);
  return value === null ? "auto" : String(value);
}

function keys(): Key[] {
  return Object.keys(DEFAULT_PLAN_OPTIONS) as Key[];
}

/** The options in a URL query (parameters absent or invalid keep `base`). */
export function fromQuery(search: string, base: FullPlanOptions): FullPlanOptions {
  const params = new URLSearchParams(search);
  const out: Record<string, unknown> = { ...base };
  for (const key of keys()) {
    const text = params.get(PARAM[key]);
    if (text === null) continue;
    const value = parse(key, text);
    if (value !== null || key === "safeZMm") out[key] = value;
  }
  return out as unknown as FullPlanOptions;
}

/** The URL query of `options` (only what differs from the defaults) and the `extra` parameters. */
export function toQuery(options: FullPlanOptions, extra: [string, string][] = []): string {
  const params = new URLSearchParams(extra);
  for (const key of keys()) {
    const text = format(key, options[key]);
    if (text !== format(key, DEFAULT_PLAN_OPTIONS[key])) params.set(PARAM[key], text);
  }
  const query = params.toString();
  return query === "" ? "" : `?${query}`;
}

/** The query saved in localStorage ("" when none). */
export function storedQuery(): string {
  try {
    return localStorage.getItem(STORAGE_KEY) ?? "";
  } catch {
    return ""; // Storage may be disabled (privacy mode): defaults then.
  }
}

/** Options at start-up: defaults, then localStorage, then the URL. */
export function initialOptions(): FullPlanOptions {
  return fromQuery(location.search, fromQuery(storedQuery(), { ...DEFAULT_PLAN_OPTIONS }));
}

/**
 * Saves to localStorage and puts the options in the address bar (no reload, no history entry);
 * `extra`: further parameters (the strategy and the flank options, flank-options.ts).
 */
export function persist(options: FullPlanOptions, extra: [string, string][] = []): void {
  const query = toQuery(options, extra);
  try {
    localStorage.setItem(STORAGE_KEY, query);
  } catch {
    // Not fatal: the URL still carries them.
  }
  history.replaceState(null, "", `${location.pathname}${query}${location.hash}`);
}

/** The CLI arguments that plan with `options` (shown on the page, used by the tests). */
export function cliArguments(options: FullPlanOptions): string[] {
  const args = ["--radius", String(options.radiusMm), "--scallop", String(options.scallopMm), "--axes", String(options.axes)];
  args.push("--lead", String(options.leadDeg), "--tilt", String(options.tiltDeg), "--post", options.post);
  args.push("--origin", originToText(options.origin), "--direction", options.direction);
  args.push("--feed", String(options.feedMmMin), "--spindle", String(options.spindleRpm));
  if (options.safeZMm !== null) args.push("--safe-z", String(options.safeZMm));
  args.push("--facets", options.facets, "--optimise", options.optimise, "--alpha", String(options.alpha), "--spread", options.spread);
  return args;
}
