// The planner worker: all heavy work runs here, never on the page's main thread.
// It holds the current Part (later: its reusable solvers) between requests.
//
// `self` is typed with the DOM lib (the page's tsconfig); postMessage(message, { transfer }) and
// the "message" event have the same shape on a DedicatedWorkerGlobalScope.

import { Part, coreVersion, errorMessage, initCore, isFatal } from "./core";
import type { WorkerRequest, WorkerResponse } from "./protocol";

let current: Part | undefined;

function post(message: WorkerResponse, transfer: Transferable[] = []): void {
  self.postMessage(message, { transfer });
}

async function load(request: WorkerRequest): Promise<void> {
  const started = performance.now();
  try {
    const part = await Part.open(new Uint8Array(request.bytes), request.options);
    current?.free();
    current = part;
    const report = part.report();
    const { positions, triangles } = part.surface();
    const ms = performance.now() - started;
    post({ type: "loaded", id: request.id, name: request.name, report, ms, positions, triangles }, [
      positions.buffer as ArrayBuffer,
      triangles.buffer as ArrayBuffer,
    ]);
  } catch (error) {
    post({ type: "error", id: request.id, message: errorMessage(error), fatal: isFatal(error) });
  }
}

self.addEventListener("message", (event: MessageEvent<WorkerRequest>) => {
  const request = event.data;
  switch (request.type) {
    case "load":
      void load(request);
      break;
  }
});

initCore().then(
  () => post({ type: "ready", version: coreVersion() }),
  (error: unknown) =>
    post({ type: "error", id: null, message: `cannot start the planner core: ${errorMessage(error)}`, fatal: true }),
);
