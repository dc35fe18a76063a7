// Shared by the end-to-end tests: a tiny static server for the built page (www/dist), Debian's
// Chromium driven by playwright-core (no downloaded browser), pixel checks and the CLI.
import { execFileSync } from "node:child_process";
import { existsSync, mkdirSync, mkdtempSync, readFileSync, rmSync } from "node:fs";
import { createServer } from "node:http";
import { tmpdir } from "node:os";
import { extname, join, normalize, resolve } from "node:path";
import { chromium } from "playwright-core";

export const root = resolve(import.meta.dirname, "../..");
export const output = join(root, "test-output");

const TYPES = {
  ".html": "text/html; charset=utf-8",
  ".js": "text/javascript",
  ".css": "text/css",
  ".wasm": "application/wasm",
  ".stl": "model/stl",
  ".json": "application/json",
};

/** Serves `dir` on 127.0.0.1 (a free port); resolves to { url, close }. */
export function serve(dir) {
  const server = createServer((request, response) => {
    const path = decodeURIComponent(new URL(request.url, "http://x").pathname);
    const file = normalize(join(dir, path.endsWith("/") ? `${path}index.html` : path));
    if (!file.startsWith(dir) || !existsSync(file)) {
      response.writeHead(404).end("not found");
      return;
    }
    response.writeHead(200, { "content-type": TYPES[extname(file)] ?? "application/octet-stream" });
    response.end(readFileSync(file));
  });
  return new Promise((res) =>
    server.listen(0, "127.0.0.1", () => res({ url: `http://127.0.0.1:${server.address().port}/`, close: () => server.close() })),
  );
}

/**
 * Headless Debian Chromium with a fresh profile; WebGL through SwiftShader so canvases render.
 * `extraArgs`: more command-line switches (the page benchmark measures the heap with them).
 */
export async function launch(extraArgs = []) {
  const profile = mkdtempSync(join(tmpdir(), "slitpath-e2e-"));
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: "/usr/bin/chromium",
    headless: true,
    acceptDownloads: true,
    viewport: { width: 1400, height: 1100 },
    args: [
      "--no-sandbox",
      "--disable-gpu",
      "--disable-dev-shm-usage",
      "--disable-background-networking",
      "--disable-component-update",
      "--disable-sync",
      "--no-first-run",
      "--disable-quic",
      "--use-gl=angle",
      "--use-angle=swiftshader",
      "--enable-unsafe-swiftshader",
      ...extraArgs,
    ],
  });
  return {
    context,
    async close() {
      await context.close();
      rmSync(profile, { recursive: true, force: true });
    },
  };
}

/**
 * Of a view's last frame, read back from its canvas in the render worker (through the page's test
 * hook `slitpathViews`; testId view-3d or view-2d): the share of pixels unlike the corner's
 * colour, and the number of distinct colours.
 */
export function viewStats(page, testId) {
  return page.evaluate(async (id) => {
    const canvas = document.querySelector(`[data-testid=${id}]`);
    const { width, height, data } = await window.slitpathViews.pixels(id.replace("view-", ""), 0, 0, canvas.clientWidth, canvas.clientHeight);
    const [r0, g0, b0] = data;
    let differ = 0;
    const colours = new Set();
    for (let i = 0; i < data.length; i += 4) {
      if (Math.abs(data[i] - r0) + Math.abs(data[i + 1] - g0) + Math.abs(data[i + 2] - b0) > 24) differ++;
      colours.add((data[i] >> 3) * 1024 + (data[i + 1] >> 3) * 32 + (data[i + 2] >> 3));
    }
    return { width, height, nonBackground: differ / (data.length / 4), colours: colours.size };
  }, testId);
}

/**
 * Waits until the page's status leaves "loading"/"planning" (reads `planned`, `error: …` or
 * `cancelled`) and returns it.
 */
