// The planner's stages in wasm (V8, the engine of Chromium) in CPU time rather than wall time:
//   node scripts/wasm-stages.mjs PART.stl [plans] [radius mm] [scallop mm]
// Plans the part with the wasm package in www/pkg (wasm-pack build --target web --out-dir www/pkg
// --release) `plans` times (default 3) and prints each plan's stage timings (ms). The core reads
// its clock through Date.now; here that returns the process's CPU time, so a machine shared with
// other work does not inflate the figures as it inflates the page benchmark's wall times. The
// first plan includes V8's compilation of the module (its background threads count): compare the
// later ones. After each plan it prints the wasm memory, which never shrinks: the peak so far.
// Figures only; see docs/benchmarks.md for the native counterpart.
import { readFileSync } from "node:fs";
import { dirname, join } from "node:path";
import { fileURLToPath } from "node:url";

const [file, plans = "3", radius = "3", scallop = "0.01"] = process.argv.slice(2);
if (!file) {
  console.error("usage: node scripts/wasm-stages.mjs PART.stl [plans] [radius mm] [scallop mm]");
  process.exit(2);
}
const pkg = join(dirname(fileURLToPath(import.meta.url)), "../www/pkg");
const core = await import(join(pkg, "slitpath.js"));
const wasm = core.initSync({ module: readFileSync(join(pkg, "slitpath_bg.wasm")) });
Date.now = () => {
  const { user, system } = process.cpuUsage();
  return (user + system) / 1000;
};
const stl = readFileSync(file);
for (let k = 0; k < Number(plans); k++) {
  const planner = new core.Planner(stl, undefined, undefined);
  planner.prepare(undefined);
  const report = planner.plan({ radiusMm: Number(radius), scallopMm: Number(scallop) }, undefined);
  const stages = Object.entries(report.timings_ms).map(([stage, ms]) => `${stage} ${Math.round(ms)}`);
  const memory = (wasm.memory.buffer.byteLength / 2 ** 20).toFixed(0);
  console.log(`plan ${k + 1}: ${stages.join(", ")}; wasm memory ${memory} MiB`);
  planner.free();
}
