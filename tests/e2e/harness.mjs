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

/** Headless Debian Chromium with a fresh profile; WebGL through SwiftShader so canvases render. */
export async function launch() {
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

/** Share of pixels unlike the canvas's corner colour, and the number of distinct colours. */
export function canvasStats(page, testId) {
  return page.evaluate((id) => {
    const source = document.querySelector(`[data-testid=${id}]`);
    const copy = document.createElement("canvas");
    [copy.width, copy.height] = [source.width, source.height];
    const g = copy.getContext("2d");
    g.drawImage(source, 0, 0);
    const { data } = g.getImageData(0, 0, copy.width, copy.height);
    const [r0, g0, b0] = data;
    let differ = 0;
    const colours = new Set();
    for (let i = 0; i < data.length; i += 4) {
      if (Math.abs(data[i] - r0) + Math.abs(data[i + 1] - g0) + Math.abs(data[i + 2] - b0) > 24) differ++;
      colours.add((data[i] >> 3) * 1024 + (data[i + 1] >> 3) * 32 + (data[i + 2] >> 3));
    }
    return { width: copy.width, height: copy.height, nonBackground: differ / (data.length / 4), colours: colours.size };
  }, testId);
}

/** Runs the slitpath CLI (the release binary `npm test` built, else through cargo). */
export function cli(...args) {
  const binary = join(root, "target/release/slitpath");
  const [command, rest] = existsSync(binary)
    ? [binary, args]
    : ["cargo", ["run", "--release", "--quiet", "--bin", "slitpath", "--", ...args]];
  return execFileSync(command, rest, { cwd: root, encoding: "utf8", stdio: ["ignore", "pipe", "pipe"] });
}

export function screenshotPath(name) {
  mkdirSync(output, { recursive: true });
  return join(output, name);
}
