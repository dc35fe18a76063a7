// The page at a real part size (issue 33): a 40k-face panel with six holes, R 3 mm, h 0.01 mm.
// Its main thread must never block for long (no long task over 250 ms: a test threshold, looser
// than the benchmark's 100 ms target so noise cannot make it flaky), both views must draw, the
// download must be the CLI's byte for byte, and scrubbing or hovering must move the cursor in the
// very next frame the views draw (read back from the canvases, not timed).
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import { join } from "node:path";
import { after, before, describe, it } from "node:test";
import { cli, launch, output, pageTimeline, recordTimeline, root, serve, viewStats } from "./harness.mjs";

const PART = join(output, "panel_40k.stl");
const LONG_TASK_LIMIT_MS = 250;

describe("a 40k-face part", { concurrency: false }, () => {
  let server, browser, page;
  const consoleErrors = [];

  const planned = () =>
    page.waitForFunction(() => /^(planned|error: )/.test(document.getElementById("status")?.textContent ?? ""), undefined, {
      timeout: 120_000,
    });
  /** The views' state after their last frame (data attributes the page keeps on the canvases). */
  const frameState = (view) =>
    page.evaluate((id) => {
      const d = document.querySelector(`[data-testid=${id}]`).dataset;
      const at = Object.fromEntries((d.cursor ?? "").split(" ").filter(Boolean).map((s) => [s.split(":")[0], s.split(":")[1].split(",").map(Number)]));
      return { frame: Number(d.frame), cursor: Number(d.cursorIndex), askedAt: Number(d.cursorAskedAt), at };
    }, `view-${view}`);
  /** Waits until both views have drawn the cursor at `index`. */
  const drawnAt = async (index) => {
    await page.waitForFunction(
      (i) => ["view-3d", "view-2d"].every((id) => document.querySelector(`[data-testid=${id}]`).dataset.cursorIndex === String(i)),
      index,
      { timeout: 10_000 },
    );
    return { "3d": await frameState("3d"), "2d": await frameState("2d") };
  };
  /** RGBA of a square of side 2r + 1 centred on (x, y) of a view's last frame, read back from its canvas. */
  const pixels = (view, [x, y], r) =>
    page.evaluate(
      async ([view, x, y, r]) => {
        const p = await window.slitpathViews.pixels(view, Math.round(x) - r, Math.round(y) - r, 2 * r + 1, 2 * r + 1);
        return { width: p.width, data: [...p.data] };
      },
      [view, x, y, r],
    );
  const brightness = (p, dx, dy) => {
    const c = (p.width - 1) / 2;
    const i = 4 * ((c + dy) * p.width + (c + dx));
    return (p.data[i] + p.data[i + 1] + p.data[i + 2]) / 3;
  };
  const difference = (a, b) => a.data.reduce((s, v, i) => (i % 4 === 3 ? s : s + Math.abs(v - b.data[i])), 0) / (a.data.length * 0.75);
  const scrubTo = (index) =>
    page.evaluate((i) => {
      const scrub = document.querySelector("[data-testid=scrub]");
      scrub.value = String(i);
      scrub.dispatchEvent(new Event("input", { bubbles: true }));
    }, index);

  before(async () => {
    cli("fixture", "panel:0.75", "-o", PART);
    server = await serve(join(root, "www/dist"));
    browser = await launch();
    page = await browser.context.newPage();
    page.on("console", (message) => message.type() === "error" && consoleErrors.push(message.text()));
    await recordTimeline(page);
    await page.goto(`${server.url}?scallop=0.01`);
    await planned();
  });

  after(async () => {
    await browser?.close();
    server?.close();
  });

  it("plans it", async () => {
    await page.getByTestId("stl-input").setInputFiles(PART);
    await planned();
    assert.equal(await page.getByTestId("status").textContent(), "planned");
    assert.match(await page.getByTestId("part-name").textContent(), /^panel_40k\.stl — 4\d{4} faces/);
    const timeline = await pageTimeline(page);
    console.log(`  choice → planned ${(timeline.chosenToPlannedMs / 1000).toFixed(2)} s, long tasks ${timeline.longTasks} (max ${timeline.longTaskMaxMs} ms)`);
  });

  it("draws the 3D and the 2D view (pixels read back)", async () => {
    await page.waitForTimeout(300);
    for (const id of ["view-3d", "view-2d"]) {
      const s = await viewStats(page, id);
      assert.ok(s.nonBackground > 0.05, `${id} is not blank: ${JSON.stringify(s)}`);
      assert.ok(s.colours > 30, `${id} shows more than a flat fill: ${JSON.stringify(s)}`);
    }
  });

  it("downloads the same G-code as the CLI, byte for byte", async () => {
    const [download] = await Promise.all([page.waitForEvent("download"), page.getByTestId("download-gcode").click()]);
    const file = join(output, "page-panel_40k.ngc");
    await download.saveAs(file);
    const cliFile = join(output, "cli-panel_40k.ngc");
    cli("plan", PART, "--radius", "3", "--scallop", "0.01", "-o", cliFile);
    const [fromPage, fromCli] = [readFileSync(file), readFileSync(cliFile)];
    assert.ok(fromCli.length > 100_000, "the CLI wrote a program");
    assert.ok(fromPage.equals(fromCli), `page ${fromPage.length} bytes, CLI ${fromCli.length} bytes: they differ`);
  });

  let target; // a path point halfway, and where the views drew it
  it("scrub: the cursor moves in the next frame drawn, in both views", async () => {
    const points = Number(await page.getByTestId("scrub").getAttribute("max")) + 1;
    assert.ok(points > 100_000, `a long path: ${points} points`);
    await scrubTo(0);
    const start = await drawnAt(0);
    const index = Math.floor(points / 2);
    // Where the tool will be, before it gets there: the same region must change when it does.
    await scrubTo(index);
    const moved = await drawnAt(index);
    await scrubTo(0);
    await drawnAt(0);
    const before3d = await pixels("3d", moved["3d"].at["3d"], 6);
    const beforeStart = await pixels("3d", start["3d"].at["3d"], 6);
    await scrubTo(index);
    const now = await drawnAt(index);
    for (const view of ["3d", "2d"]) {
      assert.equal(now[view].frame, now[view].askedAt + 1, `${view}: the cursor was drawn in the first frame after the input`);
    }
    assert.ok(difference(before3d, await pixels("3d", now["3d"].at["3d"], 6)) > 8, "the tool is drawn where it went");
    assert.ok(difference(beforeStart, await pixels("3d", start["3d"].at["3d"], 6)) > 8, "and no longer where it was");
    for (const pane of ["flat", "slit"]) {
      const dot = await pixels("2d", now["2d"].at[pane], 8);
      assert.ok(brightness(dot, 0, 0) > 200, `${pane}: the cursor's white centre`);
      const rim = Math.min(...[[5, 0], [-5, 0], [0, 5], [0, -5]].map(([dx, dy]) => brightness(dot, dx, dy)));
      assert.ok(rim < 120, `${pane}: the cursor's dark rim (${rim})`);
    }
    target = { index, at: now };
  });

  const hover = async (view, [x, y]) => {
    await page.getByTestId(`view-${view}`).scrollIntoViewIfNeeded();
    const box = await page.getByTestId(`view-${view}`).boundingBox();
    await page.mouse.move(box.x + x, box.y + y);
  };

  it("hover in the 2D view: the cursor follows in the next frame drawn", async () => {
    await scrubTo(0);
    await drawnAt(0);
    const [x, y] = target.at["2d"].at.flat;
    await hover("2d", [x, y]);
    await page.waitForFunction(() => document.querySelector("[data-testid=view-2d]").dataset.cursorIndex !== "0", undefined, { timeout: 10_000 });
    const state = await frameState("2d");
    assert.equal(state.frame, state.askedAt + 1, "drawn in the first frame after the hover");
    const [cx, cy] = state.at.flat;
    assert.ok(Math.hypot(cx - x, cy - y) <= 1.5, `the cursor is under the pointer: (${cx}, ${cy}) for (${x}, ${y})`);
    assert.equal(await page.getByTestId("scrub").inputValue(), String(state.cursor), "the scrub bar follows");
    const dot = await pixels("2d", [cx, cy], 8);
    assert.ok(brightness(dot, 0, 0) > 200, "the cursor is drawn there");
  });

  it("hover in the 3D view: the tool follows in the next frame drawn", async () => {
    await page.mouse.move(0, 0);
    await scrubTo(0);
    await drawnAt(0);
    const [x, y] = target.at["3d"].at["3d"];
    await hover("3d", [x, y]);
    await page.waitForFunction(() => document.querySelector("[data-testid=view-3d]").dataset.cursorIndex !== "0", undefined, { timeout: 10_000 });
    const state = await frameState("3d");
    assert.equal(state.frame, state.askedAt + 1, "drawn in the first frame after the hover");
    const [tx, ty] = state.at["3d"];
    assert.ok(Math.hypot(tx - x, ty - y) < 30, `the tool is near the pointer: (${tx}, ${ty}) for (${x}, ${y})`);
  });

  it(`never blocked the main thread for more than ${LONG_TASK_LIMIT_MS} ms, and logged no error`, async () => {
    const tasks = await page.evaluate(() => window.__timeline.longTasks);
    const worst = Math.max(0, ...tasks.map((t) => t.duration));
    assert.ok(worst <= LONG_TASK_LIMIT_MS, `longest main-thread task ${worst} ms: ${JSON.stringify(tasks)}`);
    assert.deepEqual(consoleErrors.filter((e) => !/Failed to load resource/.test(e)), []);
  });
});
