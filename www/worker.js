// Inference worker: loads the model files and runs their predictions (the attentive model, DMBN,
// DMBN-PTE, DMBN-PTE + time warps) in WebAssembly, off the page's main thread. The observations
// are encoded once, then the target times are decoded in chunks whose results go back as they
// come, typed arrays transferred (not copied), so the page fills the predicted sequence in
// progressively.
//
// A predict that names its sequence (`source`) and the step of each observation (`steps`) goes
// through the model's encoded steps (encoded_steps.js): each step is encoded once
// (Model.encodeContexts) and kept (at most about 128 per model), the set observed is cut from
// them and aggregated with the blend (Model.represent), so a live forecast encodes only its new
// observation. Without them the observations are encoded together (Model.encode), kept nowhere.
//
// `model` is the page's model id (attn, dmbn, pte, pte-aug): it keys the loaded files; what a
// file holds is `fileKind` (Model.kind: "attn", "dmbn" or "pte").
// Messages in (all carry an `id`; replies echo it):
//   {type: "init", module}                  the compiled WebAssembly.Module from the page
//   {type: "load", model, url}              fetch and parse a model file (kept for later)
//   {type: "predict", model, frames, joints, times, targets, blend, chunk, delay,
//    source?, steps?, firstAlone?}          a new predict cancels the running one; `source`
//                                           names the sequence, `steps` the step of each
//                                           observation; `firstAlone`: the first target is
//                                           decoded (and sent) alone, before its chunk's rest
//   {type: "sample", model, frames, joints, times, targets, blend, samples, seed,
//    source?, steps?}                       S sampled futures at `targets` (Model.sampleWithFrames),
//                                           through the encoded steps as predict's
//   {type: "cancel", target}                stop prediction `target` if it is running
//   {type: "forget"}                        drop every model's encoded steps
// Messages out:
//   {type: "inited", id}
//   {type: "loaded", id, model, fileKind, imageSize, jointCount, jointNames, normalization,
//    bytes, fetchMs, parseMs}             jointCount: D, the joint values a step it reads and
//                                          predicts (frames, joints D a step; its chunks T × D)
//   {type: "chunk", id, start, count, mean, sigma, maxSigma, jointMean, jointSigma, ms}
//   {type: "done", id, ms, encodeMs, encoded, steps}   encoded: the observations encoded
//   {type: "sampled", id, joints, frames, ms, encodeMs}  joints S × targets × D, frames the
//                                      futures' mean frames at the last target (S × S' × S' × 3)
//   {type: "forgotten", id}
//   {type: "error", id, message}       also the answer to a malformed message (fields checked
//                                      against FIELDS below); the worker keeps serving

import { EncodedSteps } from "./encoded_steps.js";

let wasm = null;
let initWasm;
const wasmReady = new Promise((resolve) => {
  initWasm = resolve;
});

/** model id → {url, promise of {model, url, info, encoded}}: each file is fetched and parsed once. */
const models = new Map();
/** Id of the prediction allowed to run; any other running loop stops at its next chunk. */
let current = null;

const post = (msg, transfer = []) => self.postMessage(msg, transfer);

self.onmessage = async (e) => {
  const msg = e.data;
  const id = msg?.id;
  try {
    const problem = malformed(msg);
    if (problem) throw new Error(`The inference worker got a malformed message: ${problem}.`);
    switch (msg.type) {
      case "init":
        await init(msg.module);
        post({ type: "inited", id: msg.id });
        break;
      case "load": {
        const { info } = await load(msg.model, msg.url);
        post({ type: "loaded", id: msg.id, ...info });
        break;
      }
      case "predict":
        current = msg.id;
        await predict(msg);
        break;
      case "sample":
        await sample(msg);
        break;
      case "cancel":
        if (current === msg.target) current = null;
        break;
      case "forget":
        await forget();
        post({ type: "forgotten", id: msg.id });
        break;
    }
  } catch (err) {
    post({ type: "error", id, message: err instanceof Error ? err.message : String(err) });
  }
};

/** A short description of any value, for a message. */
function describe(value) {
  if (typeof value === "string") return value.length > 40 ? `a string of ${value.length} characters` : JSON.stringify(value);
  if (value === null || typeof value !== "object") return String(value);
  if (Array.isArray(value)) return `an array of ${value.length} items`;
  return `an object (${value.constructor?.name ?? "no class"})`;
}

