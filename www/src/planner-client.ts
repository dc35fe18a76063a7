// Main-thread side of the planner worker: a promise per request, and a fresh worker when the
// core trapped (a panic leaves a wasm instance unusable).

import type { MeshOptions } from "./core";
import type { LoadedPart, WorkerRequest, WorkerResponse } from "./protocol";

type Pending = { resolve: (part: LoadedPart) => void; reject: (error: Error) => void };

export class PlannerClient {
  private worker: Worker;
  private nextId = 1;
  private readonly pending = new Map<number, Pending>();

  /** Called with the core's version each time a worker is ready. */
  onReady: (version: string) => void = () => {};
  /** Called when the worker itself failed (not a single request). */
  onFailure: (message: string) => void = () => {};

  constructor() {
    this.worker = this.spawn();
  }

  /** Sends the STL bytes to the worker (transferred: `bytes` is detached afterwards). */
  load(name: string, bytes: ArrayBuffer, options?: MeshOptions): Promise<LoadedPart> {
    const id = this.nextId++;
    const request: WorkerRequest = options ? { type: "load", id, name, bytes, options } : { type: "load", id, name, bytes };
    return new Promise<LoadedPart>((resolve, reject) => {
      this.pending.set(id, { resolve, reject });
      this.worker.postMessage(request, [bytes]);
    });
  }

  private spawn(): Worker {
    const worker = new Worker(new URL("./worker.ts", import.meta.url), { type: "module", name: "slitpath-planner" });
    worker.addEventListener("message", (event: MessageEvent<WorkerResponse>) => this.receive(event.data));
    worker.addEventListener("error", (event: ErrorEvent) => {
      const message = `the planner worker failed: ${event.message || "could not load its script"}`;
      this.failAll(message);
      this.onFailure(message);
    });
    return worker;
  }

  private receive(message: WorkerResponse): void {
    switch (message.type) {
      case "ready":
        this.onReady(message.version);
        return;
      case "loaded": {
        const pending = this.take(message.id);
        pending?.resolve(message);
        return;
      }
      case "error": {
        if (message.id !== null) this.take(message.id)?.reject(new Error(message.message));
        if (message.fatal) this.restart(message.message);
        return;
      }
    }
  }

  private take(id: number): Pending | undefined {
    const pending = this.pending.get(id);
    this.pending.delete(id);
    return pending;
  }

  private failAll(message: string): void {
    for (const pending of this.pending.values()) pending.reject(new Error(message));
    this.pending.clear();
  }

  private restart(reason: string): void {
    this.worker.terminate();
    this.failAll(`the planner core stopped (${reason}); it was restarted`);
    this.worker = this.spawn();
  }
}
