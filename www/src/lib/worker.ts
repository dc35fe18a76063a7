// The planner worker: all heavy work runs here, never on the page's main thread. It holds the
// current Part (with the core's cached factorisations) between requests and handles requests
// strictly one after another. Besides the core's outputs it builds what the views draw (flat
// typed arrays with levels of detail), so the main thread only hands them to WebGL.
//
// `self` is typed with the DOM lib (the page's tsconfig); postMessage(message, { transfer }) and
// the "message" event have the same shape on a DedicatedWorkerGlobalScope.

import { Part, StepModel, coreMemoryBytes, coreVersion, errorMessage, initCore, isFatal, isStep, planCoons, planFlank, planFlankOnStepModel, type MeshOptions, type PlanOutput, type StepFace, type StepOptions } from "../core";
import { coonsDrawing } from "./coons-drawing";
import { DEFAULT_PLAN_OPTIONS } from "./defaults";
import { circles, extent, heatColours, loopEdges, pathPolyline, planar, type Polyline } from "./drawing";
import { flankDrawing } from "./flank-drawing";
import { PlanarLocator, matchMoves, pathField } from "./geometry";
import { buildPointGrid } from "./point-grid";
import type { CoonsResult, FlankResult, LoadedPart, PlanDrawing, PlanResult, StepPart, WorkerRequest, WorkerResponse } from "./protocol";
import { stepDrawing } from "./step-drawing";

/** The part loaded, what the views and the pole pick need of it, and the last plan's map. */
let current:
  | {
      part: Part;
      name: string;
      /** The STL (or STEP) and its mesh options: the flank planner makes its own mesh of an STL. */
      bytes: Uint8Array;
      meshOptions: MeshOptions | undefined;
      /** A STEP file: the file read once and the faces that make the part (the flank planner's too). */
      source: StepSource | undefined;
      positions: Float32Array;
      triangles: Uint32Array;
      uv: Float64Array | null;
      /** The slit-domain image the 2D view shows (the last plan's, else the preview), and its locator. */
      w: Float64Array | null;
      locator: PlanarLocator | null;
    }
  | undefined;

/**
 * The STEP file loaded last, read and tessellated once: its faces can be chosen again, the flank
 * strategy and the Coons band plan on them.
 */
let stepFile: { model: StepModel; bytes: Uint8Array; name: string; meshOptions: MeshOptions | undefined; stepOptions: StepOptions; faces: StepFace[] } | undefined;

/** A part made of STEP faces: the file read once, and the options with the faces asked for (none: the file's top). */
type StepSource = { model: StepModel; stepOptions: StepOptions };

/** A STEP file could be read but not made the part with the faces asked for: the faces go with the error. */
class SelectionError extends Error {
  constructor(
    message: string,
    readonly step: StepPart,
  ) {
    super(message);
  }
}

/**
 * Drawn decimations, as fractions of the drawing's extent (its diagonal): a 2D pane is at most
 * about 1500 device pixels across its diagonal, the 3D part seen whole about as wide (the full
 * path is drawn nearer), so these stay within half a pixel.
 */
const PANE_TOLERANCE = 1 / 3000;
const COARSE_3D_TOLERANCE = 1 / 3000;

function post(message: WorkerResponse, transfer: Transferable[] = []): void {
  self.postMessage(message, { transfer });
}

const buffers = (...arrays: (ArrayBufferView | null)[]): ArrayBuffer[] =>
  arrays.filter((a): a is ArrayBufferView => a !== null).map((a) => a.buffer as ArrayBuffer);
const polylineBuffers = (p: Polyline) => buffers(p.positions, p.colours, p.segments, p.points);

/** The G-code header names the part like the CLI does: the file name without its extension. */
const partName = (fileName: string) => fileName.replace(/\.[^./\\]*$/, "") || "part";

function centroid(uv: Float64Array): [number, number] {
  let [x, y] = [0, 0];
  for (let i = 0; i < uv.length; i += 2) [x, y] = [x + uv[i]!, y + uv[i + 1]!];
  const n = Math.max(1, uv.length / 2);
  return [x / n, y / n];
}

