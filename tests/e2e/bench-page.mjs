// The page benchmark (`npm run bench:page`, also part of `npm run bench`): the built page (www/dist)
// in Debian's headless Chromium, as a user meets it. For each generated part: open the page (the
// sample plans first), choose the STL in the file input, wait for "planned", and print the wall
// time from the choice to "planned", the planner's own time (its report), the sum and the longest
// of the main thread's long tasks meanwhile, and the planner's peak wasm memory. Figures only:
// nothing is asserted (tests/e2e/large-part.test.mjs holds the test thresholds).
//
// SLITPATH_BENCH_PAGE=40k runs only the cases whose name contains it.
import { join } from "node:path";
import { cli, launch, output, pageTimeline, plannerFigures, recordTimeline, root, serve } from "./harness.mjs";

const CASES = [
  // name, CLI fixture, scallop h (mm); R = 3 mm (the page's default)
  { name: "10k gen:1", fixture: "gen:1:10000", scallop: 0.01 },
  { name: "40k panel", fixture: "panel:0.75", scallop: 0.01 },
  { name: "300k panel", fixture: "panel:0.275", scallop: 0.02 },
];
const TIMEOUT_MS = Number(process.env.SLITPATH_BENCH_PAGE_TIMEOUT ?? 300_000);
const only = process.env.SLITPATH_BENCH_PAGE ?? "";

const server = await serve(join(root, "www/dist"));
const rows = [];
try {
  for (const c of CASES.filter((c) => c.name.includes(only))) {
    const file = join(output, `bench-${c.fixture.replace(/[:.]/g, "_")}.stl`);
    cli("fixture", c.fixture, "-o", file);
    const faces = Number(cli("info", file).match(/faces (\d+)/)[1]);
    const browser = await launch();
    try {
      const page = await browser.context.newPage();
      await recordTimeline(page);
      await page.goto(`${server.url}?scallop=${c.scallop}`);
      await page.waitForFunction(() => document.getElementById("status")?.textContent === "planned", undefined, { timeout: 120_000 });
      await page.getByTestId("stl-input").setInputFiles(file);
      let failed = "";
      await page
        .waitForFunction(() => window.__timeline.planned !== null || /^error: /.test(document.getElementById("status")?.textContent ?? ""), undefined, {
          timeout: TIMEOUT_MS,
          polling: 100,
        })
        .catch(() => (failed = `not planned after ${TIMEOUT_MS / 1000} s`));
      const status = await page.getByTestId("status").textContent();
      if (!failed && status !== "planned") failed = status;
      await page.waitForTimeout(1000); // the frames drawn after "planned" count too
      const timeline = await pageTimeline(page);
      const figures = failed ? { plannerMs: null, wasmMiB: null } : await plannerFigures(page);
      rows.push({ ...c, faces, ...timeline, ...figures, failed });
    } finally {
      await browser.close();
    }
  }
} finally {
  server.close();
}

const f = (v, digits = 0) => (v === null || v === undefined ? "—" : v.toFixed(digits));
console.log("page benchmark, headless Chromium (R 3 mm; times in s, memory MiB)");
console.log("case          faces      h   choice→planned  planner  long tasks (n, sum, max)   wasm MiB");
for (const r of rows) {
  console.log(
    `${r.name.padEnd(12)} ${String(r.faces).padStart(6)}  ${r.scallop.toFixed(3)}  ${f(r.chosenToPlannedMs && r.chosenToPlannedMs / 1000, 2).padStart(14)}  ${f(
      r.plannerMs && r.plannerMs / 1000,
      2,
    ).padStart(7)}  ${String(r.longTasks).padStart(5)} ${f(r.longTaskSumMs / 1000, 2).padStart(7)} ${f(r.longTaskMaxMs / 1000, 3).padStart(8)}   ${f(r.wasmMiB).padStart(8)}${
      r.failed ? `  (${r.failed})` : ""
    }`,
  );
}