const isString = [(v) => typeof v === "string", "a string"];
const isIndex = [(v) => Number.isSafeInteger(v) && v >= 0, "a non-negative integer"];
const optional = ([ok, expected]) => [(v) => v == null || ok(v), `${expected} or absent`];
const typed = (Type) => [(v) => v instanceof Type, `a ${Type.name}`];
/** What `predict` and `sample` both carry: the model, the observations, the targets, the blend. */
const OBSERVED = {
  model: isString,
  frames: typed(Uint8Array),
  joints: typed(Float32Array),
  times: typed(Float32Array),
  targets: typed(Float32Array),
  blend: [(v) => typeof v === "number" && v >= 0 && v <= 1, "a number in [0, 1]"],
};
/** Each message type's fields and what they must be (as the page sends them; see the top). */
const FIELDS = {
  init: { module: [(v) => v instanceof WebAssembly.Module, "a WebAssembly.Module"] },
  load: { model: isString, url: isString },
  predict: {
    ...OBSERVED,
    chunk: [(v) => Number.isSafeInteger(v) && v >= 1, "a positive integer"],
    delay: optional([(v) => typeof v === "number" && v >= 0 && v < 60_000, "a delay in ms"]),
    source: optional([(v) => typeof v === "string" || Number.isFinite(v), "a string or number"]),
    steps: optional([(v) => Array.isArray(v) && v.every(isIndex[0]), "an array of step indices"]),
    firstAlone: optional([(v) => typeof v === "boolean", "a boolean"]),
  },
  sample: {
    ...OBSERVED,
    samples: [(v) => Number.isSafeInteger(v) && v >= 1 && v <= 256, "an integer from 1 to 256"],
    seed: isIndex,
    source: optional([(v) => typeof v === "string" || Number.isFinite(v), "a string or number"]),
    steps: optional([(v) => Array.isArray(v) && v.every(isIndex[0]), "an array of step indices"]),
  },
  cancel: { target: isIndex },
  forget: {},
};

/** Why `msg` is not a message this worker takes (each field it reads checked), or null. */
function malformed(msg) {
  if (msg === null || typeof msg !== "object") return `expected an object, got ${describe(msg)}`;
  const fields = Object.hasOwn(FIELDS, msg.type) ? FIELDS[msg.type] : null;
  if (!fields) return `unknown type ${describe(msg.type)}: expected ${Object.keys(FIELDS).join(", ")}`;
  for (const [field, [ok, expected]] of Object.entries(fields)) {
    if (!ok(msg[field])) return `${msg.type}: ${field} must be ${expected}, got ${describe(msg[field])}`;
  }
  return null;
}

async function init(module) {
  try {
    wasm = await import("../pkg/dmbn.js");
    await wasm.default({ module_or_path: module });
    initWasm();
  } catch (err) {
    throw new Error(`The inference worker could not start WebAssembly: ${err.message ?? err}`);
  }
}

function load(id, url) {
  const cached = models.get(id);
  if (cached && cached.url === url) return cached.promise;
  const promise = fetchModel(id, url);
  models.set(id, { url, promise });
  // A failed load is not cached: the next request tries again (the file may have appeared).
  promise.catch(() => {
    if (models.get(id)?.promise === promise) models.delete(id);
  });
  return promise;
}

/** The page's model ids, in words (as MODELS in config.js). */
const NAMES = {
  attn: "Attentive (DMBN-PTE + attention)",
  dmbn: "DMBN",
  pte: "DMBN-PTE",
  "pte-aug": "DMBN-PTE + time warps",
  "attn-2020": "Attentive · original data",
  "pte-2020": "DMBN-PTE · original data",
  "dmbn-2020": "DMBN · original data",
  "pte-aug-2020": "DMBN-PTE + time warps · original data",
};

async function fetchModel(id, url) {
  const name = `the ${NAMES[id] ?? id} weights`;
  const t0 = performance.now();
  let response;
  try {
    response = await fetch(url);
  } catch (err) {
    throw new Error(`Could not download ${name} from ${url}: ${err.message ?? err}.`);
  }
  if (!response.ok) {
    const hint = response.status === 404 ? " The file is missing: train the model or restore assets/models/." : "";
    throw new Error(`Could not download ${name} from ${url}: HTTP ${response.status} ${response.statusText}.${hint}`);
  }
  const bytes = new Uint8Array(await response.arrayBuffer());
  const t1 = performance.now();
  await wasmReady;
  let model;
  try {
    model = wasm.Model.fromBytes(bytes);
  } catch (err) {
    throw new Error(`${name[0].toUpperCase()}${name.slice(1)} at ${url} are corrupt or not a model file: ${err.message ?? err}`);
  }
  const info = {
    model: id,
    fileKind: model.kind,
    imageSize: model.imageSize,
    jointCount: model.jointCount,
    jointNames: model.jointNames,
    normalization: model.normalization,
    bytes: bytes.length,
    fetchMs: t1 - t0,
    parseMs: performance.now() - t1,
  };
  return { model, url, info, encoded: new EncodedSteps(model) };
}

