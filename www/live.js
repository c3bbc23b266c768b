// Live mode: the episode plays, the steps seen so far (every k-th, the observation rule) are the
// observations, and the unseen rest of the action is forecast again each time they change; each
// finished forecast's error joins the live error plot.

import { BLENDS, CHUNK, MODEL_NAMES } from "./config.js";
import { render, shownStep } from "./draw.js";
import { drawErrors } from "./error_plot.js";
import { loadModel } from "./models.js";
import { clampInt, updateObsInfo } from "./observations.js";
import { pause } from "./playback.js";
import { JOINTS } from "./plot.js";
import { cancelPrediction, observations, predict } from "./prediction.js";
import { state } from "./state.js";
import { settle, showError } from "./status.js";
import { ui } from "./ui.js";
import { cssSize } from "./views.js";

/** The observation rule: observe every `every`-th step. */
export function every() {
  return state.every;
}

/**
 * The rule's field changed (or was set from the URL): its value becomes the rule. Read only
 * then, so that a value being typed changes neither the forecasts nor the curves they join
 * (the change cancels the forecast made under the old rule).
 */
export function takeRule() {
  state.every = clampInt(ui.liveEvery.value, 1, 100);
}

/** The steps the rule has observed once `step` is reached: 0, k, 2k, … ≤ step. */
export function seenSteps(step, k = every()) {
  const steps = [];
  for (let s = 0; s <= step; s += k) steps.push(s);
  return steps;
}

/** What a forecast is made from: model, modalities and the seen steps. */
function forecastKey(steps) {
  return `${ui.model.value}|${ui.observe.value}|${steps.join(",")}`;
}

/** The step changed (playback, scrubbing): forecast again when the seen observations changed. */
export function follow(step) {
  if (state.shown?.mode === "live") forecastNow(step);
}

/**
 * Forecasts the rest of the action after the last seen observation, now: a forecast (or a model
 * comparison) still running is cancelled, never queued.
 */
export function forecastNow(step = state.step) {
  const { shown } = state;
  if (!shown || shown.mode !== "live" || state.fatal) return;
  const steps = seenSteps(step);
  const key = forecastKey(steps);
  // The forecast on screen (or coming) is already made from these observations.
  if (key === state.seenKey && state.prediction?.mode === "live") return;
  stopComparing();
  state.observed = new Set(steps);
  state.seenKey = key;
  updateObsInfo();
  const from = steps[steps.length - 1] + 1;
  document.body.dataset.seen = String(from);
  // Everything observed: the last forecast stays on screen.
  if (from >= shown.len) return render();
  // The step on screen (some steps ahead) is decoded first, alone.
  predict({ from, chunk: CHUNK, first: shownStep(step), keepEncoded: true });
}

/** The error curves of the episode on screen under the current rule and modalities. */
function curves() {
  const key = [state.episode?.digest, every(), ui.observe.value, state.shown?.len].join("|");
  if (state.curves.key !== key) state.curves = { key, byModel: new Map(), version: 0 };
  return state.curves.byModel;
}

/** Adds a forecast's error at `from` (steps seen) to `model`'s curve and redraws the plot. */
function record(model, from, error) {
  const byModel = curves();
  const points = (byModel.get(model) ?? []).filter((p) => p.from !== from);
  points.push({ from, seen: from / state.shown.len, jointRmse: error.joint_rmse, imageMse: error.image_mse });
  points.sort((a, b) => a.from - b.from);
  byModel.set(model, points);
  state.curves.version++;
  redrawErrors();
}

/** What the error plot was last drawn from: it is redrawn only when that changes. */
let errorsDrawnFrom = "";

/** Draws the error plot, the fraction of the action seen by the forecast on screen marked. */
export function redrawErrors() {
  const { shown } = state;
  if (!shown) return;
  const forecast = heldForecast();
  const now = forecast ? forecast.from / shown.len : null;
  const byModel = curves();
  const { w, h } = cssSize(ui.errorPlot);
  const key = [window.devicePixelRatio, w, h, state.curves.key, state.curves.version, now].join("|");
  if (key === errorsDrawnFrom) return;
  errorsDrawnFrom = key;
  drawErrors(ui.errorPlot, byModel, MODEL_NAMES, now);
}

