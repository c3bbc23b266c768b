// DMBN web demo: simulate an episode in WebAssembly (main thread), pick observations, and let
// one of the shipped models (the attentive model by default, DMBN, DMBN-PTE, DMBN-PTE trained
// with time warps) predict the whole sequence, with σ, in a Web Worker.
// Plain ES modules, no bundler: the `wasm-pack build --release --target web` output is
// expected in ../pkg/ and the weights in ../assets/models/ (relative URLs, so the page works
// under any path prefix). See www/README.md.

import { JOINTS, drawJoints } from "./plot.js";
import { HEAT_GRADIENT, clearFrame, drawTable, drawTimeline, heatImage, rgbImage } from "./views.js";

/** Frame size of the shipped models; episodes are simulated at this size. */
const IMAGE_SIZE = 64;
/** Playback: one recorded step is 3 physics substeps of 1/60 s, so 20 steps/s is real time. */
const STEPS_PER_SECOND = 20;
/** Target times per predict call: the sequence fills in by this many steps at a time. */
const CHUNK = 10;
const BLENDS = { images: 1, joints: 0, both: 0.5 };
/**
 * The models the page offers, by id (the `#model` option values, the `model=` URL state, and
 * the key of the weights, loading and caching): the label, the kind the file must hold (what
 * `Model.kind` says) and the shipped file. The first is the default: the best model.
 */
const MODELS = {
  attn: { name: "Attentive (DMBN-PTE + attention)", kind: "attn", file: "attn-sim.dmbn" },
  dmbn: { name: "DMBN", kind: "dmbn", file: "dmbn-sim.dmbn" },
  pte: { name: "DMBN-PTE", kind: "pte", file: "pte-sim.dmbn" },
  "pte-aug": { name: "DMBN-PTE + time warps", kind: "pte", file: "pte-aug-sim.dmbn" },
};
const MODEL_NAMES = Object.fromEntries(Object.entries(MODELS).map(([id, m]) => [id, m.name]));
/** What a model file holds (`Model.kind`), in words, for the mismatch note. */
const KIND_NAMES = { attn: "attentive", dmbn: "DMBN", pte: "DMBN-PTE" };
const MODE_NAMES = { t: "t (unchanged)", p: "p (time stamps permuted)", f: "f (frozen)" };

const params = new URLSearchParams(location.search);
/**
 * Weight files by model id, each overridable for tests and experiments by a parameter named
 * after the id: `?attn=URL`, `?dmbn=URL`, `?pte=URL`, `?pte-aug=URL` (relative to the page).
 */
const WEIGHTS = Object.fromEntries(
  Object.entries(MODELS).map(([id, m]) => [id, new URL(params.get(id) ?? `../assets/models/${m.file}`, location.href).href]),
);
/** Inference workers: one per core, at most 4 (`?workers=N`, 1 to 8). */
const WORKERS = Math.min(8, Math.max(1, Math.round(Number(params.get("workers"))) || Math.min(4, navigator.hardwareConcurrency || 2)));
/** Debugging / screenshots: a pause in ms between predicted chunks (`?chunkDelay=200`). */
const CHUNK_DELAY = Math.max(0, Number(params.get("chunkDelay")) || 0);

const $ = (id) => document.getElementById(id);
const ui = {
  action: $("action"),
  seed: $("seed"),
  random: $("random"),
  table: $("table"),
  objectInfo: $("object-info"),
  k: $("k"),
  firstK: $("first-k"),
  randomK: $("random-k"),
  clearObs: $("clear-obs"),
  obsInfo: $("obs-info"),
  model: $("model"),
  mode: $("mode"),
  freeze: $("freeze"),
  freezeFrom: $("freeze-from"),
  freezeTo: $("freeze-to"),
  observe: $("observe"),
  predict: $("predict"),
  sigmaToggle: $("sigma-toggle"),
  sigmaOpacity: $("sigma-opacity"),
  sigmaScale: $("sigma-scale"),
  heatLegend: $("heat-legend"),
  error: $("error"),
  status: $("status"),
  timing: $("timing"),
  frameTrue: $("frame-true"),
  framePred: $("frame-pred"),
  sigmaMap: $("sigma-map"),
  predLabel: $("pred-label"),
  trueLabel: $("true-label"),
  timeline: $("timeline"),
  plot: $("joints-plot"),
  play: $("play"),
  scrubber: $("scrubber"),
  counter: $("counter"),
  badge: $("state-badge"),
};