/** Drops the encoded steps of every model loaded. */
async function forget() {
  const loaded = await Promise.allSettled([...models.values()].map((m) => m.promise));
  for (const r of loaded) if (r.status === "fulfilled") r.value.encoded.forget();
}

/** Lets queued messages (a newer prediction, a cancel) in between two chunks. */
function yieldToMessages(delay) {
  return new Promise((resolve) => setTimeout(resolve, delay || 0));
}

/** The pieces of `n` targets decoded one after another: chunks of `chunk`, the first target alone first with `firstAlone`. */
function pieces(n, chunk, firstAlone) {
  const out = [];
  for (let start = 0; start < n; start += chunk) {
    const end = Math.min(n, start + chunk);
    if (start === 0 && firstAlone && end > 1) out.push([0, 1], [1, end]);
    else out.push([start, end]);
  }
  return out;
}

/** What the decoders take for the message's observations, and how many were encoded for it. */
function encode(msg, { model, encoded }) {
  const { frames, joints, times, blend, source, steps } = msg;
  if (source == null || !steps) return { encoding: model.encode(frames, joints, times, blend), count: times.length };
  const { contexts, encoded: count } = encoded.contextsOf(source, steps, frames, joints, times);
  try {
    return { encoding: model.represent(contexts, blend), count };
  } finally {
    contexts.free();
  }
}

/** The message's observations encoded one by one (a Contexts, which the caller frees): kept ones with a source. */
function contextsOf(msg, { model, encoded }) {
  const { frames, joints, times, source, steps } = msg;
  if (source == null || !steps) return model.encodeContexts(frames, joints, times);
  return encoded.contextsOf(source, steps, frames, joints, times).contexts;
}

/** S futures of the observations, drawn at once (one wasm call: it cannot be cancelled midway). */
async function sample(msg) {
  const entry = models.get(msg.model);
  if (!entry) throw new Error(`the ${NAMES[msg.model] ?? msg.model} model is not loaded`);
  const loaded = await entry.promise;
  const t0 = performance.now();
  const contexts = contextsOf(msg, loaded);
  const encodeMs = performance.now() - t0;
  let out;
  try {
    out = loaded.model.sampleWithFrames(contexts, msg.targets, msg.blend, msg.samples, msg.seed);
  } finally {
    contexts.free();
  }
  const { joints, frames } = out;
  post({ type: "sampled", id: msg.id, joints, frames, ms: performance.now() - t0, encodeMs }, [joints.buffer, frames.buffer]);
}

async function predict(msg) {
  const { id, targets } = msg;
  const entry = models.get(msg.model);
  if (!entry) throw new Error(`the ${NAMES[msg.model] ?? msg.model} model is not loaded`);
  const loaded = await entry.promise;
  if (current !== id) return;
  const { model } = loaded;
  const chunk = Math.max(1, msg.chunk | 0);
  const t0 = performance.now();
  // The observations are encoded once (only the new ones, with a source); each chunk of
  // targets is then only decoded.
  const { encoding, count } = encode(msg, loaded);
  const encodeMs = performance.now() - t0;
  try {
    for (const [start, end] of pieces(targets.length, chunk, msg.firstAlone)) {
      if (current !== id) return;
      const c0 = start === 0 ? t0 : performance.now();
      // A Prediction, as Model.predict returns: copied out (RGB bytes, σ per pixel), then freed.
      const p = model.decode(encoding, targets.subarray(start, end));
      const out = { start, count: p.len, mean: p.meanFrames(), sigma: p.pixelSigma(), maxSigma: p.maxImageSigma, jointMean: p.jointMean(), jointSigma: p.jointSigma() };
      p.free();
      out.ms = performance.now() - c0;
      post({ type: "chunk", id, ...out }, [out.mean.buffer, out.sigma.buffer, out.jointMean.buffer, out.jointSigma.buffer]);
      // (No pause between the first target and the rest of its chunk.)
      await yieldToMessages(start === 0 && end === 1 ? 0 : msg.delay);
    }
  } finally {
    encoding.free();
  }
  if (current === id) {
    current = null;
    post({ type: "done", id, ms: performance.now() - t0, encodeMs, encoded: count, steps: targets.length });
  }
}
