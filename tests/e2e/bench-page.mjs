// The page benchmark (`npm run bench:page`, also part of `npm run bench`): the built page (www/dist)
// in Debian's headless Chromium, as a user meets it. For each generated part: open the page (the
// sample plans first), choose the STL in the file input, wait for "planned" (the plan drawn), and
// print the wall time from the choice to "planning" (the part read, checked, flattened, factorised
// and shown) and to "planned", the planner's own time (its report), the sum and the
// longest of the main thread's long tasks meanwhile, and the planner's peak wasm memory. Then, in
// the same run, the native CLI on the same part and options, one thread (as in the browser), for
// wasm/native per stage; the frames the views draw per second while scrubbing and while hovering
// (software WebGL here: a GPU draws faster); and for the 40k part, ten re-plans: the page's heap (after a GC) and the
// planner's memory after each. Figures only: nothing is asserted (tests/e2e/large-part.test.mjs
// holds the test thresholds).
//
// SLITPATH_BENCH_PAGE=40k runs only the cases whose name contains it; SLITPATH_BENCH_PAGE_SPREAD=need
// plans with that ring spread (page and CLI).
import { execFileSync } from "node:child_process";
import { readFileSync } from "node:fs";
import { join } from "node:path";
import { cli, launch, output, pageTimeline, plannerFigures, recordTimeline, root, serve } from "./harness.mjs";

const CASES = [
  // name, CLI fixture, scallop h (mm); R = 3 mm (the page's default)
  { name: "10k gen:1", fixture: "gen:1:10000", scallop: 0.01 },
  { name: "40k panel", fixture: "panel:0.75", scallop: 0.01, replans: 10 },
  { name: "300k panel", fixture: "panel:0.275", scallop: 0.02 },
];
const STAGES = ["flatten", "slitmap", "origin", "optimise", "spacing", "spiral", "toolpath", "verify", "post", "total"];
const TIMEOUT_MS = Number(process.env.SLITPATH_BENCH_PAGE_TIMEOUT ?? 300_000);
const only = process.env.SLITPATH_BENCH_PAGE ?? "";
const spread = process.env.SLITPATH_BENCH_PAGE_SPREAD ?? "none";

const status = (page) => page.getByTestId("status").textContent();
const waitPlanned = (page, timeout) =>
  page.waitForFunction(() => /^(planned|error: )/.test(document.getElementById("status")?.textContent ?? ""), undefined, { timeout, polling: 100 });

/** The native CLI's stage timings (ms) on the same part and options, on one thread. */
function native(file, scallop) {
  const report = join(output, "bench-native-report.json");
  const args = ["plan", file, "--radius", "3", "--scallop", String(scallop), "--spread", spread];
  cli(...args, "-o", join(output, "bench-native.ngc"), "--report", report);
  return JSON.parse(readFileSync(report, "utf8")).timings_ms;
}

/**
 * Frames the views draw per second while the scrub bar moves on every animation frame of the page
 * for 2 s (each frame a new tool position), and while the pointer sweeps the 2D view. The sweep
 * is as fast as the driver delivers moves (each \`mouse.move\` is a round trip), so the moves per
 * second are printed beside the frames: a view that keeps up draws one frame per move.
 */
async function interaction(page) {
  const frames = () => page.evaluate(() => Number(document.querySelector("[data-testid=view-3d]").dataset.frame));
  let before = await frames();
  await page.evaluate(async () => {
    const scrub = document.querySelector("[data-testid=scrub]");
    const points = Number(scrub.max) + 1;
    const end = performance.now() + 2000;
    for (let i = 0; performance.now() < end; i++) {
      scrub.value = String(Math.floor(((i * 997) % 1000) * (points / 1000)));
      scrub.dispatchEvent(new Event("input", { bubbles: true }));
      await new Promise(requestAnimationFrame);
    }
  });
  await page.waitForTimeout(200);
  const scrubFps = ((await frames()) - before) / 2;
  await page.getByTestId("view-2d").scrollIntoViewIfNeeded();
  const box = await page.getByTestId("view-2d").boundingBox();
  before = await frames();
  const start = Date.now();
  let moves = 0;
  for (let i = 0; Date.now() - start < 2000; i++, moves++) {
    const t = (i % 200) / 200;
    await page.mouse.move(box.x + box.width * (0.1 + 0.8 * t), box.y + box.height * (0.3 + 0.4 * Math.sin(7 * t) ** 2));
  }
  await page.waitForTimeout(200);
  const seconds = (Date.now() - start - 200) / 1000;
  const hoverFps = ((await frames()) - before) / seconds;
  return { scrubFps, hoverFps, hoverMoves: moves / seconds };
}