/** Numbers for automation and the page benchmark (bench/page.mjs). */
const timings = (window.dmbnTimings = { models: {}, prediction: null });

let wasm = null;
let inference = null;
let region = null;
/** The simulated episode: the wasm Episode (kept to derive t/p/f sequences) and what it was made from. */
let episode = null;
/** The sequence shown to the model (the episode under the mode): frames, joints, times, images. */
let shown = null;
let observed = new Set();
/** The prediction on screen (or filling in). */
let prediction = null;
/** Once a prediction has been asked for, any change of settings predicts again. */
let live = false;
let step = 0;
let playing = false;
let lastTick = 0;
let fatal = false;
let stepAt = () => 0;
let timelineAt = () => -1;
let tableAt = () => null;

// ---- state and errors ----

function setState(state) {
  document.body.dataset.state = state;
  ui.badge.textContent = state;
}

function showError(err) {
  const message = err instanceof Error ? err.message : String(err);
  ui.error.textContent = message;
  ui.error.hidden = false;
  setState("error");
  console.error(err);
}

function clearError() {
  if (fatal) return false;
  ui.error.hidden = true;
  ui.error.textContent = "";
  return true;
}

function failFatal(err) {
  fatal = true;
  pause();
  for (const el of document.querySelectorAll("#controls button, #controls select, #controls input, .transport button, .transport input")) {
    el.disabled = true;
  }
  showError(err);
}

/** The state when nothing is running: what the page shows. */
function settle() {
  if (fatal) return;
  if (!episode || !models.loaded.has(ui.model.value)) return;
  setState(prediction?.complete ? "predicted" : "ready");
}

// ---- WebAssembly ----

/** A tiny module with one v128 instruction: validates only where 128-bit SIMD is supported. */
const SIMD_PROBE = new Uint8Array([0, 97, 115, 109, 1, 0, 0, 0, 1, 5, 1, 96, 0, 1, 123, 3, 2, 1, 0, 10, 10, 1, 8, 0, 65, 0, 253, 15, 253, 98, 11]);

function checkSupport() {
  if (typeof WebAssembly !== "object" || typeof WebAssembly.validate !== "function") {
    throw new Error("This browser does not support WebAssembly, which the demo needs: use a current Chrome, Edge, Firefox or Safari.");
  }
  if (!WebAssembly.validate(SIMD_PROBE)) {
    throw new Error(
      "This browser's WebAssembly has no 128-bit SIMD (simd128), which the demo's module is built with: " +
        "use Chrome/Edge ≥ 91, Firefox ≥ 89 or Safari ≥ 16.4.",
    );
  }
  if (typeof Worker !== "function") {
    throw new Error("This browser has no Web Workers, which the demo runs its models in.");
  }
}

/** Imports the glue and compiles the module once; the worker gets the compiled module. */
async function loadWasm() {
  const pkg = new URL("../pkg/", import.meta.url);
  const hint = "Build it with `wasm-pack build --release --target web --out-dir pkg` and serve the repository root over HTTP (`bash .ci/demo`).";
  let glue;
  try {
    glue = await import(new URL("dmbn.js", pkg).href);
  } catch (err) {
    throw new Error(`Could not load the WebAssembly package (${new URL("dmbn.js", pkg).href}): ${err.message ?? err}. ${hint}`);
  }
  const url = new URL("dmbn_bg.wasm", pkg).href;
  let module;
  try {
    const response = await fetch(url);
    if (!response.ok) throw new Error(`HTTP ${response.status} ${response.statusText}`);
    try {
      module = await WebAssembly.compileStreaming(response.clone());
    } catch (err) {
      // A server without the application/wasm type: compile from the bytes instead.
      if (!(err instanceof TypeError)) throw err;
      module = await WebAssembly.compile(await response.arrayBuffer());
    }
  } catch (err) {
    throw new Error(`Could not load the WebAssembly module (${url}): ${err.message ?? err}. ${hint}`);
  }
  await glue.default({ module_or_path: module });
  return { glue, module };
}

// ---- the inference workers ----

/**
 * A pool of inference workers (one per core, at most 4; `?workers=N` to choose). Each holds its
 * own copy of the models; a prediction deals its chunks of target steps out round-robin, so
 * the sequence still fills in from the start, several chunks at a time.
 */
