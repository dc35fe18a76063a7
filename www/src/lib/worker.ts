// The planner worker: all heavy work runs here, never on the page's main thread. It holds the
// current Part (with the core's cached factorisations) between requests and handles requests
// strictly one after another. Besides the core's outputs it builds what the views draw (flat
// typed arrays with levels of detail), so the main thread only hands them to WebGL.
//
// `self` is typed with the DOM lib (the page's tsconfig); postMessage(message, { transfer }) and
// the "message" event have the same shape on a DedicatedWorkerGlobalScope.

import { Part, coreMemoryBytes, coreVersion, errorMessage, initCore, isFatal, planFlank, type MeshOptions, type PlanOutput } from "../core";
import { DEFAULT_PLAN_OPTIONS } from "./defaults";
import { circles, extent, heatColours, loopEdges, pathPolyline, planar, type Polyline } from "./drawing";
import { flankDrawing } from "./flank-drawing";
import { PlanarLocator, matchMoves, pathField } from "./geometry";
import { buildPointGrid } from "./point-grid";
import type { FlankResult, LoadedPart, PlanDrawing, PlanResult, WorkerRequest, WorkerResponse } from "./protocol";

/** The part loaded, what the views and the pole pick need of it, and the last plan's map. */
let current:
  | {
      part: Part;
      name: string;
      /** The STL and its mesh options: the flank planner reads the mesh itself. */
      bytes: Uint8Array;
      meshOptions: MeshOptions | undefined;
      positions: Float32Array;
      triangles: Uint32Array;
      uv: Float64Array | null;
      /** The slit-domain image the 2D view shows (the last plan's, else the preview), and its locator. */
      w: Float64Array | null;
      locator: PlanarLocator | null;
    }
  | undefined;

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

function centroid(uv: Float64Array): [number, number] {
  let [x, y] = [0, 0];
  for (let i = 0; i < uv.length; i += 2) [x, y] = [x + uv[i]!, y + uv[i + 1]!];
  const n = Math.max(1, uv.length / 2);
  return [x / n, y / n];
}

async function load(request: Extract<WorkerRequest, { type: "load" }>): Promise<void> {
  const started = performance.now();
  // Progress over every step before planning: the core's (read, checks; refinement, flattening,
  // factorisation, facet index), then the preview map and the views' arrays.
  let offset = 0;
  const TOTAL = 8;
  const progress = (stage: string, done: number) => post({ type: "progress", id: request.id, stage, done: offset + done, total: TOTAL });
  const bytes = new Uint8Array(request.bytes);
  const part = await Part.open(bytes, request.meshOptions, progress);
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
    // The G-code header names the part like the CLI does: the file name without its extension.
    name: request.name.replace(/\.[^./\\]*$/, "") || "part",
    bytes,
    meshOptions: request.meshOptions,
    positions,
    triangles: triangles.slice(),
    uv,
    w: previewW,
    locator: null,
  };
  const loaded: LoadedPart = {
    name: request.name,
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
  };
  const { drawing: d } = loaded;
  post(
    { type: "loaded", id: request.id, part: loaded },
    buffers(loaded.positions, triangles, normals, ...loops, loaded.uv, loaded.previewW, d.uv, d.previewW, d.outerEdges, d.holeEdges),
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
  const output = await planFlank(current.bytes, current.meshOptions, { ...request.options, partName: current.name }, (stage, done, total) =>
    // The views' arrays are the last step, after the core's.
    post({ type: "progress", id: request.id, stage: stage === "done" ? "preparing the views" : stage, done, total: total + 1 }),
  );
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
    post({ type: "error", id: request.id, message: errorMessage(error), fatal: isFatal(error) });
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