/** Ten re-plans (h alternating by 5 %): the page's JS heap after a GC, and the planner's memory, after each. */
async function replans(page, scallop, count) {
  const heap = [];
  const wasm = [];
  for (let i = 1; i <= count; i++) {
    await page.evaluate(() => (document.getElementById("status").textContent = "…"));
    await page.getByTestId("opt-scallop").fill(String(i % 2 === 1 ? scallop * 1.05 : scallop));
    await waitPlanned(page, TIMEOUT_MS);
    heap.push(await page.evaluate(() => (window.gc?.(), performance.memory.usedJSHeapSize / 2 ** 20)));
    wasm.push((await plannerFigures(page)).wasmMiB);
  }
  return { heap, wasm };
}

// The CLI runs on one thread, like the browser's planner.
process.env.RAYON_NUM_THREADS = "1";
execFileSync("cargo", ["build", "--release", "--quiet", "--bin", "slitpath"], { cwd: root, stdio: "inherit" });
const server = await serve(join(root, "www/dist"));
const rows = [];
try {
  for (const c of CASES.filter((c) => c.name.includes(only))) {
    const file = join(output, `bench-${c.fixture.replace(/[:.]/g, "_")}.stl`);
    cli("fixture", c.fixture, "-o", file);
    const faces = Number(cli("info", file).match(/faces (\d+)/)[1]);
    const browser = await launch(["--js-flags=--expose-gc", "--enable-precise-memory-info"]);
    try {
      const page = await browser.context.newPage();
      await recordTimeline(page);
      await page.goto(`${server.url}?scallop=${c.scallop}&spread=${spread}`);
      await waitPlanned(page, 120_000);
      // A worker's first plan compiles most of the core (docs/benchmarks.md, stop 51): the sample
      // is what a user's first visit plans before their part, and without it the figures are a
      // cold start's.
      const sample = await status(page);
      if (sample !== "planned") console.warn(`warning: the sample did not plan (${sample}): ${c.name}'s figures include compiling the core (scripts/bench-page.sh writes the sample)`);
      await page.getByTestId("stl-input").setInputFiles(file);
      let failed = "";
      await page
        .waitForFunction(() => window.__timeline.planned !== null || /^error: /.test(document.getElementById("status")?.textContent ?? ""), undefined, {
          timeout: TIMEOUT_MS,
          polling: 100,
        })
        .catch(() => (failed = `not planned after ${TIMEOUT_MS / 1000} s`));
      if (!failed && (await status(page)) !== "planned") failed = await status(page);
      await page.waitForTimeout(1000); // the frames drawn after "planned" count too
      const timeline = await pageTimeline(page);
      const figures = failed ? { plannerMs: null, stages: {}, wasmMiB: null } : await plannerFigures(page);
      const row = { ...c, faces, ...timeline, ...figures, failed, native: native(file, c.scallop) };
      if (!failed) Object.assign(row, await interaction(page));
      if (c.replans && !failed) row.replans = await replans(page, c.scallop, c.replans);
      rows.push(row);
    } finally {
      await browser.close();
    }
  }
} finally {
  server.close();
}

const f = (v, digits = 0) => (v === null || v === undefined || Number.isNaN(v) ? "—" : v.toFixed(digits));
console.log("page benchmark, headless Chromium (R 3 mm; times in s, memory MiB)");
console.log("case          faces      h  choice→loaded  →planned  planner  long tasks (n, sum, max)   wasm MiB   frames/s scrub, hover (pointer moves/s)");
for (const r of rows) {
  const s = (ms) => (ms === null || ms === undefined ? null : ms / 1000);
  console.log(
    `${r.name.padEnd(12)} ${String(r.faces).padStart(6)}  ${r.scallop.toFixed(3)}  ${f(s(r.chosenToLoadedMs), 2).padStart(13)}  ${f(s(r.chosenToPlannedMs), 2).padStart(8)}  ${f(s(r.plannerMs), 2).padStart(7)}  ${String(
      r.longTasks,
    ).padStart(5)} ${f(r.longTaskSumMs / 1000, 2).padStart(7)} ${f(r.longTaskMaxMs / 1000, 3).padStart(8)}   ${f(r.wasmMiB).padStart(8)}   ${f(r.scrubFps).padStart(8)} ${f(r.hoverFps).padStart(6)} (${f(r.hoverMoves)})${r.failed ? `  (${r.failed})` : ""}`,
  );
}
console.log("\nplanner stages, wasm in the page / native CLI on one thread, same part and options, this run (ms)");
console.log(`case        ${STAGES.map((s) => s.padStart(17)).join("")}`);
for (const r of rows) {
  const cells = STAGES.map((stage) => {
    const [w, n] = [r.stages[stage], r.native[stage]];
    return `${f(w)}/${f(n)} ${w && n ? (w / n).toFixed(2) : "—"}`.padStart(17);
  });
  console.log(`${r.name.padEnd(12)}${cells.join("")}`);
}
for (const r of rows.filter((r) => r.replans)) {
  console.log(`\n${r.name}: ten re-plans, after each: page heap (MiB, after a GC) ${r.replans.heap.map((v) => f(v, 1)).join(" ")}`);
  console.log(`${" ".repeat(r.name.length)}  planner wasm memory (MiB) ${r.replans.wasm.map((v) => f(v)).join(" ")}`);
}
