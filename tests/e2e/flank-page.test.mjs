// End-to-end tests of the page's flank strategy (seed 002, issue 35) in Debian's headless
// Chromium: the bundled blade sample planned for flank milling, its 3D view read back, its
// metrics, its program against the CLI's `slitpath flank` byte for byte, a tool the core refuses,
// and the way back to the spiral. The tests share one page and run in order.
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import { join } from "node:path";
import { after, before, describe, it } from "node:test";
import { cli, launch, output, replan as replanStatus, root, screenshotPath, serve, settled as settledStatus, viewStats } from "./harness.mjs";

const PLAN_TIMEOUT = 180_000;
const BLADE = join(root, "www/public/samples/blade.stl");

describe("the flank strategy on the page", { concurrency: false }, () => {
  let server, browser, page;
  const consoleErrors = [];

  const settled = () => settledStatus(page, PLAN_TIMEOUT);
  const replan = (action) => replanStatus(page, action, PLAN_TIMEOUT);
  const shot = (name) => page.screenshot({ path: screenshotPath(name), fullPage: true });
  const metric = async (id) => (await page.getByTestId(id).textContent()) ?? "";

  before(async () => {
    server = await serve(join(root, "www/dist"));
    browser = await launch();
    page = await browser.context.newPage();
    page.on("console", (message) => message.type() === "error" && consoleErrors.push(message.text()));
    await page.goto(server.url);
    assert.equal(await settled(), "planned", "the spiral sample plans on opening");
  });

  after(async () => {
    await browser?.close();
    server?.close();
  });

  it("plans the blade sample with the flank strategy", async () => {
    const state = await replan(() => page.getByTestId("load-blade").click());
    assert.equal(state, "planned", await page.getByTestId("status-detail").textContent());
    assert.equal(await page.getByTestId("opt-strategy").inputValue(), "flank");
    assert.match(await page.getByTestId("part-name").textContent(), /^blade\.stl/);
    const gouge = await metric("metric-flank-gouge");
    const value = Number(gouge.match(/^([\d.e+-]+) mm/)?.[1]);
    assert.ok(Number.isFinite(value) && value >= 0, `a finite max gouge: ${gouge}`);
    for (const id of ["metric-flank-undercut", "metric-flank-rms", "metric-flank-coverage", "metric-flank-kinks", "metric-flank-rigidity"]) {
      assert.match(await metric(id), /\d/, `${id} shows a figure`);
    }
    assert.match(await metric("metric-flank-strips"), /^11 /);
    // The preset's tool body (Ø19 shank, 70 mm gauge, Ø40 holder) clears the blade: nothing is
    // flagged (issue 35: a holder at the flute top flagged 3374 of 3376 moves).
    assert.equal(await metric("metric-flank-body"), "9.5 mm / 70 mm / 20 mm");
    assert.equal(await metric("metric-flank-collisions"), "0");
    assert.match(
      await page.getByTestId("cli-command").textContent(),
      /^slitpath flank PART\.stl --tip-radius 2\.87 --top-radius 9\.56 --flute-length 21\.8 --shank-radius 9\.5 --gauge-length 70 --holder-radius 20 /,
    );
    assert.match(page.url(), /[?&]strategy=flank\b/, "the strategy is in the URL");
    assert.equal(await page.getByTestId("flank-2d-note").isVisible(), true, "the 2D view says the slit map does not apply");
    await shot("flank-1-blade.png");
  });

  it("draws the blade by deviation with the strips' tool axes (pixels read back)", async () => {
    await page.waitForTimeout(300); // one animation frame after the plan
    const s = await viewStats(page, "view-3d");
    assert.ok(s.width > 100 && s.height > 100, JSON.stringify(s));
    assert.ok(s.nonBackground > 0.05, `the 3D view is not blank: ${JSON.stringify(s)}`);
    assert.ok(s.colours > 30, `more than a flat fill: ${JSON.stringify(s)}`);
  });

  it("downloads the same program as `slitpath flank`, byte for byte", async () => {
    const [download] = await Promise.all([page.waitForEvent("download"), page.getByTestId("download-gcode").click()]);
    assert.equal(download.suggestedFilename(), "blade.ngc");
    const file = join(output, "page-blade.ngc");
    await download.saveAs(file);
    // The very arguments the page shows as its CLI equivalent.
    const shown = (await page.getByTestId("cli-command").textContent()).split(" ").slice(3);
    const cliFile = join(output, "cli-blade.ngc");
    cli("flank", BLADE, ...shown, "-o", cliFile);
    const [fromPage, fromCli] = [readFileSync(file), readFileSync(cliFile)];
    assert.ok(fromCli.length > 1000, "the CLI wrote a program");
    assert.match(fromCli.toString("utf8"), /A-?\d/, "an A/C program");
    assert.ok(fromPage.equals(fromCli), `page ${fromPage.length} bytes, CLI ${fromCli.length} bytes: they differ`);
  });

  it("downloads the CL data of the same plan, as `slitpath flank --post cl` writes it", async () => {
    const [download] = await Promise.all([page.waitForEvent("download", { timeout: PLAN_TIMEOUT }), page.getByTestId("download-cl").click()]);
    assert.equal(download.suggestedFilename(), "blade.cls");
    const file = join(output, "page-blade.cls");
    await download.saveAs(file);
    const shown = (await page.getByTestId("cli-command").textContent()).split(" ").slice(3).map((a) => (a === "ac" ? "cl" : a));
    const cliFile = join(output, "cli-blade.cls");
    cli("flank", BLADE, ...shown, "-o", cliFile);
    assert.ok(readFileSync(file).equals(readFileSync(cliFile)), "the page's CL data differ from the CLI's");
  });

  it("refuses an impossible tool with a clear error and plans again", async () => {
    const gouge = await metric("metric-flank-gouge");
    const negative = await replan(() => page.getByTestId("opt-flank-top").fill("-1"));
    assert.match(negative, /^error: .*top_radius_mm = -1/, "the message names the option");
    assert.equal(await metric("metric-flank-gouge"), gouge, "the last good plan is still shown");
    await page.getByTestId("opt-flank-top").fill("9.56");
    const zero = await replan(() => page.getByTestId("opt-flank-flute").fill("0"));
    assert.match(zero, /^error: .*flute_length_mm = 0/);
    await shot("flank-2-bad-tool.png");
    const state = await replan(() => page.getByTestId("opt-flank-flute").fill("21.8"));
    assert.equal(state, "planned");
    assert.equal(await metric("metric-flank-gouge"), gouge, "the same options plan the same figures");
  });

  it("flags a holder too near the tip, and refuses a gauge length shorter than the flutes", async () => {
    const short = await replan(() => page.getByTestId("opt-flank-gauge").fill("30"));
    assert.equal(short, "planned");
    assert.match(await metric("metric-flank-collisions"), /^[\d,]+ of [\d,]+ moves; worst: holder on (cut|approach) move \d+, -[\d.]+ mm at \(/);
    const refused = await replan(() => page.getByTestId("opt-flank-gauge").fill("10"));
    assert.match(refused, /^error: .*gauge_length_mm = 10/);
    assert.equal(await replan(() => page.getByTestId("opt-flank-gauge").fill("70")), "planned");
    assert.equal(await metric("metric-flank-collisions"), "0");
  });

  it("goes back to the spiral strategy", async () => {
    // The blade is a wall along the tool axis: a ball-end spiral cannot reach it (an error, shown).
    assert.match(await replan(() => page.getByTestId("opt-strategy").selectOption("spiral")), /^(planned|error: )/);
    const state = await replan(() => page.getByTestId("load-sample").click());
    assert.equal(state, "planned");
    assert.ok(Number((await metric("metric-rings")).replace(/,/g, "")) > 0, "a spiral plan with rings");
    assert.equal(await page.getByTestId("flank-2d-note").isVisible(), false);
    const s = await viewStats(page, "view-2d");
    assert.ok(s.nonBackground > 0.05, `the 2D view draws again: ${JSON.stringify(s)}`);
  });

  it("logs no error", () => {
    assert.deepEqual(consoleErrors.filter((e) => !/Failed to load resource/.test(e)), []);
  });
});
