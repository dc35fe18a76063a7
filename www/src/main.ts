// The page: load a part (sample, file picker, drop), plan it in the worker whenever an option
// changes, and show the plan in the 3D and 2D views (linked: hovering either, or the scrub bar,
// moves the tool and the markers together), the metrics panel and the downloads.
// The status line reads `planned` when a plan is shown and `error: <message>` after a failure;
// a failure never removes the last good plan.

import "./style.css";
import { CancelledError, SlitpathPlanner, StepSelectionError, type CoonsResult, type FlankResult, type LoadedPart, type PlanResult } from "./lib/index";
import { DEFAULT_FLANK_OPTIONS, flankOptions, type FlankFormOptions, type FullPlanOptions } from "./lib/defaults";
import { flankCliArguments, flankFromQuery, flankQuery, type Strategy } from "./flank-options";
import { cliArguments, initialOptions, persist, storedQuery } from "./options";
import { BLADE_PRESET, BLADE_SAMPLE, STEP_SAMPLE } from "./samples";
import { coonsCliArguments, coonsFromQuery, coonsOptions, coonsQuery, DEFAULT_COONS_OPTIONS, type CoonsFormOptions } from "./coons-options";
import { CoonsForm } from "./ui/coons-form";
import { renderCoonsMetrics } from "./ui/coons-metrics";
import { FaceList } from "./ui/face-list";
import { StepPage, facesFromQuery } from "./step-page";
import { FlankForm } from "./ui/flank-form";
import { renderFlankMetrics } from "./ui/flank-metrics";
import { byId } from "./ui/dom";
import { renderMetrics, renderNoPlan } from "./ui/metrics";
import { OptionsForm } from "./ui/options-form";
import { renderReport } from "./ui/report";
import { readWithProgress, saveText } from "./ui/files";
import { deviationGradientCss, heatGradientCss } from "./lib/colors";
import { Views } from "./views/views";

const SAMPLE = "freeform_4_holes.stl";
const SAMPLE_URL = `samples/${SAMPLE}`;
const REPLAN_DELAY_MS = 350;

const statusBox = byId<HTMLParagraphElement>("status");
const detailBox = byId<HTMLParagraphElement>("status-detail");
const progressRow = byId<HTMLDivElement>("progress-row");
const progress = byId<HTMLProgressElement>("progress");
const scrub = byId<HTMLInputElement>("scrub");
const scrubLabel = byId<HTMLSpanElement>("scrub-label");
const energyBox = byId<HTMLSpanElement>("energy");
const metricsBox = byId<HTMLDivElement>("metrics");
const legend = byId<HTMLDivElement>("legend");
const downloadGcode = byId<HTMLButtonElement>("download-gcode");
const downloadCl = byId<HTMLButtonElement>("download-cl");
const layerHeat = byId<HTMLInputElement>("layer-heat");
const layerPath = byId<HTMLInputElement>("layer-path");
const layerNeedles = byId<HTMLInputElement>("layer-needles");

const planner = new SlitpathPlanner();
// Both views draw in a render worker: the main thread never waits for WebGL.
const views = new Views({ "3d": byId<HTMLCanvasElement>("view-3d"), "2d": byId<HTMLCanvasElement>("view-2d") });
let options: FullPlanOptions = initialOptions();
const form = new OptionsForm(byId("options"), options);
// The strategy and the flank options: defaults, then localStorage, then the URL (like the spiral's).
let { strategy, flank } = flankFromQuery(location.search, flankFromQuery(storedQuery(), { strategy: "spiral", flank: { ...DEFAULT_FLANK_OPTIONS } }));
const flankForm = new FlankForm(byId("flank-options"), flank);
let coons: CoonsFormOptions = coonsFromQuery(location.search, coonsFromQuery(storedQuery(), { ...DEFAULT_COONS_OPTIONS }));
const coonsForm = new CoonsForm(byId("coons-options"), coons);
const stepPage = new StepPage(views, new FaceList(byId("face-list")));
/** Faces asked for in the URL (applied to the first STEP file loaded). */
let urlFaces = facesFromQuery(location.search);
const strategySelect = byId<HTMLSelectElement>("opt-strategy");

