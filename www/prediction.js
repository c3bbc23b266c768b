// Predictions of the shown sequence. Every one the page makes — Predict, live mode's forecasts,
// the model comparison — is made by `prediction` and asked of the workers by `ask`, which stores
// its chunks as they come; `predict` makes the one on screen, draws it and times it.

import { BLENDS, CHUNK, CHUNK_DELAY, MODEL_NAMES, MODELS } from "./config.js";
import { firstDrawn, render, renderSoon, shownStep } from "./draw.js";
import { emit } from "./events.js";
import { log, predictionFinished, progress, timings } from "./hooks.js";
import { jointMismatch, loadModel, refuse, selectModel } from "./models.js";
import { observedSteps } from "./observations.js";
import { state } from "./state.js";
import { setState, settle, showError } from "./status.js";
import { ui } from "./ui.js";

export function cancelPrediction() {
  if (state.prediction && !state.prediction.complete) state.prediction.cancel?.();
  state.prediction = null;
  ui.predLabel.textContent = "";
  // Imitate mode: no performance is current any more (main.js connects it).
  emit("dropped");
}

/**
 * The frames, joints (`shown.jointCount` values a step) and time stamps of sequence `shown` at
 * `steps`, as the model takes them.
 */
export function observations(steps, shown = state.shown) {
  const px = shown.size * shown.size * 3;
  const d = shown.jointCount;
  const frames = new Uint8Array(steps.length * px);
  const joints = new Float32Array(steps.length * d);
  const times = new Float32Array(steps.length);
  steps.forEach((k, i) => {
    frames.set(shown.frames.subarray(k * px, (k + 1) * px), i * px);
    joints.set(shown.joints.subarray(k * d, (k + 1) * d), i * d);
    times[i] = shown.times[k];
  });
  return { frames, joints, times };
}

/** Numbers the predictions (their `id` in the event log). */
let made = 0;

/**
 * A prediction of the shown sequence's steps from `from` on (every step by default; live mode:
 * the unseen rest) by `model` from the observed `steps` under the modalities `observe`, in
 * chunks of `chunk` steps; `first`: a step decoded alone before the others. Not asked yet (`ask`).
 * Its joints have the sequence's `jointCount` values a step (D: the model's, or `ask` refuses it).
 */
export function prediction({ model, observe, steps, from = 0, chunk = CHUNK, first = null, shown = state.shown }) {
  const { len, size, jointCount } = shown;
  const px = size * size;
  // The steps in the order they are decoded (`first` first).
  const order = Int32Array.from({ length: len - from }, (_, i) => from + i);
  if (first !== null && first > from && first < len) order.copyWithin(1, 0, first - from).fill(first, 0, 1);
  return {
    id: ++made,
    model,
    mode: shown.mode,
    observe,
    len,
    from,
    chunk,
    first,
    order,
    size,
    observed: steps.length,
    steps,
    /** The sequence predicted (live mode: the forecast on screen is held while it is shown). */
    sequence: shown,
    done: new Uint8Array(len),
    count: 0,
    mean: new Uint8Array(len * px * 3),
    sigma: new Float32Array(len * px),
    jointCount,
    jointMean: new Float32Array(len * jointCount),
    jointSigma: new Float32Array(len * jointCount),
    maxSigma: 0,
    complete: false,
    /** When it was asked for (live mode: when the observation came in). */
    asked: performance.now(),
    chunks: [],
  };
}

/**
 * Asks the workers for prediction `p`: each chunk is stored in it as it comes, then passed to
 * `onChunk`. `keepEncoded`: the workers keep the observations encoded per step of the sequence
 * and encode only the new ones; `delay`: a pause between chunks (`?chunkDelay`). Sets
 * `p.cancel`; resolves with the workers' reply ({type: "done" | "cancelled", ms, encodeMs, …}).
 */
