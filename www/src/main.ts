// The page: pick, drop or fetch an STL, hand the bytes to the planner worker, show the report.
// Later issues add the 3D view of the surface and the 2D view of the slit map beside the report.

import "./style.css";
import { PlannerClient } from "./planner-client";
import { renderReport } from "./ui/report";

const SAMPLE_URL = "samples/freeform_4_holes.stl";

function byId<T extends HTMLElement>(id: string): T {
  const node = document.getElementById(id);
  if (node === null) throw new Error(`the page has no #${id}`);
  return node as T;
}

const input = byId<HTMLInputElement>("stl-input");
const sampleButton = byId<HTMLButtonElement>("load-sample");
const errorBox = byId<HTMLSpanElement>("error");
const statusBox = byId<HTMLParagraphElement>("status");
const reportBox = byId<HTMLDivElement>("report");
const overlay = byId<HTMLDivElement>("drop-overlay");
const versionBox = document.querySelector<HTMLElement>("[data-testid=version]");

const planner = new PlannerClient();
planner.onReady = (version) => {
  if (versionBox) versionBox.textContent = `core ${version}`;
};
planner.onFailure = (message) => showError(message);

function setStatus(text: string): void {
  statusBox.textContent = text;
}

function showError(message: string): void {
  errorBox.textContent = `error: ${message}`;
  errorBox.hidden = false;
}

function clearError(): void {
  errorBox.textContent = "";
  errorBox.hidden = true;
}

function kilobytes(bytes: number): string {
  return bytes < 1024 * 1024 ? `${(bytes / 1024).toFixed(1)} kB` : `${(bytes / 1024 / 1024).toFixed(1)} MB`;
}

let generation = 0;

/** Loads one STL; a later load supersedes an earlier one still in flight. */
async function loadStl(name: string, bytes: Promise<ArrayBuffer>): Promise<void> {
  const mine = ++generation;
  clearError();
  document.body.classList.add("busy");
  setStatus(`Loading ${name}…`);
  try {
    const buffer = await bytes;
    setStatus(`Reading ${name} (${kilobytes(buffer.byteLength)})…`);
    const part = await planner.load(name, buffer);
    if (mine !== generation) return;
    renderReport(reportBox, part.report, name);
    const surface = part.report.machined ?? part.report;
    setStatus(
      `Loaded ${name}: ${surface.faces.toLocaleString("en-US")} faces to machine, ` +
        `${surface.boundary_loops} boundary loops, in ${Math.round(part.ms)} ms.`,
    );
  } catch (error) {
    if (mine !== generation) return;
    showError(error instanceof Error ? error.message : String(error));
    setStatus(`Could not load ${name}.`);
  } finally {
    if (mine === generation) document.body.classList.remove("busy");
  }
}

async function fetchSample(): Promise<ArrayBuffer> {
  const response = await fetch(SAMPLE_URL);
  const type = response.headers.get("content-type") ?? "";
  // A dev server answers unknown paths with the page itself: that is not an STL either.
  if (!response.ok || type.includes("text/html")) {
    throw new Error(`the sample part ${SAMPLE_URL} is missing (npm start generates it)`);
  }
  return response.arrayBuffer();
}

function loadFile(file: File): void {
  void loadStl(file.name, file.arrayBuffer());
}

input.addEventListener("change", () => {
  const file = input.files?.[0];
  if (file) loadFile(file);
  input.value = ""; // picking the same file again reloads it
});

sampleButton.addEventListener("click", () => void loadStl("freeform_4_holes.stl", fetchSample()));

// Drag and drop anywhere on the page.
let dragDepth = 0;
function hasFiles(event: DragEvent): boolean {
  return event.dataTransfer?.types.includes("Files") ?? false;
}
document.addEventListener("dragenter", (event) => {
  if (!hasFiles(event)) return;
  event.preventDefault();
  dragDepth++;
  overlay.hidden = false;
});
document.addEventListener("dragover", (event) => {
  if (!hasFiles(event)) return;
  event.preventDefault();
  if (event.dataTransfer) event.dataTransfer.dropEffect = "copy";
});
document.addEventListener("dragleave", (event) => {
  if (!hasFiles(event)) return;
  dragDepth = Math.max(0, dragDepth - 1);
  if (dragDepth === 0) overlay.hidden = true;
});
document.addEventListener("drop", (event) => {
  if (!hasFiles(event)) return;
  event.preventDefault();
  dragDepth = 0;
  overlay.hidden = true;
  const file = event.dataTransfer?.files[0];
  if (file) loadFile(file);
});

// Something to look at straight away: the bundled sample part.
void loadStl("freeform_4_holes.stl", fetchSample());