/**
 * The part shown and the last good plan of it. Their big arrays went to the render worker: what
 * stays here is the report, the G-code and counts.
 */
let part: LoadedPart | null = null;
let shown:
  | { gcode: string; strategy: "spiral"; options: FullPlanOptions }
  | { gcode: string; strategy: "flank"; flank: FlankFormOptions }
  | { gcode: string; strategy: "coons"; coons: CoonsFormOptions; faces: number[] }
  | null = null;
/** The name of the file loaded last (a STEP file may have no part yet: its faces are not one surface). */
let fileName = "";
/** Changes with every part shown (a plan of an older one is not shown). */
let generation = 0;
let planning = false;
let replanWanted = false;
let replanTimer = 0;

planner.version().then((v) => ((document.querySelector<HTMLElement>("[data-testid=version]")!).textContent = `core ${v}`));
planner.onFailure = (message) => setStatus(`error: ${message}`);

function setStatus(status: string, detail = ""): void {
  statusBox.textContent = status;
  statusBox.classList.toggle("is-error", status.startsWith("error:"));
  detailBox.textContent = detail;
}

function showProgress(label: string, fraction: number | null): void {
  progressRow.hidden = false;
  if (fraction === null) progress.removeAttribute("value");
  else progress.value = fraction;
  detailBox.textContent = label;
}

function hideProgress(): void {
  progressRow.hidden = true;
}

function message(error: unknown): string {
  return error instanceof Error ? error.message : String(error);
}

function lastGood(): string {
  return shown ? " The last good plan is still shown." : "";
}

async function loadStl(name: string, read: (onProgress: (fraction: number) => void) => Promise<ArrayBuffer>): Promise<void> {
  const asked = urlFaces;
  setStatus("loading", `reading ${name}`);
  showProgress(`reading ${name}`, 0);
  try {
    const bytes = await read((fraction) => showProgress(`reading ${name}`, fraction));
    showProgress(`checking ${name}`, null);
    urlFaces = null;
    const loaded = await planner.load(
      bytes,
      asked ? { name, stepOptions: { faces: asked } } : { name },
      { onProgress: (stage, done, total) => showProgress(`${stage} (${name})`, total > 0 ? done / total : null) },
    );
    fileName = name;
    shown = null;
    if (loaded.step) stepPage.show(loaded.step, loaded.stepFaces);
    else stepPage.clear();
    showPart(loaded);
    showState();
    renderNoPlan(metricsBox, "Planning…");
    setOutputs();
    void plan();
  } catch (error) {
    hideProgress();
    if (error instanceof StepSelectionError) {
      // The file's faces are shown for picking; no part of them yet.
      fileName = name;
      shown = null;
      part = null;
      ++generation;
      stepPage.show(error.step, asked); // with no part of them
      byId("part-name").textContent = `${name} — ${error.step.faces.length} STEP faces`;
      setOutputs();
      showState();
      renderNoPlan(metricsBox, "No plan: pick the faces to machine (click them in the 3D view or tick them in the face list).");
      return setStatus(`error: ${error.message}`, `${name}: pick the faces to machine.`);
    }
    if (error instanceof CancelledError) return setStatus("cancelled", `loading ${name} was cancelled.`);
    setStatus(`error: ${message(error)}`, `${name} was not loaded.${lastGood()}`);
  }
}

/** Shows a part made ready by the worker (an STL, or STEP faces): its report and surface. */
function showPart(loaded: LoadedPart): void {
  part = loaded;
  ++generation;
  const faces = loaded.stepFaces ? ` (${loaded.stepFaces.length} STEP faces)` : "";
  byId("part-name").textContent = `${loaded.name} — ${loaded.report.machined?.faces ?? loaded.report.faces} faces${faces}`;
  renderReport(byId("report"), loaded.report, loaded.name);
  form.setHoles(Math.max(0, loaded.loops.length - 1));
  views.setPart(loaded);
  stepPage.setPart(loaded.stepFaces);
}