/** Live mode: the last finished forecast of the sequence on screen (see `state.forecast`), or null. */
export function heldForecast() {
  const { shown, forecast } = state;
  return shown?.mode === "live" && forecast?.sequence === shown ? forecast : null;
}

/** The benchmark's error of a forecast of the steps from `from` on (RGB bytes, joints). */
function forecastError(from, mean, jointMean) {
  const { shown } = state;
  const px = shown.size * shown.size * 3;
  return state.wasm.forecastError(shown.frames.subarray(from * px), shown.joints.subarray(from * JOINTS), mean, jointMean);
}

/** A live forecast finished (prediction.js): its error, for the plot and for automation. */
export function forecastDone(p) {
  // Timed to its last chunk (p.doneAt): its error below is for the plot.
  const px = p.size * p.size * 3;
  const error = forecastError(p.from, p.mean.subarray(p.from * px), p.jointMean.subarray(p.from * JOINTS));
  record(p.model, p.from, error);
  state.timings.live.push({
    model: p.model,
    from: p.from,
    steps: p.len - p.from,
    observed: p.observed,
    // From the observation coming in: to the first chunk drawn, and to the whole forecast.
    first_chunk_ms: p.firstAt - p.asked,
    total_ms: p.doneAt - p.asked,
    // Of which the slowest worker's whole time, and its encoding of the observations it
    // lacked (`encoded` of them); the rest is the page's (messages, drawing).
    worker_ms: p.workerMs,
    encode_ms: p.encodeMs,
    encoded: p.encoded,
    joint_rmse: error.joint_rmse,
    image_mse: error.image_mse,
  });
}

/** Stops a running comparison (its request is cancelled). */
function stopComparing() {
  if (!state.comparing) return;
  state.comparing.stop();
  state.comparing = null;
  ui.compare.textContent = "compare models";
  ui.compareInfo.textContent = "";
}

/**
 * Every model's whole curve on this episode: the forecast from each observation point of the
 * rule, one model after another, without drawing the forecasts. Playback pauses; a step change
 * or a new episode stops it.
 */
export async function compareModels() {
  if (state.comparing) return stopComparing();
  const { shown } = state;
  if (!shown || shown.mode !== "live") return;
  pause();
  cancelPrediction();
  let stopped = false;
  let running = null;
  const run = {
    stop: () => {
      stopped = true;
      running?.cancel();
    },
  };
  state.comparing = run;
  ui.compare.textContent = "stop comparing";
  const points = seenSteps(shown.len - 2);
  const blend = BLENDS[ui.observe.value];
  const px = shown.size * shown.size * 3;
  try {
    for (const model of [...ui.model.options].map((o) => o.value)) {
      await loadModel(model);
      for (const [i, last] of points.entries()) {
        if (stopped) return;
        ui.compareInfo.textContent = `${MODEL_NAMES[model]}: ${i + 1} / ${points.length}`;
        const from = last + 1;
        const n = shown.len - from;
        const mean = new Uint8Array(n * px);
        const jointMean = new Float32Array(n * JOINTS);
        const steps = seenSteps(last);
        const { frames, joints, times } = observations(steps);
        const targets = Float32Array.from(shown.times.subarray(from));
        const chunk = Math.ceil(n / state.inference.count);
        const request = { model, frames, joints, times, targets, blend, chunk, delay: 0, source: shown.id, steps };
        running = state.inference.predict(request, (c) => {
          mean.set(c.mean, c.start * px);
          jointMean.set(c.jointMean, c.start * JOINTS);
        });
        const reply = await running.done;
        if (stopped || reply.type !== "done") return;
        record(model, from, forecastError(from, mean, jointMean));
      }
    }
  } catch (err) {
    if (!stopped) showError(err);
  } finally {
    if (state.comparing === run) {
      state.comparing = null;
      ui.compare.textContent = "compare models";
      ui.compareInfo.textContent = "";
      document.body.dataset.compared = String(Number(document.body.dataset.compared ?? 0) + 1);
      forecastNow();
      settle();
    }
  }
}