export function ask(p, { keepEncoded = false, delay = CHUNK_DELAY, onChunk = () => {} } = {}) {
  const { model, observe, first, steps, sequence } = p;
  // A model of another number of joint values a step cannot read these (the callers check first).
  const count = state.modelInfo.get(model)?.jointCount;
  if (count !== undefined && count !== p.jointCount) {
    return Promise.reject(new Error(`The ${MODEL_NAMES[model]} model reads ${count} joint values a step, the sequence has ${p.jointCount}.`));
  }
  const { frames, joints, times } = observations(steps, sequence);
  // The targets: the time stamps of the steps in decoding order (permuted for p).
  const targets = Float32Array.from(p.order, (k) => sequence.times[k]);
  const request = { model, frames, joints, times, targets, blend: BLENDS[observe], chunk: p.chunk, delay, firstAlone: first !== null };
  if (keepEncoded) Object.assign(request, { source: sequence.id, steps });
  p.start = performance.now();
  log("start", { id: p.id, mode: p.mode, model, from: p.from });
  const run = state.inference.predict(request, (c) => {
    store(p, c);
    onChunk(c);
  });
  // The event log says how each prediction ended, once.
  let ended = false;
  const end = (how) => {
    if (ended) return false;
    ended = true;
    log(how, { id: p.id, from: p.from });
    return true;
  };
  p.cancel = () => end("cancelled") && run.cancel();
  return run.done.then(
    (reply) => {
      if (reply.type === "done") end("finished");
      return reply;
    },
    (err) => {
      end("failed");
      throw err;
    },
  );
}

/** A chunk of targets `c.start`… (indices into `p.order`) came: its steps are kept in `p`. */
function store(p, c) {
  const px = p.size * p.size;
  const d = p.jointCount;
  for (let i = 0; i < c.count; i++) {
    const k = p.order[c.start + i];
    p.mean.set(c.mean.subarray(i * px * 3, (i + 1) * px * 3), k * px * 3);
    p.sigma.set(c.sigma.subarray(i * px, (i + 1) * px), k * px);
    p.jointMean.set(c.jointMean.subarray(i * d, (i + 1) * d), k * d);
    p.jointSigma.set(c.jointSigma.subarray(i * d, (i + 1) * d), k * d);
    p.done[k] = 1;
  }
  p.maxSigma = Math.max(p.maxSigma, c.maxSigma);
  p.count += c.count;
  p.chunks.push(c.ms);
  log("chunk", { id: p.id, count: c.count });
}

/**
 * Predicts the steps of the shown sequence from `from` on (see `prediction`) from the observed
 * ones, as the prediction on screen, drawing its chunks as they come (at most once an animation
 * frame). Live mode's options: `first`, the step on screen, drawn at once, the rest drawn when
 * complete; `keepEncoded` (see `ask`).
 */
export async function predict({ from = 0, chunk = CHUNK, first = null, keepEncoded = false } = {}) {
  if (state.fatal || !state.episode || !state.shown) return;
  const steps = observedSteps();
  if (!steps.length) {
    showError("Choose at least one observation: click frames on the timeline, or use “first k” / “random k”.");
    return;
  }
  state.live = true;
  cancelPrediction();
  // The chosen model reads another number of joint values a step than the sequence has: it
  // says so instead (the count is known once it is loaded: selectModel checks then).
  const why = jointMismatch();
  if (why) {
    render();
    refuse(why);
    return;
  }
  const p = prediction({ model: ui.model.value, observe: ui.observe.value, steps, from, chunk, first });
  state.prediction = p;
  setState("predicting");
  ui.predLabel.textContent = "predicting…";
  // A loaded model is asked at once: awaiting it would post the request only after the
  // caller's drawing (a live forecast's latency). selectModel still updates the status line.
  if (state.loadedModels.has(p.model)) {
    selectModel();
  } else if (!(await selectModel())) {
    if (state.prediction === p) state.prediction = null;
    return;
  }
  if (state.prediction !== p) return;
  setState("predicting");
  progress(0);
  let reply;
  try {
    reply = await ask(p, { keepEncoded, onChunk: (c) => received(p, c) });
  } catch (err) {
    if (state.prediction === p) {
      state.prediction = null;
      render();
      showError(err);
    }
    return;
  }
  if (reply.type === "cancelled" || state.prediction !== p) return;
  finish(p, reply);
}