/** Plans the shown part with the current options; an edit during a plan re-plans right after. */
async function plan(): Promise<void> {
  window.clearTimeout(replanTimer);
  if (part === null && !stepPage.isStep()) return;
  if (planning) {
    replanWanted = true;
    return;
  }
  planning = true;
  const mine = generation;
  const planned = { ...options };
  const flanked = { ...flank };
  const banded = { ...coons };
  setStatus("planning", "");
  showProgress("planning", null);
  const onProgress = (stage: string, done: number, total: number) => showProgress(`${stage} ${done}/${total}`, total > 0 ? done / total : null);
  try {
    stepPage.setSurfaceHidden(strategy === "coons");
    if (strategy === "coons") {
      if (!stepPage.isStep()) throw new Error("the Coons band strategy needs a STEP file (its exact faces): open a .step or .stp part, or try the STEP blade band");
      const faces = stepPage.selection();
      const result = await planner.planCoons(faces, coonsOptions(banded), { onProgress });
      if (generation === mine) await showCoons(result, banded);
    } else {
      // STEP input: the selected faces become the part first (when they changed).
      if (stepPage.isStep() && !stepPage.partIsSelection()) {
        showProgress("meshing the selected faces", null);
        showPart(await planner.selectFaces(stepPage.selection(), { onProgress }));
      }
      if (part === null) throw new Error("no part is loaded");
      const current = generation;
      if (strategy === "flank") {
        const result = await planner.planFlank(flankOptions(flanked), { onProgress });
        if (generation === current) await showFlank(result, flanked);
      } else {
        const result = await planner.plan(planned, { onProgress });
        if (generation === current) await show(result, planned);
      }
    }
  } catch (error) {
    if (error instanceof CancelledError) setStatus("cancelled", `Planning was cancelled.${lastGood()}`);
    else if (strategy === "coons" && stepPage.isStep())
      setStatus(
        `error: ${message(error)}`,
        `Seed 004 needs a closed band of four-sided faces. The spiral strategy plans the selected faces on their tessellation.${lastGood()}`,
      );
    else setStatus(`error: ${message(error)}`, `Not planned.${lastGood()}`);
    if (shown === null) renderNoPlan(metricsBox, "No plan: see the message beside the part.");
  } finally {
    planning = false;
    hideProgress();
    if (replanWanted) {
      replanWanted = false;
      void plan();
    }
  }
}

/** Shows a plan; the status reads "planned" once the views have drawn it. */
async function show(result: PlanResult, planned: FullPlanOptions): Promise<void> {
  shown = { gcode: result.gcode, strategy: "spiral", options: planned };
  showStrategy("spiral");
  renderMetrics(metricsBox, result, planned.scallopMm);
  const points = result.pathContacts.length / 3;
  const drawn = views.setPlan(result, planned.radiusMm, planned.axes === 5); // transfers the arrays it draws
  views.setPicked(typeof planned.origin === "object" && !("z" in planned.origin) ? [planned.origin.x, planned.origin.y] : null);
  scrub.max = String(Math.max(0, points - 1));
  scrub.value = "0";
  scrub.disabled = points === 0;
  setCursor(0);
  showScallopLegend(planned.scallopMm);
  setOutputs();
  const { path } = result.report;
  await drawn;
  setStatus("planned", `${fileName}: ${result.ringRadii.length} rings, ${path.length_mm.toFixed(0)} mm, ${path.time_min.toFixed(1)} min — in ${(result.ms / 1000).toFixed(1)} s`);
}

