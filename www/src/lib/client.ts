// SlitpathPlanner: the main-thread side of the planner worker, and the API a web CAM portal
// embeds. One promise per request; cancel() (and a trap in the core) replaces the worker and
// reloads the last part into the new one, so the planner stays usable.

import type { CoonsOptions, FlankOptions, MeshOptions, PlanOptions, StepOptions } from "../core";
import type { CoonsResult, FlankResult, LoadedPart, PlanResult, StepPart, WorkerRequest, WorkerResponse } from "./protocol";

/** Rejection reason of requests that were cancelled (by `cancel()` or a newer request). */
export class CancelledError extends Error {
  constructor() {
    super("cancelled");
    this.name = "CancelledError";
  }
}

/**
 * `load()` of a STEP file whose faces (all, or `stepOptions.faces`) cannot be made the part (a
 * closed solid, faces apart, …): the message says why; `step` holds the file's faces, so the
 * caller can show them and choose others with `selectFaces()`.
 */
export class StepSelectionError extends Error {
  constructor(
    message: string,
    readonly step: StepPart,
  ) {
    super(message);
    this.name = "StepSelectionError";
  }
}

export interface PlannerOptions {
  /** Makes the worker; by default the bundled module worker. */
  createWorker?: () => Worker;
}

export interface LoadOptions {
  /** Shown in messages and used for file names. Default "part.stl". */
  name?: string;
  meshOptions?: MeshOptions;
  /** STEP input: the faces to machine (default all, when they form one open surface) and the tessellation. */
  stepOptions?: StepOptions;
}

type Kept = { bytes: ArrayBuffer; name: string; meshOptions?: MeshOptions; stepOptions?: StepOptions };

export interface PlanCallbacks {
  /** Called as each step starts (loading: read, checks, flattening, factorisation, …; planning: origin, spacing, …). */
  onProgress?: (stage: string, done: number, total: number) => void;
}

type Pending = {
  resolve: (value: never) => void;
  reject: (error: Error) => void;
  onProgress?: PlanCallbacks["onProgress"];
};

export class SlitpathPlanner {
  private worker: Worker;
  private nextId = 1;
  private readonly pending = new Map<number, Pending>();
  private last: Kept | undefined;
  private versionPromise: Promise<string>;
  private resolveVersion: (version: string) => void = () => {};

  /** Called when the worker itself failed (not a single request), with a readable message. */
  onFailure: (message: string) => void = () => {};

  constructor(private readonly options: PlannerOptions = {}) {
    this.versionPromise = new Promise((resolve) => (this.resolveVersion = resolve));
    this.worker = this.spawn();
  }

  /** The core's version once the worker has started. */
  version(): Promise<string> {
    return this.versionPromise;
  }

  /**
   * Reads an STL (binary or ASCII) or a STEP file (AP203/214/242, detected by content), checks and
   * flattens it and factorises its slit map, reporting each step. The bytes are copied (kept to
   * reload after a cancel). A STEP part is made of `options.stepOptions.faces` (default all) and
   * comes with all the file's faces (`part.step`); when those faces cannot be the part, the
   * promise rejects with a `StepSelectionError` that holds them.
   */
  load(stl: ArrayBuffer | Uint8Array, options: LoadOptions = {}, callbacks: PlanCallbacks = {}): Promise<LoadedPart> {
    const bytes = stl instanceof Uint8Array ? stl.slice().buffer : stl.slice(0);
    const name = options.name ?? "part.stl";
    const kept: Kept = { bytes, name };
    if (options.meshOptions) kept.meshOptions = options.meshOptions;
    if (options.stepOptions) kept.stepOptions = options.stepOptions;
    const promise = this.sendLoad(kept, callbacks.onProgress);
    // Only a part that loaded is reloaded after a cancel.
    promise.then(() => (this.last = kept), () => {});
    return promise;
  }

  /** Plans the loaded part. Rejects with an Error (readable message) or a CancelledError. */
  plan(options: PlanOptions = {}, callbacks: PlanCallbacks = {}): Promise<PlanResult> {
    return this.request<PlanResult>({ type: "plan", id: this.nextId++, options }, [], callbacks.onProgress);
  }

  /**
   * Plans the loaded part for 5-axis flank milling with a conical tool (seed 002): tool tips,
   * axes and strip boundaries as typed arrays, the verifier's deviation per vertex of the planned
   * surface, the report and the program. Needs no slit map (a part whose flattening failed
   * plans too). Rejects with an Error (readable message) or a CancelledError.
   */
  planFlank(options: FlankOptions = {}, callbacks: PlanCallbacks = {}): Promise<FlankResult> {
    return this.request<FlankResult>({ type: "flank", id: this.nextId++, options }, [], callbacks.onProgress);
  }

