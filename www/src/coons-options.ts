// The Coons band strategy's options (seed 004, `slitpath coons`): defaults (the CLI's), the URL
// query and localStorage (`coons-*` parameters, only what differs from the defaults), and the CLI
// arguments of a Coons plan (shown on the page, used by the tests).

import type { CoonsOptions } from "./core";

export interface CoonsFormOptions {
  radiusMm: number;
  scallopMm: number;
  axes: 3 | 5;
  leadDeg: number;
  tiltDeg: number;
  post: "ac" | "cl" | "linuxcnc" | "grbl";
  smooth: boolean;
  feedMmMin: number;
  spindleRpm: number;
  verifySamples: number;
}

/** The CLI's defaults (`slitpath coons --help`), which are the core's `CoonsOptions::default()`. */
export const DEFAULT_COONS_OPTIONS: Readonly<CoonsFormOptions> = Object.freeze({
  radiusMm: 3,
  scallopMm: 0.02,
  axes: 5,
  leadDeg: 15,
  tiltDeg: 0,
  post: "ac",
  smooth: true,
  feedMmMin: 1000,
  spindleRpm: 12000,
  verifySamples: 100000,
});

type Key = keyof CoonsFormOptions;

export const COONS_PARAM: Record<Key, string> = {
  radiusMm: "coons-radius",
  scallopMm: "coons-scallop",
  axes: "coons-axes",
  leadDeg: "coons-lead",
  tiltDeg: "coons-tilt",
  post: "coons-post",
  smooth: "coons-smooth",
  feedMmMin: "coons-feed",
  spindleRpm: "coons-spindle",
  verifySamples: "coons-samples",
};

/** One option's value from its text; undefined when it does not parse. */
export function parseCoons<K extends Key>(key: K, text: string): CoonsFormOptions[K] | undefined {
  const t = text.trim();
  let value: unknown;
  if (key === "axes") value = t === "3" ? 3 : t === "5" ? 5 : undefined;
  else if (key === "post") value = ["ac", "cl", "linuxcnc", "grbl"].includes(t) ? t : undefined;
  else if (key === "smooth") value = t === "true" ? true : t === "false" ? false : undefined;
  else if (key === "verifySamples") value = /^\d+$/.test(t) ? Number(t) : undefined;
  else value = t !== "" && Number.isFinite(Number(t)) ? Number(t) : undefined;
  return value as CoonsFormOptions[K] | undefined;
}

const keys = () => Object.keys(DEFAULT_COONS_OPTIONS) as Key[];

/** The Coons options of a URL query (absent or invalid parameters keep `base`). */
export function coonsFromQuery(search: string, base: CoonsFormOptions): CoonsFormOptions {
  const params = new URLSearchParams(search);
  const out: Record<string, unknown> = { ...base };
  for (const key of keys()) {
    const text = params.get(COONS_PARAM[key]);
    const value = text === null ? undefined : parseCoons(key, text);
    if (value !== undefined) out[key] = value;
  }
  return out as unknown as CoonsFormOptions;
}

/** Query parameters of the options that differ from the defaults. */
export function coonsQuery(options: CoonsFormOptions): [string, string][] {
  return keys()
    .filter((key) => options[key] !== DEFAULT_COONS_OPTIONS[key])
    .map((key) => [COONS_PARAM[key], String(options[key])]);
}

/** The core's options (every field: the core checks them). */
export const coonsOptions = (o: CoonsFormOptions): CoonsOptions => ({ ...o });

/** The `slitpath coons` arguments that plan the faces `faces` with `o`. */
export function coonsCliArguments(faces: number[], o: CoonsFormOptions): string[] {
  const args = ["--faces", faces.join(","), "--radius", String(o.radiusMm), "--scallop", String(o.scallopMm), "--axes", String(o.axes)];
  if (o.axes === 5) args.push("--lead", String(o.leadDeg), "--tilt", String(o.tiltDeg));
  args.push("--post", o.post);
  if (!o.smooth) args.push("--no-smooth");
  args.push("--feed", String(o.feedMmMin), "--spindle", String(o.spindleRpm), "--verify-samples", String(o.verifySamples));
  return args;
}