/** Shows a flank plan: the part coloured by the verifier's deviation, the strips' tips and axes. */
async function showFlank(result: FlankResult, planned: FlankFormOptions): Promise<void> {
  shown = { gcode: result.gcode, strategy: "flank", flank: planned };
  showStrategy("flank");
  renderFlankMetrics(metricsBox, result);
  const drawn = views.setFlank(result); // transfers the arrays it draws
  scrub.max = "0";
  scrub.value = "0";
  scrub.disabled = true;
  setCursor(0);
  const limit = result.drawing.limitMm;
  byId("legend-title").textContent = "deviation";
  byId("legend-bar").style.background = deviationGradientCss();
  byId("legend-min").textContent = `−${limit.toPrecision(2)} mm (gouge)`;
  byId("legend-max").textContent = `+${limit.toPrecision(2)} mm (left)`;
  byId("legend-extra").hidden = true;
  legend.hidden = !layerHeat.checked;
  setOutputs();
  const { output } = result.report;
  await drawn;
  setStatus("planned", `${fileName}: flank, ${result.report.guide.strips} strips, ${output.moves} moves, ${(output.estimated_time_s / 60).toFixed(1)} min — in ${(result.ms / 1000).toFixed(1)} s`);
}

/** The heat map's legend: the scallop from 0 to h. */
function showScallopLegend(scallopMm: number): void {
  byId("legend-title").textContent = "scallop";
  byId("legend-bar").style.background = heatGradientCss();
  byId("legend-min").textContent = "0";
  byId("legend-max").textContent = `h = ${scallopMm} mm`;
  byId("legend-extra").hidden = false;
  legend.hidden = !layerHeat.checked;
}

/**
 * Shows a Coons band plan: the path on the STEP faces, the tool and its axes, and the scallop
 * heat map on the part's surface when the part is the band's faces.
 */
async function showCoons(result: CoonsResult, planned: CoonsFormOptions): Promise<void> {
  shown = { gcode: result.gcode, strategy: "coons", coons: planned, faces: result.faces };
  showStrategy("coons");
  renderCoonsMetrics(metricsBox, result);
  const points = result.pathContacts.length / 3;
  const heat = result.drawing.heat !== undefined;
  stepPage.setSurfaceHidden(!heat);
  const drawn = views.setCoons(result, planned.radiusMm, planned.axes === 5); // transfers the arrays it draws
  scrub.max = String(Math.max(0, points - 1));
  scrub.value = "0";
  scrub.disabled = points === 0;
  setCursor(0);
  if (heat) showScallopLegend(result.report.scallop_mm);
  else legend.hidden = true;
  setOutputs();
  const r = result.report;
  await drawn;
  setStatus("planned", `${fileName}: Coons band, ${r.revolutions} revolutions, ${r.length_mm.toFixed(0)} mm, ${r.time_min.toFixed(1)} min — in ${(result.ms / 1000).toFixed(1)} s`);
}

/** What the shown plan's strategy needs of the page: the 2D slit map only for the spiral. */
function showStrategy(shownStrategy: Strategy): void {
  document.body.classList.toggle("flank-shown", shownStrategy !== "spiral");
  byId("layer-heat-label").textContent = shownStrategy === "flank" ? "deviation heat map" : "scallop heat map";
}

function setOutputs(): void {
  downloadGcode.disabled = downloadCl.disabled = shown === null;
  const post = shownPost();
  downloadGcode.textContent = post === "cl" ? "Download CL data" : `Download G-code (${post})`;
}

const postOf = (s: Strategy) => (s === "flank" ? flank.post : s === "coons" ? coons.post : options.post);

function shownPost(): FullPlanOptions["post"] {
  if (shown === null) return postOf(strategy);
  return shown.strategy === "flank" ? shown.flank.post : shown.strategy === "coons" ? shown.coons.post : shown.options.post;
}

function setCursor(index: number): void {
  const points = Number(scrub.max) + 1;
  // A flank plan has no path points to scrub (its strips are drawn whole).
  scrubLabel.textContent = shown !== null && shown.strategy !== "flank" ? `point ${index + 1} of ${points}` : "";
}

