// End-to-end check of the built page (www/dist) in headless Chromium, as a person would use it:
// the bundled sample loads on opening and its report shows; a garbled STL picked with the file
// input shows a readable error and the page stays usable; the sample loads again.
// Drives Debian's chromedriver over plain WebDriver HTTP (no npm dependency). Writes screenshots
// to test-output/. Usage (after `vite build www`): node scripts/page-check.mjs
import { spawn } from "node:child_process";
import { mkdirSync, mkdtempSync, writeFileSync } from "node:fs";
import { createServer } from "node:net";
import { tmpdir } from "node:os";
import { join, resolve } from "node:path";

const root = resolve(import.meta.dirname, "..");
const children = [];
let failures = 0;

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const check = (ok, what, detail = "") => {
  console.log(`${ok ? "✔" : "✘"} ${what}${detail ? `: ${detail}` : ""}`);
  if (!ok) failures++;
};

function freePort() {
  return new Promise((res, rej) => {
    const srv = createServer();
    srv.once("error", rej);
    srv.listen(0, "127.0.0.1", () => {
      const { port } = srv.address();
      srv.close(() => res(port));
    });
  });
}

function start(cmd, args) {
  const child = spawn(cmd, args, { cwd: root, stdio: ["ignore", "ignore", "inherit"] });
  children.push(child);
  return child;
}

async function waitHttp(url, ms = 20000) {
  const until = Date.now() + ms;
  while (Date.now() < until) {
    try {
      await fetch(url);
      return;
    } catch {
      await sleep(150);
    }
  }
  throw new Error(`${url} did not answer within ${ms} ms`);
}

async function main() {
  const [pagePort, driverPort] = [await freePort(), await freePort()];
  const pageUrl = `http://127.0.0.1:${pagePort}/`;
  const driver = `http://127.0.0.1:${driverPort}`;
  start(join(root, "node_modules/.bin/vite"), ["preview", "www", "--host", "127.0.0.1", "--port", String(pagePort), "--strictPort"]);
  start("chromedriver", [`--port=${driverPort}`]);
  await Promise.all([waitHttp(pageUrl), waitHttp(`${driver}/status`)]);

  const wd = async (method, path, body) => {
    const r = await fetch(driver + path, {
      method,
      headers: { "content-type": "application/json" },
      body: body === undefined ? undefined : JSON.stringify(body),
    });
    const json = await r.json();
    if (!r.ok) throw new Error(`WebDriver ${method} ${path}: ${json.value?.message ?? r.status}`);
    return json.value;
  };
  const profile = mkdtempSync(join(tmpdir(), "slitpath-chromium-"));
  const { sessionId } = await wd("POST", "/session", {
    capabilities: {
      alwaysMatch: {
        "goog:chromeOptions": {
          binary: "/usr/bin/chromium",
          args: ["--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--disable-background-networking",
            "--disable-component-update", "--disable-sync", "--no-first-run", "--disable-quic", `--user-data-dir=${profile}`,
            "--window-size=1200,1000"],
        },
      },
    },
  });
  const s = `/session/${sessionId}`;
  const js = (script) => wd("POST", `${s}/execute/sync`, { script, args: [] });
  const text = (id) => js(`const e = document.querySelector('[data-testid=${id}]'); return e && !e.hidden ? e.textContent : null;`);
  const element = async (id) => Object.values(await wd("POST", `${s}/element`, { using: "css selector", value: `[data-testid=${id}]` }))[0];
  const settle = async (ms = 30000) => {
    const until = Date.now() + ms;
    let status = "";
    while (Date.now() < until) {
      status = (await text("status")) ?? "";
      if (/^(Loaded|Could not)/.test(status)) return status;
      await sleep(200);
    }
    return status;
  };

  try {
    await wd("POST", `${s}/url`, { url: pageUrl });
    let status = await settle();
    check(status.startsWith("Loaded freeform_4_holes.stl"), "the sample part loads on opening", status);
    const report = await js("return document.querySelector('[data-testid=report]').innerText");
    check(/Boundary loops\s+5 \(outer \d+ vertices; holes/.test(report), "the report shows 5 boundary loops (outer + 4 holes)");
    check(/Genus\s+0/.test(report) && /Closed\s+no/.test(report), "the report shows genus 0, not closed");
    check(/^core \d+\.\d+\.\d+/.test((await text("version")) ?? ""), "the core version shows", await text("version"));
    check((await text("error")) === null, "no error is shown");

    const bad = join(profile, "garbled.stl");
    writeFileSync(bad, "solid garbled\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 zz\n");
    await wd("POST", `${s}/element/${await element("stl-input")}/value`, { text: bad });
    status = await settle();
    const error = (await text("error")) ?? "";
    check(status.startsWith("Could not load garbled.stl"), "a garbled STL is refused", status);
    check(/^error: .*line 4/.test(error), "its error names the line", error);
    mkdirSync(join(root, "test-output"), { recursive: true });
    writeFileSync(join(root, "test-output/page-error.png"), Buffer.from(await wd("GET", `${s}/screenshot`), "base64"));

    await wd("POST", `${s}/element/${await element("load-sample")}/click`, {});
    await sleep(100);
    status = await settle();
    check(status.startsWith("Loaded freeform_4_holes.stl"), "the page stays usable: the sample loads again", status);
    check((await text("error")) === null, "the error is cleared");

    writeFileSync(join(root, "test-output/page.png"), Buffer.from(await wd("GET", `${s}/screenshot`), "base64"));
    console.log("screenshots: test-output/page.png, test-output/page-error.png");
  } finally {
    await wd("DELETE", s).catch(() => {});
  }
}

try {
  await main();
} catch (error) {
  check(false, "page check ran", error instanceof Error ? error.message : String(error));
} finally {
  for (const child of children) child.kill();
}
process.exit(failures === 0 ? 0 : 1);
