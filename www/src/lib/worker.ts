// The planner worker: all heavy work runs here, never on the page's main thread. It holds the
// current Part (with the core's cached factorisations) between requests and handles requests
// strictly one after another.
//
// `self` is typed with the DOM lib (the page's tsconfig); postMessage(message, { transfer }) and
// the "message" event have the same shape on a DedicatedWorkerGlobalScope.

import { Part, coreMemoryBytes, coreVersion, errorMessage, initCore, isFatal } from "../core";
import { PlanarLocator, boundaryLoops, mapPoints, matchMoves } from "./geometry";
import type { LoadedPart, PlanResult, WorkerRequest, WorkerResponse } from "./protocol";

let current: Part | undefined;
let currentName = "part";
let currentUv: Float64Array | null = null;
let currentTriangles: Uint32Array | null = null;

function post(message: WorkerResponse, transfer: Transferable[] = []): void {
  self.postMessage(message, { transfer });
}

const buffers = (...arrays: ArrayBufferView[]): ArrayBuffer[] => arrays.map((a) => a.buffer as ArrayBuffer);

function centroid(uv: Float64Array): [number, number] {
  let [x, y] = [0, 0];
  for (let i = 0; i < uv.length; i += 2) [x, y] = [x + uv[i]!, y + uv[i + 1]!];
  const n = Math.max(1, uv.length / 2);
  return [x / n, y / n];
}

async function load(request: Extract<WorkerRequest, { type: "load" }>): Promise<void> {
  const started = performance.now();
  const part = await Part.open(new Uint8Array(request.bytes), request.meshOptions);
  current?.free();
  current = part;
  // The G-code header names the part like the CLI does: the file name without its extension.
  currentName = request.name.replace(/\.[^./\\]*$/, "") || "part";
  let uv: Float64Array | null = null;
  let previewW: Float64Array | null = null;
  let conformalError: string | null = null;
  try {
    uv = part.flattened();
    const [x, y] = centroid(uv);
    previewW = part.slitMap(x, y);
  } catch (error) {
    if (isFatal(error)) throw error;
    conformalError = errorMessage(error);
  }
  // After flattening: the planner's surface has its hole rims refined and ears split (more vertices).
  const { positions, triangles } = part.surface();
  currentUv = uv;
  currentTriangles = triangles.slice();
  const loaded: LoadedPart = {
    name: request.name,
    report: part.report(),
    positions,
    triangles,
    loops: boundaryLoops(triangles),
    uv: uv?.slice() ?? null,
    previewW,
    conformalError,
    ms: performance.now() - started,
    wasmMemoryBytes: coreMemoryBytes(),
  };
  const extra = [loaded.uv, previewW].filter((a): a is Float64Array => a !== null);
  post({ type: "loaded", id: request.id, part: loaded }, buffers(positions, triangles, ...loaded.loops, ...extra));
}

function plan(request: Extract<WorkerRequest, { type: "plan" }>): void {
  if (current === undefined) throw new Error("no part is loaded");
  const started = performance.now();
  const output = current.plan({ ...request.options, partName: currentName }, (stage, done, total) =>
    post({ type: "progress", id: request.id, stage, done, total }),
  );
  // The views link the slit domain to the flattened one: locate each path point's w in the image.
  const pathUv =
    currentUv !== null && currentTriangles !== null
      ? mapPoints(new PlanarLocator(output.w, currentTriangles), output.pathW, currentUv)
      : new Float64Array(output.pathW.length).fill(NaN);
  const result: PlanResult = {
    ...output,
    pathUv,
    moveOfPoint: matchMoves(output.pathContacts, output.pathTips),
    ms: performance.now() - started,
    wasmMemoryBytes: coreMemoryBytes(),
  };
  const { w, ringRadii, pathContacts, pathW, pathTips, pathAxes, vertexScallop, moveOfPoint } = result;
  post(
    { type: "planned", id: request.id, plan: result },
    buffers(w, ringRadii, pathContacts, pathW, pathTips, pathAxes, vertexScallop, pathUv, moveOfPoint),
  );
}

async function handle(request: WorkerRequest): Promise<void> {
  try {
    switch (request.type) {
      case "load":
        return await load(request);
      case "plan":
        return plan(request);
      case "energy":
        if (current === undefined) throw new Error("no part is loaded");
        return post({ type: "energy", id: request.id, value: current.energy(request.x, request.y) });
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
