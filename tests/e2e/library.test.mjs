// The npm package for portals (www/dist-lib, `npm run build:lib`) used without the page: a bare
// HTML file imports slitpath.js, loads an STL, plans it with progress, and reads the results.
import assert from "node:assert/strict";
import { cpSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from "node:fs";
import { tmpdir } from "node:os";
import { join } from "node:path";
import { after, before, describe, it } from "node:test";
import { launch, root, serve } from "./harness.mjs";

describe("the npm package (worker-based API)", { concurrency: false }, () => {
  let dir, server, browser, page;

  before(async () => {
    dir = mkdtempSync(join(tmpdir(), "slitpath-lib-"));
    cpSync(join(root, "www/dist-lib"), join(dir, "lib"), { recursive: true });
    cpSync(join(root, "www/public/samples/freeform_4_holes.stl"), join(dir, "part.stl"));
    cpSync(join(root, "www/public/samples/blade.stl"), join(dir, "blade.stl"));
    cpSync(join(root, "www/public/samples/blade_band.step"), join(dir, "band.step"));
    writeFileSync(join(dir, "index.html"), '<!doctype html><meta charset="utf-8"><title>portal</title><p>portal</p>');
    server = await serve(dir);
    browser = await launch();
    page = await browser.context.newPage();
    await page.goto(server.url);
  });

  after(async () => {
    await browser?.close();
    server?.close();
    if (dir) rmSync(dir, { recursive: true, force: true });
  });

  it("declares its API in TypeScript", () => {
    const types = readFileSync(join(root, "www/dist-lib/types/lib/index.d.ts"), "utf8");
    assert.match(types, /SlitpathPlanner/);
    assert.match(readFileSync(join(root, "www/dist-lib/types/lib/client.d.ts"), "utf8"), /plan\(options\?: PlanOptions, callbacks\?: PlanCallbacks\): Promise<PlanResult>/);
    assert.match(readFileSync(join(root, "www/dist-lib/types/lib/client.d.ts"), "utf8"), /planFlank\(options\?: FlankOptions, callbacks\?: PlanCallbacks\): Promise<FlankResult>/);
    assert.match(types, /FlankReport/);
  });

  it("loads STEP bytes (issue 36): the faces come with the part, faces that are not one surface are refused with them, selectFaces and planCoons plan", async () => {
    const r = await page.evaluate(async () => {
      const { SlitpathPlanner, StepSelectionError } = await import("./lib/slitpath.js");
      const planner = new SlitpathPlanner();
      const bytes = await (await fetch("band.step")).arrayBuffer();
      const part = await planner.load(bytes, { name: "band.step" });
      const ids = part.step.faces.map((f) => f.id);
      let refused = null;
      try {
        await planner.load(bytes, { name: "band.step", stepOptions: { faces: [ids[0], ids[2]] } });
      } catch (error) {
        refused = { isStepError: error instanceof StepSelectionError, faces: error.step?.faces.length, message: error.message };
      }
      const two = await planner.selectFaces([ids[0], ids[1]]);
      const band = await planner.planCoons(ids, { verifySamples: 5000 });
      let notBand = "";
      try {
        await planner.planCoons(ids.slice(0, 3), { verifySamples: 0 });
      } catch (error) {
        notBand = error.message;
      }
      planner.dispose();
      return {
        faces: ids.length,
        faceOfTriangle: part.step.drawing.faceOfTriangle.length,
        partFaces: part.stepFaces.length,
        refused,
        selected: two.stepFaces,
        twoIds: [ids[0], ids[1]],
        revolutions: band.report.revolutions,
        contacts: band.pathContacts instanceof Float64Array ? band.pathContacts.length : -1,
        gcode: band.gcode.length,
        notBand,
      };
    });
    assert.equal(r.faces, 8);
    assert.ok(r.faceOfTriangle > 10000, JSON.stringify(r));
    assert.equal(r.partFaces, 8);
    // Two faces that share no edge are not one surface: refused, with the file's faces.
    assert.deepEqual([r.refused?.isStepError, r.refused?.faces], [true, 8], JSON.stringify(r.refused));
    assert.deepEqual(r.selected, r.twoIds);
    assert.equal(r.revolutions, 71);
    assert.ok(r.contacts > 3000 && r.gcode > 10000, JSON.stringify(r));
    assert.match(r.notBand, /band/);
  });

  it("plans flank strips (seed 002): tips, axes and strips as typed arrays, the verifier's figures, the program; a bad tool is refused", async () => {
    const result = await page.evaluate(async () => {
      const { SlitpathPlanner, DEFAULT_FLANK_OPTIONS, flankOptions } = await import("./lib/slitpath.js");
      const planner = new SlitpathPlanner();
      await planner.load(await (await fetch("blade.stl")).arrayBuffer(), { name: "blade.stl" });
      const stages = new Set();
      const options = flankOptions({ ...DEFAULT_FLANK_OPTIONS, tipRadiusMm: 2.87, topRadiusMm: 9.56, fluteLengthMm: 21.8, direction: [0, -1, 0], strips: 4 });
      const plan = await planner.planFlank({ ...options, verifySamples: 4000 }, { onProgress: (stage) => stages.add(stage) });
      let bad = "";
      try {
        await planner.planFlank({ ...options, fluteLengthMm: 0 });
      } catch (error) {
        bad = error.message;
      }
      planner.dispose();
      return {
        stages: [...stages],
        moves: plan.tips instanceof Float64Array ? plan.tips.length / 3 : -1,
        axes: plan.axes.length / 3,
        strips: [...plan.stripMoves],
        deviations: plan.vertexDeviation.length,
        vertices: plan.positions.length / 3,
        strategy: plan.report.strategy,
        reportStrips: plan.report.guide.strips,
        gouge: plan.report.verify?.max_gouge_mm,
        gcode: plan.gcode.slice(0, 400),
        bad,
      };
    });
    assert.ok(result.moves > 100 && result.axes === result.moves, JSON.stringify(result));
    assert.equal(result.strips.length, 2 * 4, "[first, end) per strip");
    assert.equal(result.reportStrips, 4);
    assert.equal(result.deviations, result.vertices, "one deviation per vertex");
    assert.ok(Number.isFinite(result.gouge), `a finite max gouge: ${result.gouge}`);
    assert.ok(result.stages.includes("optimise"), `progress was reported: ${result.stages}`);
    assert.match(result.gcode, /post ac/);
    assert.match(result.bad, /flute_length_mm = 0/);
  });

  it("loads and plans with progress, results as typed arrays; a cancel rejects and the planner recovers", async () => {
    const result = await page.evaluate(async () => {
      const { SlitpathPlanner, CancelledError } = await import("./lib/slitpath.js");
      const planner = new SlitpathPlanner();
      const stl = await (await fetch("part.stl")).arrayBuffer();
      const part = await planner.load(stl, { name: "part.stl" });
      const stages = new Set();
      const plan = await planner.plan({ scallopMm: 0.05 }, { onProgress: (stage) => stages.add(stage) });
      // Cancel a plan straight away: it rejects with CancelledError; the part is reloaded.
      const cancelled = planner.plan({ scallopMm: 0.05 }).then(() => "finished", (e) => (e instanceof CancelledError ? "cancelled" : String(e)));
      planner.cancel();
      const again = await planner.plan({ scallopMm: 0.05 });
      let bad = "";
      try {
        await planner.plan({ scallopMm: 0.05, noSuchOption: 1 });
      } catch (error) {
        bad = error.message;
      }
      planner.dispose();
      return {
        faces: part.triangles.length / 3,
        stages: [...stages],
        rings: plan.ringRadii.length,
        contacts: plan.pathContacts instanceof Float64Array ? plan.pathContacts.length : -1,
        scallop: plan.vertexScallop.length,
        vertices: part.positions.length / 3,
        gcode: plan.gcode.slice(0, 2000),
        cancelled: await cancelled,
        same: again.gcode === plan.gcode,
        bad,
      };
    });
    assert.ok(result.faces > 1000, JSON.stringify(result));
    assert.ok(result.rings > 0 && result.contacts > 0, JSON.stringify(result));
    assert.equal(result.scallop, result.vertices, "one scallop value per vertex");
    assert.ok(result.stages.length > 0, "progress was reported");
    assert.match(result.gcode, /G21/);
    assert.equal(result.cancelled, "cancelled");
    assert.ok(result.same, "the same options plan the same G-code after a cancel");
    assert.match(result.bad, /noSuchOption/);
  });
});
