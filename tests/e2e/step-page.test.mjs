// End-to-end tests of STEP input on the page (issue 36) in Debian's headless Chromium: the
// bundled STEP sample (seed 004's blade band) read in the worker, its faces listed and drawn,
// planned with the Coons band spiral (its scallop heat map on the faces); a face clicked in the
// 3D view leaves the band (a typed error with the way out) and clicked again closes it; the
// download is byte-identical to `slitpath coons`; a garbled STEP file gives an error naming the
// entity and the page goes on; the ball-end spiral refuses the band's walls (undercuts for a
// 3-axis tool) and plans a block of faces picked from a grid of B-spline faces, the same program
// as `slitpath plan --faces`; a closed solid opened without a selection plans on its top face;
// the flank strategy on two faces of a B-spline cylinder band (the file read once, when opened),
// the same program as `slitpath flank --faces`.
// The tests share one page and run in order.
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import { join } from "node:path";
import { after, before, describe, it } from "node:test";
import { cli, launch, output, replan as replanStatus, root, screenshotPath, serve, settled as settledStatus, viewStats } from "./harness.mjs";

const PLAN_TIMEOUT = 180_000;
const SAMPLE = join(root, "www/public/samples/blade_band.step");
const FACES = [156, 176, 196, 216, 232, 248, 264, 280];

