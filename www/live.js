// Live mode: the episode plays, the steps seen so far (every k-th, the observation rule) are the
// observations, and the unseen rest of the action is forecast again each time they change; each
// finished forecast's error joins the live error plot. Comparing the models makes the same
// forecasts (prediction.js) for every model and observation point, without drawing them.

import { CHUNK, MODEL_NAMES } from "./config.js";
import { render, shownStep } from "./draw.js";
import { curves, redrawErrors } from "./error_plot.js";
import { comparisonEnded, seen, timings } from "./hooks.js";
import { jointMismatch, loadModel } from "./models.js";
import { clampInt, updateObsInfo } from "./observations.js";
import { pause } from "./playback.js";
import { ask, cancelPrediction, predict, prediction } from "./prediction.js";
import { state } from "./state.js";
import { settle, showError } from "./status.js";
import { ui } from "./ui.js";

/**
 * The rule's field changed (or was set from the URL): its value becomes the rule. Read only
 * then, so that a value being typed changes neither the forecasts nor the curves they join
 * (the change cancels the forecast made under the old rule).
 */
export function takeRule() {
  state.every = clampInt(ui.liveEvery.value, 1, 100);
}

/** The steps the rule has observed once `step` is reached: 0, k, 2k, … ≤ step. */
export function seenSteps(step, k = state.every) {
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
  seen(from);
  // Everything observed: the last forecast stays on screen.
  if (from >= shown.len) return render();
  // The step on screen (some steps ahead) is decoded first, alone.
  predict({ from, chunk: CHUNK, first: shownStep(step), keepEncoded: true });
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

/** The benchmark's error of forecast `p` over the steps it predicted (RGB bytes, joints: D a step). */
function forecastError(p) {
  const { sequence: shown, from, jointCount: d } = p;
  const px = shown.size * shown.size * 3;
  const truth = [shown.frames.subarray(from * px), shown.joints.subarray(from * d)];
  return state.wasm.forecastError(...truth, p.mean.subarray(from * px), p.jointMean.subarray(from * d), d);
}

/** A live forecast finished (prediction.js, through main.js): its error, for the plot and for automation. */
export function forecastDone(p) {
  // Timed to its last chunk (p.doneAt): its error below is for the plot.
  const error = forecastError(p);
  record(p.model, p.from, error);
  timings.live.push({
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
 * rule, one model after another, made as live mode makes them (prediction.js) but not drawn.
 * Playback pauses; a step change or a new episode stops it.
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
  const observe = ui.observe.value;
  try {
    for (const model of [...ui.model.options].map((o) => o.value)) {
      await loadModel(model);
      // A model of another number of joint values a step has no curve on this episode.
      if (jointMismatch(model)) continue;
      for (const [i, last] of points.entries()) {
        if (stopped) return;
        ui.compareInfo.textContent = `${MODEL_NAMES[model]}: ${i + 1} / ${points.length}`;
        const from = last + 1;
        // Nothing waits on the first step: the rest spread evenly over the workers.
        const chunk = Math.ceil((shown.len - from) / state.inference.count);
        running = prediction({ model, observe, steps: seenSteps(last), from, chunk, shown });
        const reply = await ask(running, { keepEncoded: true, delay: 0 });
        if (stopped || reply.type !== "done") return;
        record(model, from, forecastError(running));
      }
    }
  } catch (err) {
    if (!stopped) showError(err);
  } finally {
    if (state.comparing === run) {
      state.comparing = null;
      ui.compare.textContent = "compare models";
      ui.compareInfo.textContent = "";
      comparisonEnded();
      forecastNow();
      settle();
    }
  }
}
