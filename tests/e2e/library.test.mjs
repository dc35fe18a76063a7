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