/** Loads an STL, or a STEP file (its faces read first, then the faces asked for made the part). */
async function load(request: Extract<WorkerRequest, { type: "load" }>): Promise<void> {
  const bytes = new Uint8Array(request.bytes);
  if (!(await isStep(bytes))) {
    stepFile?.model.free();
    stepFile = undefined;
    return loadPart(request.id, request.name, bytes, request.meshOptions, undefined, null);
  }
  const started = performance.now();
  const progress = (stage: string, done: number) => post({ type: "progress", id: request.id, stage, done, total: 3 });
  const stepOptions = request.stepOptions ?? {};
  // The faces list and view show all the file's faces; the part is made of those asked for.
  const { faces: _, ...allFaces } = stepOptions;
  const model = await StepModel.open(bytes, allFaces, progress);
  const read = model.faces();
  progress("preparing the face view", 2);
  const step: StepPart = {
    name: request.name,
    faces: read.faces,
    drawing: stepDrawing(read),
    chordalErrorMm: read.chordalErrorMm,
    readMs: read.readMs,
    tessellateMs: read.tessellateMs,
  };
  stepFile?.model.free();
  stepFile = { model, bytes, name: request.name, meshOptions: request.meshOptions, stepOptions: allFaces, faces: read.faces };
  try {
    await loadPart(request.id, request.name, bytes, request.meshOptions, { model, stepOptions }, step, started);
  } catch (error) {
    if (isFatal(error)) throw error;
    throw new SelectionError(errorMessage(error), step);
  }
}

/** Makes the STEP file's faces `faces` the part. */
async function selectFaces(request: Extract<WorkerRequest, { type: "selectFaces" }>): Promise<void> {
  if (stepFile === undefined) throw new Error("no STEP file is loaded");
  if (request.faces.length === 0) throw new Error("no faces are selected: pick the faces to machine");
  const known = new Set(stepFile.faces.map((f) => f.id));
  const unknown = request.faces.find((f) => !known.has(f));
  if (unknown !== undefined) throw new Error(`face #${unknown} is not a face of ${stepFile.name}`);
  // The load's tessellation options (chordal tolerance, edge and triangle limits) stay.
  await loadPart(request.id, stepFile.name, stepFile.bytes, stepFile.meshOptions, { model: stepFile.model, stepOptions: { ...stepFile.stepOptions, faces: request.faces } }, null);
}

async function loadPart(id: number, name: string, bytes: Uint8Array, meshOptions: MeshOptions | undefined, source: StepSource | undefined, step: StepPart | null, started = performance.now()): Promise<void> {
  // Progress over every step before planning: the core's (read, checks; refinement, flattening,
  // factorisation, facet index), then the preview map and the views' arrays.
  let offset = 0;
  const TOTAL = 8;
  const progress = (stage: string, done: number) => post({ type: "progress", id, stage, done: offset + done, total: TOTAL });
  if (source) progress("meshing the selected faces", 1);
  const part = source ? await Part.fromStepModel(source.model, meshOptions, source.stepOptions.faces) : await Part.open(bytes, meshOptions, progress);
  current?.part.free();
  current = undefined;
  offset = 2;
  let uv: Float64Array | null = null;
  let previewW: Float64Array | null = null;
  let conformalError: string | null = null;
  try {
    part.prepare(progress);
    uv = part.flattened();
    progress("preview slit map", 4);
    const [x, y] = centroid(uv);
    previewW = part.slitMap(x, y);
  } catch (error) {
    if (isFatal(error)) throw error;
    conformalError = errorMessage(error);
  }
  progress("preparing the views", 5);
  // After flattening: the planner's surface has its hole rims refined and ears split (more vertices).
  const { positions, triangles, normals, loops } = part.surface();
  const [outer, ...holes] = loops;
  current = {
    part,
    name: partName(name),
    bytes,
    meshOptions,
    source,
    positions,
    triangles: triangles.slice(),
    uv,
    w: previewW,
    locator: null,
  };
  const stepIds = source ? part.stepFaces() : null;
  const loaded: LoadedPart = {
    name,
    report: part.report(),
    positions: positions.slice(),
    triangles,
    normals,
    loops,
    uv: uv?.slice() ?? null,
    previewW: previewW?.slice() ?? null,
    conformalError,
    drawing: {
      uv: uv && planar(uv),
      previewW: previewW && planar(previewW),
      outerEdges: loopEdges(outer ? [outer] : []),
      holeEdges: loopEdges(holes),
    },
    ms: performance.now() - started,
    wasmMemoryBytes: coreMemoryBytes(),
    stepFaces: stepIds,
    step,
  };
  const { drawing: d } = loaded;
  post(
    { type: "loaded", id, part: loaded },
    [...buffers(loaded.positions, triangles, normals, ...loops, loaded.uv, loaded.previewW, d.uv, d.previewW, d.outerEdges, d.holeEdges), ...stepBuffers(step)],
  );
}

