// The pool of inference workers: starting them, loading models into them, dealing out chunks.

import { pass } from "./hooks.js";
import { failFatal } from "./status.js";

/**
 * A pool of inference workers (one per core, at most 4; `?workers=N` to choose). Each holds its
 * own copy of the models; a prediction deals its chunks of target steps out round-robin, so
 * the sequence still fills in from the start, several chunks at a time.
 */
export class Inference {
  constructor(module, count) {
    this.nextId = 1;
    this.pending = new Map();
    this.module = module;
    this.count = count;
    this.workers = [];
    /** Resolves once the first worker runs WebAssembly (the others start after the first load). */
    this.started = this.spawn().started;
  }

  spawn() {
    const worker = new Worker(new URL("./worker.js", import.meta.url), { type: "module" });
    worker.models = new Set();
    worker.onmessage = (e) => this.receive(e.data);
    worker.onerror = (e) => {
      e.preventDefault?.();
      this.fail(new Error(`The inference worker failed: ${e.message || "it could not be started (www/worker.js or ../pkg/dmbn.js did not load)"}.`));
    };
    worker.onmessageerror = () => this.fail(new Error("The inference worker sent a message the page could not read."));
    worker.started = this.send(worker, { type: "init", module: this.module }).done;
    worker.started.catch((err) => this.fail(err));
    this.workers.push(worker);
    return worker;
  }

  /** Sends a message to one worker: {id, done}, `done` resolving with its final reply. */
  send(worker, msg, transfer = [], onChunk = null) {
    const id = this.nextId++;
    const done = new Promise((resolve, reject) => {
      this.pending.set(id, { worker, resolve, reject, onChunk });
      worker.postMessage({ ...msg, id }, transfer);
    });
    return { id, done };
  }

  receive(msg) {
    // A prediction's replies go through the test hook that can hold them back (hooks.js).
    if (this.pending.get(msg.id)?.onChunk) pass(() => this.deliver(msg));
    else this.deliver(msg);
  }

  deliver(msg) {
    // Replies to cancelled requests have no entry any more: dropped.
    const entry = this.pending.get(msg.id);
    if (!entry) return;
    if (msg.type === "chunk") {
      entry.onChunk?.(msg);
      return;
    }
    this.pending.delete(msg.id);
    if (msg.type === "error") entry.reject(new Error(msg.message));
    else entry.resolve(msg);
  }

  fail(err) {
    if (this.failed) return;
    this.failed = err;
    for (const entry of this.pending.values()) entry.reject(err);
    this.pending.clear();
    failFatal(err);
  }

  /** Every worker drops the observations it keeps encoded (they are encoded again when next observed). */
  forget() {
    return Promise.all(this.workers.map((w) => this.send(w, { type: "forget" }).done));
  }

  /** Stops request `id` (it resolves as cancelled). */
  cancel(id) {
    const entry = this.pending.get(id);
    if (!entry) return;
    this.pending.delete(id);
    entry.resolve({ type: "cancelled", id });
    entry.worker.postMessage({ type: "cancel", target: id });
  }

  /**
   * Loads model `model` (an id of MODELS) from `url` in the first worker, resolving with its
   * report, then in the others in the background (so that loading does not delay the page);
   * predictions use the workers that have it.
   */
  async load(model, url) {
    const [first] = this.workers;
    const reply = await this.send(first, { type: "load", model, url }).done;
    first.models.add(model);
    while (this.workers.length < this.count) this.spawn();
    for (const w of this.workers.slice(1)) {
      this.send(w, { type: "load", model, url }).done.then(
        () => w.models.add(model),
        () => {}, // the first worker loaded the same file: this one just stays out of it
      );
    }
    return reply;
  }

  /**
   * Samples `samples` futures (seeded by `seed`) at `targets` with model `model` from the
   * observations, in one worker: the last that has the model (the first decodes a live
   * forecast's step shown first). With `source` and `steps`, the worker's kept encodings serve,
   * as for `predict`. Returns {done, cancel}: `done` resolves with {type: "sampled", joints,
   * frames, ms, encodeMs} or {type: "cancelled"}. Cancelling drops the reply; the worker, busy
   * in one wasm call, finishes it.
   */
  sample({ model, frames, joints, times, targets, blend, samples, seed, source, steps }) {
    const worker = this.workers.findLast((w) => w.models.has(model)) ?? this.workers[0];
    const msg = { type: "sample", model, frames, joints, times, targets, blend, samples, seed };
    if (source != null && steps) Object.assign(msg, { source, steps: Array.from(steps) });
    const { id, done } = this.send(worker, msg, [frames.buffer, joints.buffer, times.buffer, targets.buffer]);
    return { done, cancel: () => this.cancel(id) };
  }

  /**
   * Predicts `targets` with model `model` (an id) from the observations in chunks of `chunk`
   * steps spread over the workers; `onChunk({start, count, mean, sigma, maxSigma, jointMean, jointSigma})`
   * gets each chunk (`start` a step index of `targets`) as it arrives (with `firstAlone`, the
   * first target comes alone first, sooner). With `source` (a name of the sequence) and `steps` (each observation's step),
   * the workers keep the encoded steps and encode only those they lack. Returns {done, cancel}:
   * `done` resolves with {type: "done" | "cancelled", ms, encodeMs, decodeMs, encoded, workers} (the
   * slowest worker's times, the most observations a worker encoded) or rejects with the first
   * failure.
   */
  predict({ model, frames, joints, times, targets, blend, chunk, delay, source, steps, firstAlone = false }, onChunk) {
    const workers = this.workers.filter((w) => w.models.has(model));
    const chunks = Math.ceil(targets.length / chunk);
    const active = Math.max(1, Math.min(workers.length, chunks));
    const requests = [];
    for (let w = 0; w < active; w++) {
      // Chunks w, w + active, w + 2·active, … of the targets, back to back.
      const mine = [];
      for (let c = w; c < chunks; c += active) mine.push(...targets.subarray(c * chunk, (c + 1) * chunk));
      const part = Float32Array.from(mine);
      const copies = [frames.slice(), joints.slice(), times.slice()];
      // A worker's target i is in its chunk ⌊i / chunk⌋ (pieces never cross a chunk).
      const toGlobal = (start) => (w + Math.floor(start / chunk) * active) * chunk + (start % chunk);
      const msg = { type: "predict", model, frames: copies[0], joints: copies[1], times: copies[2], targets: part, blend, chunk, delay };
      if (source != null && steps) Object.assign(msg, { source, steps: Array.from(steps) });
      // Only the worker holding the first target decodes it alone.
      msg.firstAlone = firstAlone && w === 0;
      requests.push(
        this.send(workers[w], msg, [...copies.map((a) => a.buffer), part.buffer], (m) => onChunk({ ...m, start: toGlobal(m.start) })),
      );
    }
    const cancel = () => requests.forEach((r) => this.cancel(r.id));
    const done = Promise.all(requests.map((r) => r.done)).then(
      (replies) => ({
        type: replies.some((r) => r.type === "cancelled") ? "cancelled" : "done",
        ms: Math.max(...replies.map((r) => r.ms ?? 0)),
        encodeMs: Math.max(...replies.map((r) => r.encodeMs ?? 0)),
        decodeMs: Math.max(...replies.map((r) => (r.ms ?? 0) - (r.encodeMs ?? 0))),
        encoded: Math.max(...replies.map((r) => r.encoded ?? 0)),
        workers: active,
      }),
      (err) => {
        cancel();
        throw err;
      },
    );
    return { done, cancel };
  }
}