class Inference {
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
   * Predicts `targets` with model `model` (an id) from the observations in chunks of `chunk`
   * steps spread over the workers; `onChunk({start, count, mean, sigma, jointMean, jointSigma})`
   * gets each chunk (`start` a step index of `targets`) as it arrives. Returns {done, cancel}: `done` resolves
   * with {type: "done" | "cancelled", encodeMs, decodeMs, workers} (the slowest worker's
   * times) or rejects with the first failure.
   */
  predict({ model, frames, joints, times, targets, blend, chunk, delay }, onChunk) {
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
      const toGlobal = (start) => (w + (start / chunk) * active) * chunk;
      requests.push(
        this.send(
          workers[w],
          { type: "predict", model, frames: copies[0], joints: copies[1], times: copies[2], targets: part, blend, chunk, delay },
          [...copies.map((a) => a.buffer), part.buffer],
          (msg) => onChunk({ ...msg, start: toGlobal(msg.start) }),
        ),
      );
    }
    const cancel = () => requests.forEach((r) => this.cancel(r.id));
    const done = Promise.all(requests.map((r) => r.done)).then(
      (replies) => ({
        type: replies.some((r) => r.type === "cancelled") ? "cancelled" : "done",
        encodeMs: Math.max(...replies.map((r) => r.encodeMs ?? 0)),
        decodeMs: Math.max(...replies.map((r) => (r.ms ?? 0) - (r.encodeMs ?? 0))),
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

const models = {
  /** model id → Promise of the loaded reply. */
  requests: new Map(),
  loaded: new Set(),
  load(id) {
    let p = this.requests.get(id);
    if (!p) {
      p = inference.load(id, WEIGHTS[id]).then(
        (info) => {
          if (info.imageSize !== IMAGE_SIZE) {
            throw new Error(
              `The ${MODEL_NAMES[id]} weights (${WEIGHTS[id]}) are for ${info.imageSize}×${info.imageSize} frames; this page simulates ${IMAGE_SIZE}×${IMAGE_SIZE}.`,
            );
          }
          timings.models[id] = info;
          this.loaded.add(id);
          return info;
        },
      );
      // Failures are not kept: choosing the model again retries.
      p.catch(() => this.requests.delete(id));
      this.requests.set(id, p);
    }
    return p;
  },
};

function describeModel(id) {
  const info = timings.models[id];
  if (!info) return "";
  const file = decodeURIComponent(new URL(WEIGHTS[id]).pathname.split("/").pop());
  // The file should hold the kind of model the id names (pte-aug: a DMBN-PTE).
  const mismatch =
    info.fileKind !== MODELS[id].kind ? ` — note: the file holds a ${KIND_NAMES[info.fileKind] ?? info.fileKind} model` : "";
  return `${MODEL_NAMES[id]} ready: ${file}, ${(info.bytes / 1e6).toFixed(1)} MB, loaded in ${Math.round(info.fetchMs + info.parseMs)} ms${mismatch}`;
}

/** Makes the chosen model available; shows progress and errors. */
async function selectModel() {
  const id = ui.model.value;
  if (!models.loaded.has(id)) {
    setState("loading");
    ui.status.textContent = `Loading the ${MODEL_NAMES[id]} weights…`;
  }
  try {
    await models.load(id);
  } catch (err) {
    if (ui.model.value === id) {
      ui.status.textContent = "";
      showError(err);
    }
    return false;
  }
  if (ui.model.value !== id) return false;
  clearError();
  ui.status.textContent = describeModel(id);
  return true;
}

// ---- episodes ----

/** Simulates an episode; `place` [x, y] puts the object there, otherwise the seed places it. */
function generate(place = episode?.placed ? episode.object : null) {
  const action = ui.action.value;
  const seed = Number(ui.seed.value === "" ? NaN : ui.seed.value);
  const t0 = performance.now();
  let ep;
  try {
    if (place) {
      const sim = wasm.Simulator.withObject(action, place[0], place[1], seed, IMAGE_SIZE);
      ep = sim.run();
    } else {
      ep = wasm.runEpisode(action, seed, IMAGE_SIZE);
    }
  } catch (err) {
    showError(err);
    return false;
  }
  const ms = performance.now() - t0;
  clearError();
  cancelPrediction();
  episode?.handle.free();
  const object = ep.object();
  const len = ep.len;
  episode = {
    handle: ep,
    action,
    seed,
    placed: Boolean(place),
    len,
    object: [object[0], object[1]],
    end: [object[(len - 1) * 3], object[(len - 1) * 3 + 1]],
    joints: ep.joints(),
    digest: ep.digest(),
    ms,
  };
  timings.episode_ms = ms;
  ui.freezeFrom.max = ui.freezeTo.max = String(len);
  if (!(Number(ui.freezeTo.value) > 0) || Number(ui.freezeTo.value) > len) ui.freezeTo.value = String(len);
  if (Number(ui.freezeFrom.value) >= len) ui.freezeFrom.value = String(Math.floor(len / 2));
  ui.objectInfo.textContent =
    `${len} steps simulated in ${ms < 10 ? ms.toFixed(1) : Math.round(ms)} ms · object at ` +
    `(${episode.object[0].toFixed(3)}, ${episode.object[1].toFixed(3)}) m`;
  ui.objectInfo.title = `episode sha256 ${episode.digest}`;
  drawTableMap();
  // Keep the chosen steps that the new episode has; otherwise "random k", seeded by the seed.
  observed = new Set([...(pendingObserved ?? observed)].filter((k) => k < len));
  pendingObserved = null;
  if (!observed.size) chooseRandom(Number(ui.k.value), mulberry32(seed >>> 0));
  updateObsInfo();
  buildShown();
  ui.scrubber.max = String(len - 1);
  show(0);
  writeUrl();
  play();
  return true;
}

/** Steps from the URL, used by the first episode. */
let pendingObserved = null;

/** The sequence shown to the model under the chosen mode (the p permutation uses the episode seed). */
function buildShown() {
  const mode = ui.mode.value;
  ui.freeze.hidden = mode !== "f";
  let ev;
  try {
    const from = clampInt(ui.freezeFrom.value, 0, episode.len - 1);
    const to = clampInt(ui.freezeTo.value, from + 1, episode.len);
    ev = mode === "f" ? episode.handle.evalSequence(mode, episode.seed, from, to) : episode.handle.evalSequence(mode, episode.seed);
  } catch (err) {
    showError(err);
    return false;
  }
  const frames = ev.frames();
  const size = IMAGE_SIZE;
  const px = size * size * 3;
  const images = [];
  const sprite = document.createElement("canvas");
  sprite.width = size * ev.len;
  sprite.height = size;
  const sg = sprite.getContext("2d");
  for (let k = 0; k < ev.len; k++) {
    images.push(rgbImage(frames, size, k * px));
    sg.putImageData(images[k], k * size, 0);
  }
  shown = { mode, len: ev.len, size, frames, joints: ev.joints(), times: ev.times(), images, sprite };
  ev.free();
  return true;
}

function clampInt(v, lo, hi) {
  const n = Math.round(Number(v));
  return Math.min(hi, Math.max(lo, Number.isFinite(n) ? n : lo));
}

// ---- observations ----

/** A small seeded generator, so "random k" for a given seed is reproducible. */
function mulberry32(a) {
  return () => {
    a = (a + 0x6d2b79f5) | 0;
    let t = Math.imul(a ^ (a >>> 15), 1 | a);
    t = (t + Math.imul(t ^ (t >>> 7), 61 | t)) ^ t;
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

function chooseFirst(k) {
  const n = clampInt(k, 1, episode.len);
  observed = new Set(Array.from({ length: n }, (_, i) => i));
}

function chooseRandom(k, rand = Math.random) {
  const n = clampInt(k, 1, episode.len);
  const steps = Array.from({ length: episode.len }, (_, i) => i);
  for (let i = steps.length - 1; i > 0; i--) {
    const j = Math.floor(rand() * (i + 1));
    [steps[i], steps[j]] = [steps[j], steps[i]];
  }
  observed = new Set(steps.slice(0, n));
}

function observedSteps() {
  return [...observed].sort((a, b) => a - b);
}

function updateObsInfo() {
  const steps = observedSteps();
  ui.obsInfo.textContent = steps.length
    ? `${steps.length} observed: ${steps.length > 12 ? `${steps.slice(0, 12).join(", ")}, …` : steps.join(", ")}`
    : "nothing observed: click frames on the timeline";
  ui.predict.disabled = fatal || steps.length === 0;
}

function observationsChanged() {
  updateObsInfo();
  writeUrl();
  invalidate();
}

// ---- prediction ----

function cancelPrediction() {
  if (prediction && !prediction.complete) prediction.cancel?.();
  prediction = null;
  ui.predLabel.textContent = "";
}

/** Settings changed: predict again when live, otherwise drop the outdated prediction. */
function invalidate() {
  if (live && episode && observed.size) {
    predict();
  } else {
    cancelPrediction();
    render();
    settle();
  }
}

/** The shown sequence's frames, joints and time stamps at `steps`, as the model takes them. */
function observations(steps) {
  const px = shown.size * shown.size * 3;
  const frames = new Uint8Array(steps.length * px);
  const joints = new Float32Array(steps.length * JOINTS);
  const times = new Float32Array(steps.length);
  steps.forEach((k, i) => {
    frames.set(shown.frames.subarray(k * px, (k + 1) * px), i * px);
    joints.set(shown.joints.subarray(k * JOINTS, (k + 1) * JOINTS), i * JOINTS);
    times[i] = shown.times[k];
  });
  return { frames, joints, times };
}

async function predict() {
  if (fatal || !episode || !shown) return;
  const steps = observedSteps();
  if (!steps.length) {
    showError("Choose at least one observation: click frames on the timeline, or use “first k” / “random k”.");
    return;
  }
  live = true;
  cancelPrediction();
  const model = ui.model.value;
  const mode = shown.mode;
  const observe = ui.observe.value;
  const blend = BLENDS[observe];
  const size = shown.size;
  const px = size * size;
  const n = steps.length;
  const { frames, joints, times } = observations(steps);
  // Targets: the time stamps of the shown sequence, step by step (permuted for p).
  const targets = Float32Array.from(shown.times);
  const len = targets.length;
  const p = {
    model,
    mode,
    observe,
    len,
    size,
    observed: n,
    done: new Uint8Array(len),
    count: 0,
    mean: new Uint8Array(len * px * 3),
    sigma: new Float32Array(len * px),
    jointMean: new Float32Array(len * JOINTS),
    jointSigma: new Float32Array(len * JOINTS),
    maxSigma: 0,
    complete: false,
    chunks: [],
  };
  prediction = p;
  setState("predicting");
  ui.predLabel.textContent = "predicting…";
  if (!(await selectModel())) {
    if (prediction === p) prediction = null;
    return;
  }
  if (prediction !== p) return;
  setState("predicting");
  document.body.dataset.progress = "0";
  const t0 = performance.now();
  p.start = t0;
  const run = inference.predict(
    { model, frames, joints, times, targets, blend, chunk: CHUNK, delay: CHUNK_DELAY },
    (chunk) => receiveChunk(p, chunk),
  );
  p.cancel = run.cancel;
  let reply;
  try {
    reply = await run.done;
  } catch (err) {
    if (prediction === p) {
      prediction = null;
      render();
      showError(err);
    }
    return;
  }
  if (reply.type === "cancelled" || prediction !== p) return;
  p.complete = true;
  p.totalMs = performance.now() - t0;
  // A counter that automation can wait on: it changes with every finished prediction.
  document.body.dataset.predictions = String(Number(document.body.dataset.predictions ?? 0) + 1);
  timings.prediction = {
    model,
    mode,
    observe,
    observed: n,
    steps: len,
    total_ms: p.totalMs,
    per_frame_ms: p.totalMs / len,
    first_chunk_ms: p.firstMs,
    encode_ms: reply.encodeMs,
    chunk: CHUNK,
    workers: reply.workers,
  };
  ui.predLabel.textContent = "";
  ui.timing.textContent =
    `${len} steps in ${Math.round(p.totalMs)} ms (${(p.totalMs / len).toFixed(1)} ms per frame) · ` +
    `first ${Math.min(CHUNK, len)} after ${Math.round(p.firstMs)} ms · ${reply.workers} worker${reply.workers > 1 ? "s" : ""}`;
  ui.timing.title = `${MODEL_NAMES[model]}, mode ${mode}, ${observe}, ${n} observed steps; encoding ${Math.round(reply.encodeMs)} ms`;
  render();
  settle();
}

function receiveChunk(p, c) {
  if (prediction !== p) return;
  const px = p.size * p.size;
  p.mean.set(c.mean, c.start * px * 3);
  p.sigma.set(c.sigma, c.start * px);
  p.jointMean.set(c.jointMean, c.start * JOINTS);
  p.jointSigma.set(c.jointSigma, c.start * JOINTS);
  for (let i = 0; i < c.sigma.length; i++) if (c.sigma[i] > p.maxSigma) p.maxSigma = c.sigma[i];
  p.done.fill(1, c.start, c.start + c.count);
  p.count += c.count;
  p.chunks.push(c.ms);
  if (p.firstMs === undefined) p.firstMs = performance.now() - p.start;
  document.body.dataset.progress = String(p.count);
  ui.predLabel.textContent = `predicting… ${p.count} / ${p.len}`;
  ui.timing.textContent = `${p.count} / ${p.len} steps · ${Math.round(performance.now() - p.start)} ms`;
  render();
}

// ---- drawing ----

function show(k) {
  if (!shown) return;
  step = Math.max(0, Math.min(shown.len - 1, k));
  ui.scrubber.value = String(step);
  render();
}

function render() {
  if (!shown) {
    drawJoints(ui.plot, null);
    return;
  }
  ui.frameTrue.getContext("2d").putImageData(shown.images[step], 0, 0);
  const p = prediction;
  const has = p && p.done[step];
  if (has) {
    const px = p.size * p.size;
    ui.framePred.getContext("2d").putImageData(rgbImage(p.mean, p.size, step * px * 3), 0, 0);
    ui.sigmaMap.getContext("2d").putImageData(heatImage(p.sigma, p.size, step * px, p.maxSigma), 0, 0);
    ui.sigmaScale.textContent = p.maxSigma.toFixed(3);
  } else {
    clearFrame(ui.framePred);
    clearFrame(ui.sigmaMap);
  }
  const stack = ui.framePred.parentElement;
  stack.classList.toggle("empty", !has);
  stack.dataset.empty = p ? "this step is not predicted yet" : "no prediction yet: choose observations, then Predict";
  ui.counter.textContent = `step ${step} / ${shown.len - 1} · t = ${shown.times[step].toFixed(3)}`;
  ui.trueLabel.textContent = shown.mode === "t" ? "" : `mode ${shown.mode}`;
  timelineAt = drawTimeline(ui.timeline, {
    len: shown.len,
    size: shown.size,
    sprite: shown.sprite,
    observed,
    done: p?.done,
    step,
  });
  stepAt = drawJoints(ui.plot, {
    len: shown.len,
    joints: shown.joints,
    observed: observedSteps(),
    step,
    prediction: p,
  });
}

function drawTableMap() {
  tableAt = drawTable(ui.table, region, episode?.object, episode?.end);
}

function sigmaOverlay() {
  ui.sigmaMap.hidden = !ui.sigmaToggle.checked;
  ui.sigmaMap.style.opacity = String(Number(ui.sigmaOpacity.value) / 100);
  ui.sigmaOpacity.disabled = fatal || !ui.sigmaToggle.checked;
}

// ---- playback ----

function play() {
  if (!shown) return;
  if (step >= shown.len - 1) show(0);
  playing = true;
  ui.play.textContent = "❚❚ Pause";
  ui.play.setAttribute("aria-pressed", "true");
  lastTick = performance.now();
  requestAnimationFrame(tick);
}

function pause() {
  playing = false;
  ui.play.textContent = "▶ Play";
  ui.play.setAttribute("aria-pressed", "false");
}

function toggle() {
  playing ? pause() : play();
}

function tick(now) {
  if (!playing || !shown) return;
  const advance = Math.floor(((now - lastTick) * STEPS_PER_SECOND) / 1000);
  if (advance > 0) {
    lastTick += (advance * 1000) / STEPS_PER_SECOND;
    show(step + advance);
    if (step >= shown.len - 1) {
      pause();
      return;
    }
  }
  requestAnimationFrame(tick);
}

// ---- URL ----

function readUrl() {
  const set = (el, key) => {
    if (!params.has(key)) return;
    const v = params.get(key);
    if (el instanceof HTMLSelectElement && ![...el.options].some((o) => o.value === v)) return;
    el.value = v;
  };
  set(ui.action, "action");
  set(ui.seed, "seed");
  set(ui.model, "model");
  set(ui.mode, "mode");
  set(ui.observe, "observe");
  set(ui.k, "k");
  set(ui.freezeFrom, "from");
  set(ui.freezeTo, "to");
  if (params.has("obs")) {
    pendingObserved = params
      .get("obs")
      .split(",")
      .map(Number)
      .filter((k) => Number.isInteger(k) && k >= 0);
  }
  if (params.has("x") && params.has("y")) {
    const x = Number(params.get("x"));
    const y = Number(params.get("y"));
    if (Number.isFinite(x) && Number.isFinite(y)) return [x, y];
  }
  return null;
}

function writeUrl() {
  if (!episode) return;
  const q = new URLSearchParams(location.search);
  const put = (key, value) => (value === null ? q.delete(key) : q.set(key, value));
  put("action", ui.action.value);
  put("seed", ui.seed.value);
  put("x", episode.placed ? episode.object[0].toFixed(4) : null);
  put("y", episode.placed ? episode.object[1].toFixed(4) : null);
  put("model", ui.model.value);
  put("mode", ui.mode.value);
  put("from", ui.mode.value === "f" ? ui.freezeFrom.value : null);
  put("to", ui.mode.value === "f" ? ui.freezeTo.value : null);
  put("observe", ui.observe.value);
  put("obs", observedSteps().join(","));
  history.replaceState(null, "", `${location.pathname}?${q}`);
}

// ---- wiring ----

function isTyping(el) {
  return (
    (el instanceof HTMLInputElement && !["range", "checkbox", "button"].includes(el.type)) ||
    el instanceof HTMLSelectElement ||
    el instanceof HTMLTextAreaElement
  );
}

function onKey(e) {
  if (!shown || fatal || isTyping(e.target) || e.ctrlKey || e.metaKey || e.altKey) return;
  const jump = e.shiftKey ? 10 : 1;
  const keys = {
    " ": toggle,
    ArrowLeft: () => (pause(), show(step - jump)),
    ArrowRight: () => (pause(), show(step + jump)),
    Home: () => (pause(), show(0)),
    End: () => (pause(), show(shown.len - 1)),
  };
  if (e.target === ui.timeline && e.key === "Enter") {
    if (e.type === "keydown") toggleObserved(step);
    e.preventDefault();
    return;
  }
  const action = keys[e.key];
  if (!action) return;
  // Handled here, so a focused button or the scrubber does not act on the key as well.
  e.preventDefault();
  if (e.type === "keydown") action();
}

function toggleObserved(k) {
  if (k < 0 || !shown) return;
  if (observed.has(k)) observed.delete(k);
  else observed.add(k);
  observationsChanged();
}

function wire() {
  ui.heatLegend.style.background = HEAT_GRADIENT;
  document.getElementById("controls").addEventListener("submit", (e) => e.preventDefault());
  ui.action.addEventListener("change", () => generate() && invalidate());
  ui.seed.addEventListener("change", () => generate(null) && invalidate());
  ui.random.addEventListener("click", () => {
    ui.seed.value = String(Math.floor(Math.random() * 2 ** 31));
    generate(null) && invalidate();
  });
  ui.table.addEventListener("click", (e) => {
    const at = tableAt(e.clientX, e.clientY);
    if (at && !fatal) generate(at) && invalidate();
  });
  ui.firstK.addEventListener("click", () => {
    chooseFirst(ui.k.value);
    observationsChanged();
  });
  ui.randomK.addEventListener("click", () => {
    chooseRandom(ui.k.value);
    observationsChanged();
  });
  ui.clearObs.addEventListener("click", () => {
    observed = new Set();
    observationsChanged();
  });
  ui.model.addEventListener("change", async () => {
    writeUrl();
    if (live) invalidate();
    else {
      cancelPrediction();
      render();
      if (await selectModel()) settle();
    }
  });
  const modeChanged = () => {
    if (!episode) return;
    if (buildShown()) {
      clearError();
      show(step);
      writeUrl();
      invalidate();
    }
  };
  ui.mode.addEventListener("change", modeChanged);
  ui.freezeFrom.addEventListener("change", modeChanged);
  ui.freezeTo.addEventListener("change", modeChanged);
  ui.observe.addEventListener("change", () => {
    writeUrl();
    invalidate();
  });
  ui.predict.addEventListener("click", () => predict());
  ui.sigmaToggle.addEventListener("change", sigmaOverlay);
  ui.sigmaOpacity.addEventListener("input", sigmaOverlay);
  ui.play.addEventListener("click", toggle);
  ui.scrubber.addEventListener("input", () => {
    pause();
    show(Number(ui.scrubber.value));
  });
  ui.timeline.addEventListener("click", (e) => toggleObserved(timelineAt(e.clientX)));
  ui.timeline.addEventListener("mousemove", (e) => {
    const k = timelineAt(e.clientX);
    ui.timeline.title = k < 0 ? "" : `step ${k}: click to ${observed.has(k) ? "stop observing it" : "observe it"}`;
  });
  const scrubPlot = (e) => {
    if (!shown || !(e.buttons & 1)) return;
    pause();
    show(stepAt(e.clientX));
  };
  ui.plot.addEventListener("pointerdown", (e) => {
    ui.plot.setPointerCapture(e.pointerId);
    scrubPlot(e);
  });
  ui.plot.addEventListener("pointermove", scrubPlot);
  addEventListener("keydown", onKey);
  addEventListener("keyup", onKey);
  const redraw = () => {
    render();
    if (region) drawTableMap();
  };
  new ResizeObserver(redraw).observe(ui.plot);
  new ResizeObserver(redraw).observe(ui.timeline);
  sigmaOverlay();
}

/** For bench/page.mjs: times `n` target steps (evenly spaced phases) with model `model` (an id of
 * MODELS: attn, dmbn, pte, pte-aug) on the current observations, through the same worker path and
 * chunking as the page, without drawing. */
async function timePrediction(n, model = ui.model.value, chunk = CHUNK) {
  if (!Object.hasOwn(MODELS, model)) {
    throw new Error(`timePrediction: unknown model ${JSON.stringify(model)} (one of ${Object.keys(MODELS).join(", ")})`);
  }
  await models.load(model);
  const { frames, joints, times } = observations(observedSteps());
  const targets = Float32Array.from({ length: n }, (_, i) => (n > 1 ? i / (n - 1) : 0.5));
  const t0 = performance.now();
  let first = null;
  const reply = await inference.predict(
    { model, frames, joints, times, targets, blend: BLENDS[ui.observe.value], chunk, delay: 0 },
    () => (first ??= performance.now() - t0),
  ).done;
  return {
    wall_ms: performance.now() - t0,
    first_chunk_ms: first,
    encode_ms: reply.encodeMs,
    decode_ms: reply.decodeMs,
    workers: reply.workers,
  };
}

async function main() {
  window.dmbnStarted = true;
  setState("loading");
  wire();
  const place = readUrl();
  ui.status.textContent = "Loading WebAssembly…";
  try {
    checkSupport();
    const t0 = performance.now();
    const { glue, module } = await loadWasm();
    wasm = glue;
    timings.wasm_ms = performance.now() - t0;
    inference = new Inference(module, WORKERS);
  } catch (err) {
    ui.status.textContent = "";
    failFatal(err);
    return;
  }
  window.dmbn = { timePrediction, predict: () => predict() };
  // The chosen model loads in the worker while the episode is simulated here.
  const modelReady = selectModel();
  // Simulating blocks this thread for a moment: first let the worker start (its start needs
  // this thread), so that it downloads and parses the weights meanwhile.
  try {
    await inference.started;
  } catch {
    return; // shown by Inference.fail
  }
  region = wasm.placementRegion();
  if (!generate(place)) {
    // A bad seed or object position from the URL: fall back to the defaults.
    ui.seed.value = "7";
    generate(null);
  }
  observationsChanged();
  // (The weights may be in already: then selectModel has described them.)
  if (!models.loaded.has(ui.model.value)) ui.status.textContent = `Loading the ${MODEL_NAMES[ui.model.value]} weights…`;
  if (await modelReady) {
    timings.ready_ms = performance.now();
    settle();
  }
}

addEventListener("error", (e) => {
  // A benign browser notice, not a failure of the page.
  if (/ResizeObserver loop/.test(e.message ?? "")) return;
  if (!fatal) failFatal(new Error(`Error: ${e.message}`));
});
addEventListener("unhandledrejection", (e) => {
  if (!fatal) failFatal(new Error(`Error: ${e.reason?.message ?? e.reason}`));
});

main();