const stepBuffers = (step: StepPart | null) => (step ? buffers(step.drawing.positions, step.drawing.normals, step.drawing.triangles, step.drawing.faceOfVertex, step.drawing.faceOfTriangle) : []);

/** Seed 004's spiral over a band of the STEP file's faces, and the 3D view's arrays. */
async function coons(request: Extract<WorkerRequest, { type: "coons" }>): Promise<void> {
  if (stepFile === undefined) throw new Error("the Coons band strategy needs a STEP file: open a .step or .stp part");
  const started = performance.now();
  post({ type: "progress", id: request.id, stage: "Coons band spiral", done: 0, total: 2 });
  // The part shown is the band's faces (the page makes the selection the part): its heat map too.
  const sameFaces = (a: number[] | null, b: number[]) => a !== null && a.length === b.length && [...a].sort().join() === [...b].sort().join();
  const part = current?.source?.model === stepFile.model && sameFaces(current.part.stepFaces(), request.faces) ? current.part : undefined;
  const output = await planCoons(stepFile.model, request.faces, { ...request.options, partName: partName(stepFile.name) }, part);
  post({ type: "progress", id: request.id, stage: "preparing the views", done: 1, total: 2 });
  // The report's radius and scallop are the ones planned with (the core's defaults when none was given).
  const r = output.report;
  const drawing = coonsDrawing(output, r.radius_mm, COARSE_3D_TOLERANCE, r.scallop_mm);
  const result: CoonsResult = { ...output, faces: request.faces, drawing, ms: performance.now() - started, wasmMemoryBytes: coreMemoryBytes() };
  const { drawing: d } = result;
  post(
    { type: "coonsPlanned", id: request.id, plan: result },
    [...buffers(result.pathContacts, result.pathNormals, result.pathFaces, result.pathTips, result.pathAxes, result.vertexScallop ?? null, d.moveOfPoint, d.heat ?? null), ...[d.path, d.pathCoarse].flatMap(polylineBuffers)],
  );
}

/** The views' arrays of a plan (see PlanDrawing). */
function drawing(output: PlanOutput, pathUv: Float64Array, scallopMm: number): PlanDrawing {
  const slit = PANE_TOLERANCE * extent(output.pathW, 2);
  return {
    heat: heatColours(output.vertexScallop, scallopMm),
    path: pathPolyline(output.pathContacts, 3, 0),
    pathCoarse: pathPolyline(output.pathContacts, 3, COARSE_3D_TOLERANCE * extent(output.pathContacts, 3)),
    flatPath: pathPolyline(pathUv, 2, PANE_TOLERANCE * extent(pathUv, 2)),
    slitPath: pathPolyline(output.pathW, 2, slit),
    flatGrid: buildPointGrid(pathUv),
    slitGrid: buildPointGrid(output.pathW),
    w: planar(output.w),
    rings: circles(output.ringRadii, slit),
  };
}

function plan(request: Extract<WorkerRequest, { type: "plan" }>): void {
  if (current === undefined) throw new Error("no part is loaded");
  const started = performance.now();
  const part = current;
  const output = part.part.plan({ ...request.options, partName: part.name }, (stage, done, total) =>
    // The views' arrays are the last step, after the core's.
    post({ type: "progress", id: request.id, stage: stage === "done" ? "preparing the views" : stage, done, total: total + 1 }),
  );
  // The views link the slit domain to the flattened one: each path point's face carries it over.
  const pathUv =
    part.uv !== null
      ? pathField(output.pathContacts, output.pathFaces, part.positions, part.triangles, part.uv)
      : new Float64Array(output.pathW.length).fill(NaN);
  part.w = output.w;
  part.locator = null;
  const radiusMm = request.options.radiusMm ?? DEFAULT_PLAN_OPTIONS.radiusMm;
  const result: PlanResult = {
    ...output,
    w: output.w.slice(), // the worker keeps its own for the pole pick
    pathUv,
    moveOfPoint: matchMoves(output.pathContacts, output.pathNormals, output.pathTips, output.pathAxes, radiusMm),
    drawing: drawing(output, pathUv, request.options.scallopMm ?? DEFAULT_PLAN_OPTIONS.scallopMm),
    ms: performance.now() - started,
    wasmMemoryBytes: coreMemoryBytes(),
  };
  const { w, ringRadii, pathContacts, pathNormals, pathW, pathFaces, pathTips, pathAxes, vertexScallop, moveOfPoint, drawing: d } = result;
  post(
    { type: "planned", id: request.id, plan: result },
    [
      ...buffers(w, ringRadii, pathContacts, pathNormals, pathW, pathFaces, pathTips, pathAxes, vertexScallop, pathUv, moveOfPoint),
      ...buffers(d.heat, d.w, d.rings, d.flatGrid.starts, d.flatGrid.order, d.slitGrid.starts, d.slitGrid.order),
      ...[d.path, d.pathCoarse, d.flatPath, d.slitPath].flatMap(polylineBuffers),
    ],
  );
}