/** A chunk of the prediction on screen came (stored by `ask`): it is drawn. */
function received(p, c) {
  if (state.prediction !== p) return;
  progress(p.count);
  if (p.mode !== "live") {
    const steps = p.len - p.from;
    ui.predLabel.textContent = `predicting… ${p.count} / ${steps}`;
    ui.timing.textContent = `${p.count} / ${steps} steps · ${Math.round(performance.now() - p.start)} ms`;
    renderSoon();
    return;
  }
  // A live forecast (about 100 ms) shows no progress: its frames are drawn at its first chunk
  // and the step on screen (`first`, decoded alone first), everything when complete (finish).
  const at = shownStep();
  let shown = false;
  for (let i = 0; i < c.count; i++) shown ||= p.order[c.start + i] === at;
  if (p.count === c.count || shown) renderSoon({ framesOnly: true });
}

/** A prediction is complete: its timings, for the page and for automation. */
function finish(p, reply) {
  const { model, mode, observe, from } = p;
  const len = p.len - from;
  p.complete = true;
  p.doneAt = performance.now();
  if (mode === "live") state.forecast = p;
  p.totalMs = p.doneAt - p.start;
  // Every chunk came before an animation frame drew one: the last ones are drawn below.
  firstDrawn(p);
  p.encodeMs = reply.encodeMs;
  p.workerMs = reply.ms;
  p.encoded = reply.encoded;
  // Live mode: its error joins the plot; imitate mode: the arm performs the joints imagined
  // (main.js connects them). Before the counter below moves.
  emit("predicted", p);
  // A counter that automation can wait on: it changes with every finished prediction.
  predictionFinished();
  timings.prediction = {
    model,
    mode,
    observe,
    observed: p.observed,
    steps: len,
    from,
    total_ms: p.totalMs,
    per_frame_ms: p.totalMs / len,
    first_chunk_ms: p.firstMs,
    encode_ms: reply.encodeMs,
    chunk: p.chunk,
    workers: reply.workers,
  };
  ui.predLabel.textContent = "";
  ui.timing.textContent =
    `${len} steps in ${Math.round(p.totalMs)} ms (${(p.totalMs / len).toFixed(1)} ms per frame) · ` +
    `first ${p.first !== null ? 1 : Math.min(p.chunk, len)} after ${Math.round(p.firstMs)} ms · ${reply.workers} worker${reply.workers > 1 ? "s" : ""}`;
  ui.timing.title = `${MODEL_NAMES[model]}, mode ${mode}, ${observe}, ${p.observed} observed steps; encoding ${Math.round(reply.encodeMs)} ms`;
  render();
  // A performance that failed keeps its message up (state error); the prediction stays drawn.
  if (mode !== "imitate" || state.imagined) settle();
}

/** For bench/page.mjs: times `n` target steps (evenly spaced phases) with model `model` (an id of
 * MODELS: attn, dmbn, pte, pte-aug) on the current observations, through the same worker path and
 * chunking as the page, without drawing. */
export async function timePrediction(n, model = ui.model.value, chunk = CHUNK) {
  if (!Object.hasOwn(MODELS, model)) {
    throw new Error(`timePrediction: unknown model ${JSON.stringify(model)} (one of ${Object.keys(MODELS).join(", ")})`);
  }
  await loadModel(model);
  const why = jointMismatch(model);
  if (why) throw new Error(`timePrediction: ${why}`);
  const { frames, joints, times } = observations(observedSteps());
  const targets = Float32Array.from({ length: n }, (_, i) => (n > 1 ? i / (n - 1) : 0.5));
  const t0 = performance.now();
  let first = null;
  const reply = await state.inference.predict(
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