  /**
   * STEP input: makes the faces `faces` (STEP ids) of the loaded file the part (planned by `plan()`
   * and `planFlank()`), like a new load. Rejects when they cannot be (not one open surface, …).
   */
  selectFaces(faces: number[], callbacks: PlanCallbacks = {}): Promise<LoadedPart> {
    const promise = this.request<LoadedPart>({ type: "selectFaces", id: this.nextId++, faces: [...faces] }, [], callbacks.onProgress);
    promise.then(() => this.last && (this.last = { ...this.last, stepOptions: { ...this.last.stepOptions, faces: [...faces] } }), () => {});
    return promise;
  }

  /**
   * STEP input: seed 004's spiral over the closed band of four-sided faces `faces` (STEP ids) of
   * the loaded file (`slitpath coons`). Rejects with the reason when they are not such a band (the
   * slit-map spiral, `plan()`, plans any open surface).
   */
  planCoons(faces: number[], options: CoonsOptions = {}, callbacks: PlanCallbacks = {}): Promise<CoonsResult> {
    return this.request<CoonsResult>({ type: "coons", id: this.nextId++, faces: [...faces], options }, [], callbacks.onProgress);
  }

  /** E_min of a pole (x, y) of the flattened plane (waits for a running plan). */
  energy(x: number, y: number): Promise<number> {
    return this.request<number>({ type: "energy", id: this.nextId++, x, y });
  }

  /** The flattened-plane point under a slit-domain point (x, y) of the last map (plan or preview), or null outside it. */
  flatPoint(x: number, y: number): Promise<[number, number] | null> {
    return this.request<[number, number] | null>({ type: "flatPoint", id: this.nextId++, x, y });
  }

  /** Stops whatever runs: every pending request rejects with CancelledError; the last part is reloaded. */
  cancel(): void {
    this.restart(new CancelledError());
  }

  /** Stops the worker for good. */
  dispose(): void {
    this.worker.terminate();
    this.failAll(new CancelledError());
  }

  private sendLoad(part: Kept, onProgress?: Pending["onProgress"]): Promise<LoadedPart> {
    const bytes = part.bytes.slice(0); // the copy is transferred, the original kept
    const message: WorkerRequest = { type: "load", id: this.nextId++, name: part.name, bytes };
    if (part.meshOptions) message.meshOptions = part.meshOptions;
    if (part.stepOptions) message.stepOptions = part.stepOptions;
    return this.request<LoadedPart>(message, [bytes], onProgress);
  }

  private request<T>(message: WorkerRequest, transfer: Transferable[] = [], onProgress?: Pending["onProgress"]): Promise<T> {
    return new Promise<T>((resolve, reject) => {
      const pending: Pending = { resolve: resolve as (value: never) => void, reject };
      if (onProgress) pending.onProgress = onProgress;
      this.pending.set(message.id, pending);
      this.worker.postMessage(message, transfer);
    });
  }

  private spawn(): Worker {
    const worker =
      this.options.createWorker?.() ??
      new Worker(new URL("./worker.ts", import.meta.url), { type: "module", name: "slitpath-planner" });
    worker.addEventListener("message", (event: MessageEvent<WorkerResponse>) => this.receive(event.data));
    worker.addEventListener("error", (event: ErrorEvent) => {
      const message = `the planner worker failed: ${event.message || "could not load its script"}`;
      this.failAll(new Error(message));
      this.onFailure(message);
    });
    return worker;
  }

  private receive(message: WorkerResponse): void {
    switch (message.type) {
      case "ready":
        this.resolveVersion(message.version);
        return;
      case "progress":
        this.pending.get(message.id)?.onProgress?.(message.stage, message.done, message.total);
        return;
      case "loaded":
        return this.settle(message.id, message.part);
      case "planned":
      case "flanked":
      case "coonsPlanned":
        return this.settle(message.id, message.plan);
      case "energy":
        return this.settle(message.id, message.value);
      case "flatPoint":
        return this.settle(message.id, message.point);
      case "error": {
        if (message.id === null) {
          this.failAll(new Error(message.message));
          this.onFailure(message.message);
          return;
        }
        this.take(message.id)?.reject(message.step ? new StepSelectionError(message.message, message.step) : new Error(message.message));
        // A trap leaves the wasm instance unusable.
        if (message.fatal) this.restart(new Error(`the planner core stopped (${message.message}); it was restarted`));
        return;
      }
    }
  }

  private settle(id: number, value: unknown): void {
    this.take(id)?.resolve(value as never);
  }

  private take(id: number): Pending | undefined {
    const pending = this.pending.get(id);
    this.pending.delete(id);
    return pending;
  }

  private failAll(error: Error): void {
    const all = [...this.pending.values()];
    this.pending.clear();
    for (const pending of all) pending.reject(error);
  }

  private restart(reason: Error): void {
    this.worker.terminate();
    this.failAll(reason);
    this.worker = this.spawn();
    if (this.last) this.sendLoad(this.last).catch((error: unknown) => this.onFailure(String(error)));
  }
}