describe("STEP input on the page", { concurrency: false }, () => {
  let server, browser, page;

  const settled = () => settledStatus(page, PLAN_TIMEOUT);
  const replan = (action) => replanStatus(page, action, PLAN_TIMEOUT);
  const metric = async (id) => (await page.getByTestId(id).textContent()) ?? "";
  const ticked = () => page.evaluate(() => [...document.querySelectorAll("[data-testid^=face-]")].filter((b) => b.type === "checkbox" && b.checked).map((b) => Number(b.dataset.testid.slice(5))));
  /** Clicks face `index` (list order) where the 3D view shows it; false when it is hidden from this view. */
  const clickFace = async (index) => {
    const at = await page.evaluate((i) => window.slitpathViews.facePoint(i), index);
    if (at === null) return false;
    await page.getByTestId("view-3d").click({ position: { x: at[0], y: at[1] } });
    return true;
  };

  before(async () => {
    server = await serve(join(root, "www/dist"));
    browser = await launch();
    page = await browser.context.newPage();
    // 20 000 verifier samples keep the Coons plans quick (the CLI gets the same).
    await page.goto(`${server.url}?coons-samples=20000`);
    assert.equal(await settled(), "planned", "the spiral sample plans on opening");
  });

  after(async () => {
    await browser?.close();
    server?.close();
  });

  it("opens the STEP sample, lists its faces and plans the Coons band", async () => {
    const state = await replan(() => page.getByTestId("load-step").click());
    assert.equal(state, "planned", await page.getByTestId("status-detail").textContent());
    assert.equal(await page.getByTestId("opt-strategy").inputValue(), "coons");
    assert.deepEqual(await ticked(), FACES, "all eight faces listed and selected");
    assert.match(await page.getByTestId("face-list").textContent(), /#156b-spline313\.6 mm²/, "the face listed with its facets' area");
    assert.match(await metric("metric-coons-band"), /^4 × 2 faces/);
    const max = Number((await metric("metric-coons-scallop")).match(/^([\d.]+) mm/)?.[1]);
    assert.ok(max > 0 && max <= 0.02, `max scallop ≤ h: ${max}`);
    const after = Number((await metric("metric-coons-seams")).match(/round the loop max [\d.]+° → ([\d.]+)°/)?.[1]);
    assert.ok(after < 0.1, `seam jumps round the loop under 0.1° after smoothing: ${after}`);
    assert.match(await metric("metric-coons-length"), / 0 retractions/);
    assert.match(page.url(), /[?&]strategy=coons\b/);
    await page.waitForTimeout(300);
    const s = await viewStats(page, "view-3d");
    assert.ok(s.nonBackground > 0.05 && s.colours > 30, `faces and path drawn: ${JSON.stringify(s)}`);
    // The scallop heat map on the band's faces (the part), with its legend; the layer toggles it.
    assert.equal(await page.getByTestId("legend").isVisible(), true, "the scallop legend shows");
    assert.equal(await page.locator("#legend-max").textContent(), "h = 0.02 mm");
    await page.getByTestId("layer-heat").uncheck();
    await page.waitForTimeout(300);
    const plain = await viewStats(page, "view-3d");
    assert.equal(await page.getByTestId("legend").isVisible(), false, "no legend without the heat map");
    assert.ok(s.colours > plain.colours + 10, `the heat map colours the faces: ${s.colours} colours with it, ${plain.colours} without`);
    await page.getByTestId("layer-heat").check();
    await page.screenshot({ path: screenshotPath("step-1-coons.png"), fullPage: true });
  });

  it("downloads the same program as `slitpath coons`, byte for byte", async () => {
    const [download] = await Promise.all([page.waitForEvent("download"), page.getByTestId("download-gcode").click()]);
    assert.equal(download.suggestedFilename(), "blade_band.ngc");
    const file = join(output, "page-blade_band.ngc");
    await download.saveAs(file);
    const command = await page.getByTestId("cli-command").textContent();
    assert.match(command, /^slitpath coons PART\.step --faces 156,176,196,216,232,248,264,280 /);
    const cliFile = join(output, "cli-blade_band.ngc");
    cli("coons", SAMPLE, ...command.split(" ").slice(3), "-o", cliFile);
    const [fromPage, fromCli] = [readFileSync(file), readFileSync(cliFile)];
    assert.ok(fromCli.length > 10_000, "the CLI wrote a program");
    assert.ok(fromPage.equals(fromCli), `page ${fromPage.length} bytes, CLI ${fromCli.length} bytes: they differ`);
  });

  it("picks faces by clicking them in the 3D view: an open selection is refused, closing it plans again", async () => {
    const length = await metric("metric-coons-length");
    let index = 0;
    while (index < FACES.length && (await page.evaluate((i) => window.slitpathViews.facePoint(i), index)) === null) index++;
    assert.ok(index < FACES.length, "some face is visible");
    const refused = await replan(() => clickFace(index));
    assert.match(refused, /^error: the faces (are not a band of rows|do not close into a band): .*face #\d+/);
    assert.match(await page.getByTestId("status-detail").textContent(), /closed band of four-sided faces\. The spiral strategy plans the selected faces/);
    assert.deepEqual(await ticked(), FACES.filter((_, i) => i !== index), "the clicked face is deselected in the list");
    assert.match(page.url(), new RegExp(`[?&]faces=${FACES.filter((_, i) => i !== index).join("%2C")}`));
    assert.equal(await metric("metric-coons-length"), length, "the last good plan is still shown");
    const again = await replan(() => clickFace(index));
    assert.equal(again, "planned");
    assert.deepEqual(await ticked(), FACES);
    assert.equal(await metric("metric-coons-length"), length, "the same band plans the same path");
  });

  it("shows a typed error for a garbled STEP file and stays usable", async () => {
    const text = readFileSync(SAMPLE, "utf8").replace("EDGE_CURVE('',#", "EDGE_CURVE('',#999999");
    const failed = await replan(() => page.getByTestId("stl-input").setInputFiles({ name: "garbled.step", mimeType: "application/step", buffer: Buffer.from(text) }));
    assert.match(failed, /^error: .*#999999/, "the message names the entity");
    assert.match(await page.getByTestId("status-detail").textContent(), /garbled\.step was not loaded\. The last good plan is still shown/);
    assert.equal(await page.getByTestId("download-gcode").isEnabled(), true);
    const state = await replan(() => page.getByTestId("opt-coons-samples").fill("10000").then(() => page.getByTestId("opt-coons-samples").dispatchEvent("change")));
    assert.equal(state, "planned", "the page plans again");
  });

  it("plans a selection of STEP faces with the ball-end spiral, the same program as `slitpath plan --faces`", async () => {
    // The blade band's walls face sideways: a clear error, not a plan.
    const walls = await replan(() => page.getByTestId("opt-strategy").selectOption("spiral"));
    assert.match(walls, /^error: .*undercut/);
    const file = join(output, "field_grid.step");
    cli("fixture", "step:field_grid", "-o", file);
    assert.equal(await replan(() => page.getByTestId("stl-input").setInputFiles(file)), "planned", await page.getByTestId("status-detail").textContent());
    assert.equal((await ticked()).length, 20, "all twenty faces listed and selected");
    const all = await metric("metric-length");
    // A 2 × 3 block of the grid, ticked in one go (one re-plan).
    const block = [50, 91, 132, 254, 287, 320];
    const state = await replan(() =>
      page.evaluate((ids) => {
        document.querySelector("[data-testid=faces-none]").click();
        for (const id of ids) document.querySelector(`[data-testid=face-${id}]`).click();
      }, block),
    );
    assert.equal(state, "planned", await page.getByTestId("status-detail").textContent());
    assert.deepEqual(await ticked(), block);
    assert.notEqual(await metric("metric-length"), all, "the block plans a path of its own");
    const command = await page.getByTestId("cli-command").textContent();
    assert.match(command, /^slitpath plan PART\.step --faces 50,91,132,254,287,320 /);
    const [download] = await Promise.all([page.waitForEvent("download"), page.getByTestId("download-gcode").click()]);
    assert.equal(download.suggestedFilename(), "field_grid.ngc");
    const fromPageFile = join(output, "page-field_grid.ngc");
    await download.saveAs(fromPageFile);
    const cliFile = join(output, "cli-field_grid.ngc");
    cli("plan", file, ...command.split(" ").slice(3), "-o", cliFile);
    const [fromPage, fromCli] = [readFileSync(fromPageFile), readFileSync(cliFile)];
    assert.ok(fromCli.length > 10_000, "the CLI wrote a program");
    assert.ok(fromPage.equals(fromCli), `page ${fromPage.length} bytes, CLI ${fromCli.length} bytes: they differ`);
  });

  it("plans the top of a STEP solid opened without a selection, by whole faces", async () => {
    const file = join(output, "field_block.step");
    cli("fixture", "step:field_block", "-o", file);
    assert.equal(await replan(() => page.getByTestId("stl-input").setInputFiles(file)), "planned", await page.getByTestId("status-detail").textContent());
    const boxes = await page.evaluate(() => document.querySelectorAll("[data-testid^=face-][type=checkbox]").length);
    assert.equal(boxes, 6, "all six faces of the solid listed");
    assert.deepEqual(await ticked(), [50], "only the B-spline top selected");
    const [max, h] = (await metric("metric-max-scallop")).match(/[\d.]+/g).map(Number);
    assert.ok(max > 0 && max <= h, `max scallop ≤ h: ${max} / ${h}`);
  });

  it("flank-mills a selection of STEP faces, the same program as `slitpath flank --faces`", async () => {
    // Four quarter-cylinder B-spline faces (R 20 mm, 30 mm high); two of them, a half cylinder,
    // are a wall the page's default cone flanks within the verifier's tolerance.
    const file = join(output, "cylinder_band.step");
    cli("fixture", "step:cylinder_band", "-o", file);
    assert.match(await replan(() => page.getByTestId("opt-strategy").selectOption("flank")), /^(planned|error: )/);
    assert.match(await replan(() => page.getByTestId("stl-input").setInputFiles(file)), /^(planned|error: )/, "the whole band opens (planned or refused)");
    assert.equal((await ticked()).length, 4, "all four faces listed and selected");
    const pick = [62, 78];
    const state = await replan(() =>
      page.evaluate((ids) => {
        document.querySelector("[data-testid=faces-none]").click();
        for (const id of ids) document.querySelector(`[data-testid=face-${id}]`).click();
      }, pick),
    );
    assert.equal(state, "planned", await page.getByTestId("status-detail").textContent());
    assert.deepEqual(await ticked(), pick);
    assert.equal(await page.getByTestId("opt-strategy").inputValue(), "flank");
    const gouge = Number((await metric("metric-flank-gouge")).match(/^([\d.e+-]+) mm/)?.[1]);
    assert.ok(Number.isFinite(gouge) && gouge < 0.01, `max gouge under 0.01 mm: ${gouge}`);
    for (const id of ["metric-flank-undercut", "metric-flank-strips", "metric-flank-coverage"]) {
      assert.match(await metric(id), /\d/, `${id} shows a figure`);
    }
    const command = await page.getByTestId("cli-command").textContent();
    assert.match(command, /^slitpath flank PART\.step --faces 62,78 /);
    const [download] = await Promise.all([page.waitForEvent("download"), page.getByTestId("download-gcode").click()]);
    assert.equal(download.suggestedFilename(), "cylinder_band.ngc");
    const fromPageFile = join(output, "page-cylinder_band.ngc");
    await download.saveAs(fromPageFile);
    const cliFile = join(output, "cli-cylinder_band.ngc");
    cli("flank", file, ...command.split(" ").slice(3), "-o", cliFile);
    const [fromPage, fromCli] = [readFileSync(fromPageFile), readFileSync(cliFile)];
    assert.ok(fromCli.length > 1000, "the CLI wrote a program");
    assert.ok(fromPage.equals(fromCli), `page ${fromPage.length} bytes, CLI ${fromCli.length} bytes: they differ`);
  });
});