/** A flank plan of the loaded part (seed 002): the core's outputs and the 3D view's arrays. */
async function flank(request: Extract<WorkerRequest, { type: "flank" }>): Promise<void> {
  if (current === undefined) throw new Error("no part is loaded");
  const started = performance.now();
  const progress = (stage: string, done: number, total: number) =>
    // The views' arrays are the last step, after the core's.
    post({ type: "progress", id: request.id, stage: stage === "done" ? "preparing the views" : stage, done, total: total + 1 });
  const options = { ...request.options, partName: current.name };
  const { source } = current;
  // A STEP part plans on the file read when it was opened (while it is still the one held: a
  // file that failed to open replaced it but left the last good part shown).
  const output =
    source !== undefined && source.model === stepFile?.model
      ? await planFlankOnStepModel(source.model, source.stepOptions.faces, current.meshOptions, options, progress)
      : await planFlank(current.bytes, current.meshOptions, options, progress, source?.stepOptions);
  const result: FlankResult = { ...output, drawing: flankDrawing(output), ms: performance.now() - started, wasmMemoryBytes: coreMemoryBytes() };
  const { tips, axes, stripMoves, positions, triangles, vertexDeviation, drawing: d } = result;
  post(
    { type: "flanked", id: request.id, plan: result },
    buffers(tips, axes, stripMoves, positions, triangles, vertexDeviation, d.normals, d.heat, d.axisLines, d.axisColours, d.tipLines, d.tipColours, d.envelopeLines, d.envelopeColours, result.contactPoints, result.posesPerStrip),
  );
}

/** The flattened-plane point under a slit-domain point (x, y) of the map the 2D view shows. */
function flatPoint(x: number, y: number): [number, number] | null {
  if (current === undefined || current.uv === null || current.w === null) return null;
  current.locator ??= new PlanarLocator(current.w, current.triangles);
  return current.locator.map(x, y, current.uv);
}

async function handle(request: WorkerRequest): Promise<void> {
  try {
    switch (request.type) {
      case "load":
        return await load(request);
      case "selectFaces":
        return await selectFaces(request);
      case "coons":
        return await coons(request);
      case "plan":
        return plan(request);
      case "flank":
        return await flank(request);
      case "energy":
        if (current === undefined) throw new Error("no part is loaded");
        return post({ type: "energy", id: request.id, value: current.part.energy(request.x, request.y) });
      case "flatPoint":
        return post({ type: "flatPoint", id: request.id, point: flatPoint(request.x, request.y) });
    }
  } catch (error) {
    if (error instanceof SelectionError) post({ type: "error", id: request.id, message: error.message, fatal: false, step: error.step }, stepBuffers(error.step));
    else post({ type: "error", id: request.id, message: errorMessage(error), fatal: isFatal(error) });
  }
}

// One request at a time, in arrival order (a load awaits the wasm start-up).
let queue: Promise<void> = Promise.resolve();
self.addEventListener("message", (event: MessageEvent<WorkerRequest>) => {
  const request = event.data;
  queue = queue.then(() => handle(request));
});

initCore().then(
  () => post({ type: "ready", version: coreVersion() }),
  (error: unknown) =>
    post({ type: "error", id: null, message: `cannot start the planner core: ${errorMessage(error)}`, fatal: true }),
);
