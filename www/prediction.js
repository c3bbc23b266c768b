// Predicting the shown sequence: the request, its chunks as they come, cancelling, timings.

import { BLENDS, CHUNK, CHUNK_DELAY, MODEL_NAMES, MODELS } from "./config.js";
import { render, renderSoon, shownStep } from "./draw.js";
import { clearPerformances, performImagined } from "./imitate.js";
import { forecastDone, forecastNow } from "./live.js";
import { loadModel, selectModel } from "./models.js";
import { observedSteps } from "./observations.js";
import { JOINTS } from "./plot.js";
import { state } from "./state.js";
import { setState, settle, showError } from "./status.js";
import { ui } from "./ui.js";

export function cancelPrediction() {
  if (state.prediction && !state.prediction.complete) state.prediction.cancel?.();
  state.prediction = null;
  ui.predLabel.textContent = "";
  clearPerformances();
}

/** Settings changed: predict again when live, otherwise drop the outdated prediction. */
export function invalidate() {
  if (state.shown?.mode === "live") {
    forecastNow();
    return;
  }
  if (state.live && state.episode && state.observed.size) {
    predict();
  } else {
    cancelPrediction();
    render();
    settle();
  }
}

/** The shown sequence's frames, joints and time stamps at `steps`, as the model takes them. */
export function observations(steps) {
  const { shown } = state;
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

/**
 * Predicts the steps of the shown sequence from `from` on (every step by default; live mode's
 * forecast: the unseen rest) from the observed ones, drawing the chunks of `chunk` steps as they
 * come (at most once an animation frame). Live mode's options: `first`, a step decoded alone
 * before the others (the one on screen) and drawn at once, the rest drawn when complete;
 * `keepEncoded`, the workers keep the observations encoded per step of the shown sequence and
 * encode only the new ones.
 */
export async function predict({ from = 0, chunk = CHUNK, first = null, keepEncoded = false } = {}) {
  const { shown } = state;
  if (state.fatal || !state.episode || !shown) return;
  const steps = observedSteps();
  if (!steps.length) {
    showError("Choose at least one observation: click frames on the timeline, or use “first k” / “random k”.");
    return;
  }
  state.live = true;
  cancelPrediction();
  const model = ui.model.value;
  const observe = ui.observe.value;
  const size = shown.size;
  const px = size * size;
  const { frames, joints, times } = observations(steps);
  const len = shown.len;
  // The steps in the order they are decoded (`first` first), and their time stamps (permuted
  // for p): the targets.
  const order = Int32Array.from({ length: len - from }, (_, i) => from + i);
  if (first !== null && first > from && first < len) order.copyWithin(1, 0, first - from).fill(first, 0, 1);
  const targets = Float32Array.from(order, (k) => shown.times[k]);
  const p = {
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
    jointMean: new Float32Array(len * JOINTS),
    jointSigma: new Float32Array(len * JOINTS),
    maxSigma: 0,
    complete: false,
    /** When it was asked for (live mode: when the observation came in). */
    asked: performance.now(),
    chunks: [],
  };
  state.prediction = p;
  setState("predicting");
  ui.predLabel.textContent = "predicting…";
  // A loaded model is asked at once: awaiting it would post the request only after the
  // caller's drawing (a live forecast's latency). selectModel still updates the status line.
  if (state.loadedModels.has(model)) {
    selectModel();
  } else if (!(await selectModel())) {
    if (state.prediction === p) state.prediction = null;
    return;
  }
  if (state.prediction !== p) return;
  setState("predicting");
  document.body.dataset.progress = "0";
  p.start = performance.now();
  const run = state.inference.predict(
    { model, frames, joints, times, targets, blend: BLENDS[observe], chunk, delay: CHUNK_DELAY, firstAlone: first !== null, ...(keepEncoded && { source: shown.id, steps }) },
    (c) => receiveChunk(p, c),
  );
  p.cancel = run.cancel;
  let reply;
  try {
    reply = await run.done;
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

/** A chunk of targets `c.start`… (indices into `p.order`) came: its steps are kept and drawn. */
function receiveChunk(p, c) {
  if (state.prediction !== p) return;
  const px = p.size * p.size;
  let shown = false;
  const at = shownStep();
  for (let i = 0; i < c.count; i++) {
    const k = p.order[c.start + i];
    p.mean.set(c.mean.subarray(i * px * 3, (i + 1) * px * 3), k * px * 3);
    p.sigma.set(c.sigma.subarray(i * px, (i + 1) * px), k * px);
    p.jointMean.set(c.jointMean.subarray(i * JOINTS, (i + 1) * JOINTS), k * JOINTS);
    p.jointSigma.set(c.jointSigma.subarray(i * JOINTS, (i + 1) * JOINTS), k * JOINTS);
    p.done[k] = 1;
    shown ||= k === at;
  }
  p.maxSigma = Math.max(p.maxSigma, c.maxSigma);
  p.count += c.count;
  p.chunks.push(c.ms);
  document.body.dataset.progress = String(p.count);
  if (p.mode !== "live") {
    const steps = p.len - p.from;
    ui.predLabel.textContent = `predicting… ${p.count} / ${steps}`;
    ui.timing.textContent = `${p.count} / ${steps} steps · ${Math.round(performance.now() - p.start)} ms`;
    renderSoon();
    return;
  }
  // A live forecast (about 100 ms) shows no progress: its frames are drawn at its first chunk
  // and the step on screen (`first`, decoded alone first), everything when complete (finish).
  if (p.count === c.count || shown) renderSoon({ framesOnly: true });
}

/** The prediction's first steps are drawn (draw.js): when, for its timings. */
export function firstDrawn(p) {
  if (p.firstAt !== undefined) return;
  p.firstAt = performance.now();
  p.firstMs = p.firstAt - p.start;
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
  if (mode === "live") forecastDone(p);
  // Imitate mode: the arm performs the joints imagined (before the counter below moves).
  if (mode === "imitate") performImagined(p);
  // A counter that automation can wait on: it changes with every finished prediction.
  document.body.dataset.predictions = String(Number(document.body.dataset.predictions ?? 0) + 1);
  state.timings.prediction = {
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