export async function settled(page, timeout) {
  await page.waitForFunction(
    () => /^(planned|error: |cancelled)/.test(document.querySelector("[data-testid=status]")?.textContent ?? ""),
    undefined,
    { timeout },
  );
  return page.getByTestId("status").textContent();
}

/** Waits for a new outcome after `action` (the status is cleared first), and returns it. */
export async function replan(page, action, timeout) {
  await page.evaluate(() => (document.querySelector("[data-testid=status]").textContent = "…"));
  await action();
  return settled(page, timeout);
}

/** Runs the slitpath CLI (the release binary `npm test` built, else through cargo). */
export function cli(...args) {
  const binary = join(process.env.CARGO_TARGET_DIR ? resolve(root, process.env.CARGO_TARGET_DIR) : join(root, "target"), "release/slitpath");
  const [command, rest] = existsSync(binary)
    ? [binary, args]
    : ["cargo", ["run", "--release", "--quiet", "--bin", "slitpath", "--", ...args]];
  return execFileSync(command, rest, { cwd: root, encoding: "utf8", stdio: ["ignore", "pipe", "pipe"] });
}

export function screenshotPath(name) {
  mkdirSync(output, { recursive: true });
  return join(output, name);
}

/**
 * Records, in the page, the main thread's long tasks (PerformanceObserver 'longtask'), when a file
 * was chosen in the STL input, and when the status first read "planning" (the part loaded) and
 * "planned" after that. Call before
 * page.goto; read with pageTimeline(page).
 */
export async function recordTimeline(page) {
  await page.addInitScript(() => {
    const t = (window.__timeline = { longTasks: [], chosen: null, loaded: null, planned: null });
    new PerformanceObserver((list) => {
      for (const e of list.getEntries()) t.longTasks.push({ start: e.startTime, duration: e.duration });
    }).observe({ type: "longtask", buffered: true });
    document.addEventListener(
      "change",
      (event) => {
        if (event.target?.id !== "stl-input") return;
        t.chosen = performance.now();
        t.loaded = t.planned = null;
      },
      true,
    );
    new MutationObserver(() => {
      const status = document.getElementById("status")?.textContent ?? "";
      if (t.chosen === null) return;
      // The part is loaded (and shown) when planning starts.
      if (t.loaded === null && status === "planning") t.loaded = performance.now();
      if (t.planned === null && status === "planned") t.planned = performance.now();
    }).observe(document, { subtree: true, childList: true, characterData: true });
  });
}

/** Since the file was chosen: wall time to "planning" (loaded) and to "planned", and the long tasks (ms). */
export function pageTimeline(page) {
  return page.evaluate(() => {
    const t = window.__timeline;
    const tasks = t.longTasks.filter((e) => t.chosen !== null && e.start + e.duration > t.chosen);
    return {
      chosenToLoadedMs: t.loaded !== null ? t.loaded - t.chosen : null,
      chosenToPlannedMs: t.planned !== null ? t.planned - t.chosen : null,
      longTaskSumMs: tasks.reduce((s, e) => s + e.duration, 0),
      longTaskMaxMs: tasks.reduce((m, e) => Math.max(m, e.duration), 0),
      longTasks: tasks.length,
    };
  });
}

/**
 * The planner's own time (the report's total, ms), its stage timings (ms) and its memory (MiB), as
 * the metrics panel shows them.
 */
export async function plannerFigures(page) {
  const timings = (await page.getByTestId("metric-timings").textContent()) ?? "";
  const memory = (await page.getByTestId("metric-memory").textContent().catch(() => "")) ?? "";
  const number = (text) => Number(text.replace(/,/g, ""));
  const stages = Object.fromEntries([...timings.matchAll(/(\w+) ([\d,]+)/g)].map((m) => [m[1], number(m[2])]));
  const mib = memory.match(/([\d,]+) MiB/);
  return { plannerMs: stages.total ?? null, stages, wasmMiB: mib ? number(mib[1]) : null };
}