function optionsChanged(next: FullPlanOptions, now = false): void {
  options = next;
  showState();
  window.clearTimeout(replanTimer);
  if (now) void plan();
  else replanTimer = window.setTimeout(() => void plan(), REPLAN_DELAY_MS);
}

/** Puts the options (and a STEP selection) in the URL and localStorage, and shows the CLI command. */
function showState(): void {
  const faces: [string, string][] = stepPage.isStep() && !stepPage.allSelected() ? [["faces", stepPage.selection().join(",")]] : [];
  persist(options, [...flankQuery(strategy, flank), ...coonsQuery(coons), ...faces]);
  byId("cli-command").textContent = cliCommand();
}

/** The `slitpath` command of the current strategy and options (STEP: with the selected faces). */
function cliCommand(): string {
  const step = stepPage.isStep();
  const file = step ? "PART.step" : "PART.stl";
  const faces = step && !stepPage.allSelected() ? ` --faces ${stepPage.selection().join(",")}` : "";
  if (strategy === "coons") return `slitpath coons ${file} ${coonsCliArguments(stepPage.selection(), coons).join(" ")}`;
  if (strategy === "flank") return `slitpath flank ${file}${faces} ${flankCliArguments(flank).join(" ")}`;
  return `slitpath plan ${file}${faces} ${cliArguments(options).join(" ")}`;
}

/** Shows the strategy's options (and plans with it unless `plan` is false). */
function strategyChanged(next: Strategy, plan = true): void {
  strategy = next;
  strategySelect.value = next;
  byId("options").hidden = next !== "spiral";
  byId("flank-options").hidden = next !== "flank";
  byId("coons-options").hidden = next !== "coons";
  document.body.classList.toggle("flank-on", next !== "spiral");
  if (plan) optionsChanged(options, true);
}

/** `part.stl` → `part.ngc` (LinuxCNC, AC), `part.nc` (GRBL), `part.cls` (CL data). */
function outputName(post: FullPlanOptions["post"]): string {
  const base = (fileName || "part.stl").replace(/\.(stl|step|stp)$/i, "") || "part";
  const ext = { linuxcnc: "ngc", grbl: "nc", ac: "ngc", cl: "cls" }[post];
  return `${base}.${ext}`;
}

form.onChange = (next) => optionsChanged(next);
form.onInvalid = (text) => setStatus(`error: ${text}`, `Not planned.${lastGood()}`);
flankForm.onChange = (next) => {
  flank = next;
  optionsChanged(options);
};
flankForm.onInvalid = form.onInvalid;
coonsForm.onChange = (next) => {
  coons = next;
  optionsChanged(options);
};
coonsForm.onInvalid = form.onInvalid;
stepPage.onChange = () => optionsChanged(options);
strategySelect.addEventListener("change", () => strategyChanged(strategySelect.value as Strategy));
strategyChanged(strategy, false);
optionsChanged(options, false);
window.clearTimeout(replanTimer); // the first plan follows the first load

// A hover in a view has moved the cursor there already: follow it with the scrub bar.
views.onCursor = (index) => {
  scrub.value = String(index);
  setCursor(index);
};
views.onPick = (pane, x, y) => {
  if (pane === "flat") return pick(x, y);
  // Slit domain: back to the flattened plane through the image triangles (in the planner worker).
  planner.flatPoint(x, y).then(
    (uv) => uv && pick(...uv),
    () => {},
  );
};
function pick(x: number, y: number): void {
  const next = { ...options, origin: { x, y } };
  form.set(next);
  energyBox.textContent = "E_min at the picked pole: …";
  planner.energy(x, y).then(
    (e) => (energyBox.textContent = `E_min at the picked pole: ${e.toPrecision(4)}`),
    (error: unknown) => {
      if (!(error instanceof CancelledError)) energyBox.textContent = `E_min: ${message(error)}`;
    },
  );
  optionsChanged(next, true);
}
scrub.addEventListener("input", () => {
  setCursor(Number(scrub.value));
  views.setCursor(Number(scrub.value));
});

