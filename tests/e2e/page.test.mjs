// End-to-end tests of the built page (www/dist) in Debian's headless Chromium, as a machinist
// would use it. Run after `vite build www`: node --test tests/e2e/
// The tests share one page and run in order (each state builds on the previous one).
import assert from "node:assert/strict";
import { readFileSync, writeFileSync } from "node:fs";
import { join } from "node:path";
import { after, before, describe, it } from "node:test";
import { cli, launch, output, replan as replanStatus, root, screenshotPath, serve, settled as settledStatus, viewStats } from "./harness.mjs";

const PLAN_TIMEOUT = 60_000;
const SAMPLE = join(root, "www/public/samples/freeform_4_holes.stl");

describe("the planner page", { concurrency: false }, () => {
  let server, browser, page;
  const foreign = [];
  const consoleErrors = [];

  const settled = () => settledStatus(page, PLAN_TIMEOUT);
  const rings = async () => Number((await page.getByTestId("metric-rings").textContent()).replace(/,/g, ""));
  const replan = (action) => replanStatus(page, action, PLAN_TIMEOUT);
  const shot = (name) => page.screenshot({ path: screenshotPath(name), fullPage: true });

  before(async () => {
    server = await serve(join(root, "www/dist"));
    browser = await launch();
    page = await browser.context.newPage();
    const origin = new URL(server.url).origin;
    page.on("request", (request) => {
      const url = new URL(request.url());
      if (!["data:", "blob:"].includes(url.protocol) && url.origin !== origin) foreign.push(request.url());
    });
    page.on("console", (message) => message.type() === "error" && consoleErrors.push(message.text()));
    await page.goto(server.url);
  });

  after(async () => {
    await browser?.close();
    server?.close();
  });

  it("plans the bundled sample on opening", async () => {
    assert.equal(await settled(), "planned");
    assert.ok((await rings()) > 0, "the metrics show rings");
    assert.match(await page.getByTestId("metrics").innerText(), /Max scallop[\s\S]*h = 0\.02 mm/);
    assert.match((await page.getByTestId("version").textContent()) ?? "", /^core \d+\.\d+\.\d+/);
    assert.equal(await page.getByTestId("download-gcode").isEnabled(), true);
    await shot("1-sample-planned.png");
  });

  it("renders the 3D and the 2D view (pixels read back)", async () => {
    await page.waitForTimeout(300); // one animation frame after the plan
    for (const id of ["view-3d", "view-2d"]) {
      const s = await viewStats(page, id);
      assert.ok(s.width > 100 && s.height > 100, `${id} has a size: ${JSON.stringify(s)}`);
      assert.ok(s.nonBackground > 0.05, `${id} is not blank: ${JSON.stringify(s)}`);
      assert.ok(s.colours > 30, `${id} shows more than a flat fill: ${JSON.stringify(s)}`);
    }
  });

  it("downloads the same G-code as the CLI, byte for byte", async () => {
    const [download] = await Promise.all([page.waitForEvent("download"), page.getByTestId("download-gcode").click()]);
    assert.equal(download.suggestedFilename(), "freeform_4_holes.ngc");
    const file = join(output, "page-freeform_4_holes.ngc");
    await download.saveAs(file);
    const cliFile = join(output, "cli-freeform_4_holes.ngc");
    cli("plan", SAMPLE, "--radius", "3", "--scallop", "0.02", "-o", cliFile);
    const [fromPage, fromCli] = [readFileSync(file), readFileSync(cliFile)];
    assert.ok(fromCli.length > 1000, "the CLI wrote a program");
    assert.ok(fromPage.equals(fromCli), `page ${fromPage.length} bytes, CLI ${fromCli.length} bytes: they differ`);
  });

  it("re-plans when the scallop height changes, with fewer rings for a larger h", async () => {
    const before = await rings();
    const state = await replan(() => page.getByTestId("opt-scallop").fill("0.08"));
    assert.equal(state, "planned");
    const after = await rings();
    assert.ok(after < before, `rings ${before} at h = 0.02 mm, ${after} at h = 0.08 mm`);
    assert.match(page.url(), /[?&]scallop=0\.08\b/, "the options are in the URL");
    await shot("2-scallop-0.08.png");
  });

  it("keeps the options across visits (localStorage)", async () => {
    await page.goto(server.url); // no query: the stored options

    assert.equal(await settled(), "planned");
    assert.equal(await page.getByTestId("opt-scallop").inputValue(), "0.08");
  });

  it("takes every option from a shared URL: the ring spread too", async () => {
    await page.goto(`${server.url}?spread=need`);
    assert.equal(await settled(), "planned");
    assert.equal(await page.getByTestId("opt-spread").inputValue(), "need");
    assert.equal(await page.getByTestId("opt-scallop").inputValue(), "0.08", "the stored options beneath");
    assert.match(await page.getByTestId("metric-spread").textContent(), /^((not )?kept: [\d,.]+ mm against [\d,.]+ mm|kept: [\d,.]+ mm \([\d.]+ h\); the unspread path was not needed)/);
    await page.goto(`${server.url}?spread=none`);
    assert.equal(await settled(), "planned");
    assert.equal(await page.getByTestId("metric-spread").count(), 0);
  });

  it("warns when the STL's facets alone leave more than h, and not otherwise (issue 34)", async () => {
    // A six-hole panel meshed at 3 mm: its concave creases and pits alone leave about 5.7 µm
    // for R 3, whatever the path.
    const file = join(output, "coarse_panel.stl");
    cli("fixture", "panel:3", "-o", file);
    assert.equal(await replan(() => page.getByTestId("stl-input").setInputFiles(file)), "planned");
    assert.equal(await page.getByTestId("plan-warning").count(), 0, "no warning at h = 0.08 mm");
    assert.equal(await replan(() => page.getByTestId("opt-scallop").fill("0.004")), "planned");
    const warning = await page.getByTestId("plan-warning").textContent();
    assert.match(warning, /facets alone leave .* --facets smooth/);
    assert.equal(await replan(() => page.getByTestId("opt-scallop").fill("0.08")), "planned");
    assert.equal(await page.getByTestId("plan-warning").count(), 0, "gone again at h = 0.08 mm");
  });

  it("plans an uploaded STL (a fixture written by the CLI)", async () => {
    const file = join(output, "plate_3_holes.stl");
    cli("fixture", "plate_3_holes", "-o", file);
    const state = await replan(() => page.getByTestId("stl-input").setInputFiles(file));
    assert.equal(state, "planned");
    assert.match(await page.getByTestId("part-name").textContent(), /^plate_3_holes\.stl/);
    assert.ok((await rings()) > 0);
    await shot("3-uploaded-plate.png");
  });

  it("shows a bad STL's error and keeps the last good plan", async () => {
    const ringsBefore = await rings();
    const state = await replan(() => page.getByTestId("stl-input").setInputFiles(join(root, "tests/fixtures/garbled_ascii.stl")));
    assert.match(state, /^error: .*line \d+/, "the message names the line");
    assert.equal(await rings(), ringsBefore, "the last good plan is still shown");
    assert.match(await page.getByTestId("part-name").textContent(), /^plate_3_holes\.stl/);
    await shot("4-bad-stl.png");
  });

  it("still works after the error: an impossible option is refused, a good one plans", async () => {
    const refused = await replan(() => page.getByTestId("opt-radius").fill("-1"));
    assert.match(refused, /^error: /);
    const state = await replan(() => page.getByTestId("opt-radius").fill("2"));
    assert.equal(state, "planned");
    await shot("5-recovered.png");
  });

  it("cancels a long plan and stays usable", async () => {
    await page.getByTestId("opt-samples").fill("3000000"); // a slow verification
    await page.getByTestId("cancel").waitFor({ state: "visible", timeout: 10_000 });
    await page.getByTestId("cancel").click();
    assert.equal(await settled(), "cancelled");
    const state = await replan(() => page.getByTestId("opt-samples").fill("100000"));
    assert.equal(state, "planned");
  });

  it("sets the pole by a click in the flattened domain and shows its energy", async () => {
    const box = await page.getByTestId("view-2d").boundingBox();
    const state = await replan(() => page.getByTestId("view-2d").click({ position: { x: box.width * 0.25, y: box.height * 0.55 } }));
    assert.equal(state, "planned");
    assert.match(await page.getByTestId("energy").textContent(), /E_min at the picked pole: \d/);
    assert.match(page.url(), /[?&]origin=-?[\d.]+%2C-?[\d.]+/, "the picked pole is in the URL");
    await shot("6-picked-pole.png");
  });

  it("makes no request outside its own origin and logs no error", () => {
    assert.deepEqual(foreign, []);
    assert.deepEqual(consoleErrors.filter((e) => !/Failed to load resource/.test(e)), []);
    writeFileSync(join(output, "e2e-ok.txt"), "the planner page e2e tests passed\n");
  });
});