const layers = () => views.setLayers({ heatMap: layerHeat.checked, path: layerPath.checked, needles: layerNeedles.checked });
for (const box of [layerHeat, layerPath, layerNeedles]) box.addEventListener("change", layers);
layerHeat.addEventListener("change", () => (legend.hidden = !layerHeat.checked || shown === null));
byId("fit").addEventListener("click", () => views.fit());
byId("legend-bar").style.background = heatGradientCss();

byId("cancel").addEventListener("click", () => planner.cancel());

downloadGcode.addEventListener("click", () => {
  if (shown) saveText(shown.gcode, outputName(shownPost()));
});
downloadCl.addEventListener("click", async () => {
  if (!shown) return;
  if (shownPost() === "cl") return saveText(shown.gcode, outputName("cl"));
  showProgress("CL data", null);
  try {
    // The same plan through the CL post: what `--post cl` writes.
    const s = shown;
    const cl =
      s.strategy === "flank"
        ? await planner.planFlank(flankOptions({ ...s.flank, post: "cl" }))
        : s.strategy === "coons"
          ? await planner.planCoons(s.faces, coonsOptions({ ...s.coons, post: "cl" }))
          : await planner.plan({ ...s.options, post: "cl" });
    saveText(cl.gcode, outputName("cl"));
  } catch (error) {
    if (!(error instanceof CancelledError)) setStatus(`error: ${message(error)}`, "No CL data.");
  } finally {
    hideProgress();
  }
});

const fetchSample = (url: string) => async (onProgress: (fraction: number) => void): Promise<ArrayBuffer> => {
  const response = await fetch(url);
  const type = response.headers.get("content-type") ?? "";
  // A dev server answers unknown paths with the page itself: that is not a part either.
  if (!response.ok || type.includes("text/html")) {
    throw new Error(`the sample part ${url} is missing (npm start generates it)`);
  }
  onProgress(0.5);
  return response.arrayBuffer();
};

function loadFile(file: File): void {
  void loadStl(file.name, (onProgress) => readWithProgress(file, onProgress));
}

const input = byId<HTMLInputElement>("stl-input");
input.addEventListener("change", () => {
  const file = input.files?.[0];
  if (file) loadFile(file);
  input.value = ""; // picking the same file again reloads it
});
byId("load-sample").addEventListener("click", () => void loadStl(SAMPLE, fetchSample(SAMPLE_URL)));
// The flank sample: a blade-like wall, with a tool and direction that suit it (the defaults'
// direction +X runs along its normals).
byId("load-blade").addEventListener("click", () => {
  flank = { ...BLADE_PRESET };
  flankForm.set(flank);
  strategyChanged("flank", false);
  optionsChanged(options);
  window.clearTimeout(replanTimer); // the plan follows the load
  void loadStl(BLADE_SAMPLE, fetchSample(`samples/${BLADE_SAMPLE}`));
});
// The STEP sample: seed 004's blade band (4 × 2 B-spline faces), planned with the Coons band spiral.
byId("load-step").addEventListener("click", () => {
  strategyChanged("coons", false);
  optionsChanged(options);
  window.clearTimeout(replanTimer); // the plan follows the load
  void loadStl(STEP_SAMPLE, fetchSample(`samples/${STEP_SAMPLE}`));
});

// Drag and drop anywhere on the page.
const overlay = byId<HTMLDivElement>("drop-overlay");
let dragDepth = 0;
const hasFiles = (event: DragEvent) => event.dataTransfer?.types.includes("Files") ?? false;
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

// A first visit shows the product working: the bundled sample, planned.
void loadStl(SAMPLE, fetchSample(SAMPLE_URL));
// The e2e tests read the views' pixels back through this (the canvases belong to the render worker).
(window as unknown as { slitpathViews: Views }).slitpathViews = views;
