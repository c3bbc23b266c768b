// "Imagine S futures" (live and imitate modes): once a prediction is complete, a worker samples S
// futures of the same observations (Model.sampleWithFrames: `dmbn sample`'s sampling, seeded),
// which the joint panels draw as a fan of thin lines and the strip as each future's final frame;
// in imitate mode the arm performs each future too, and the strip gives its outcome.
//
// One sampling runs at a time (a worker is busy with it for a few hundred ms): a prediction
// finished meanwhile waits, and only the latest one on screen is sampled next, so live mode's
// forecasts keep their workers while it plays.

import { BLENDS } from "./config.js";
import { render } from "./draw.js";
import { futuresImagined, log } from "./hooks.js";
import { performFuture, showFuture } from "./imitate.js";
import { loadModel } from "./models.js";
import { clampInt, observedSteps } from "./observations.js";
import { observations } from "./prediction.js";
import { heldForecast, state } from "./state.js";
import { ui } from "./ui.js";

/** The most futures the control offers. */
const MAX_FUTURES = 32;

/** The control's settings: {samples (0: off), seed}. */
function futureSettings() {
  return { samples: clampInt(ui.futures.value, 0, MAX_FUTURES), seed: clampInt(ui.futuresSeed.value, 0, 2 ** 31 - 1) };
}

/** The prediction whose futures the page draws: live mode's held forecast, imitate mode's prediction. */
function onScreen() {
  const { shown, prediction } = state;
  if (shown?.mode === "live") return heldForecast();
  return shown?.mode === "imitate" && prediction?.complete ? prediction : null;
}

/** Whether a sampling is running, and the prediction to sample once it is done. */
let running = false;
let waiting = null;

/** Prediction `p` is complete (main.js), or the settings changed: its futures, unless off. */
export function imagine(p = onScreen()) {
  const { samples, seed } = futureSettings();
  if (!p || !samples || !["live", "imitate"].includes(p.mode)) return;
  if (p.futures?.samples === samples && p.futures.seed === seed) return;
  if (running) {
    waiting = p;
    return;
  }
  sample(p, samples, seed);
}

/** The control changed: the futures of the prediction on screen are sampled again, or dropped (0). */
export function futuresChanged() {
  const p = onScreen();
  const { samples, seed } = futureSettings();
  if (p?.futures && (p.futures.samples !== samples || p.futures.seed !== seed)) {
    p.futures = null;
    // A future's performance drawn: back to the imagined joints'.
    if (state.performance?.source === "future") showFuture(state.performance);
  }
  ui.futuresInfo.textContent = "";
  render();
  imagine(p);
}

/** Asks a worker for `samples` futures of `p`'s observations at its predicted steps, then stores them in `p`. */
async function sample(p, samples, seed) {
  const { sequence, from, len, jointCount } = p;
  const { frames, joints, times } = observations(p.steps, sequence);
  const targets = sequence.times.slice(from, len);
  const blend = BLENDS[p.observe];
  running = true;
  log("imagine", { id: p.id, samples, seed });
  ui.futuresInfo.textContent = `imagining ${samples} futures…`;
  let reply = null;
  try {
    const request = { model: p.model, frames, joints, times, targets, blend, samples, seed, source: sequence.id, steps: p.steps };
    reply = await state.inference.sample(request).done;
  } catch (err) {
    if (onScreen() === p) ui.futuresInfo.textContent = `No futures: ${err.message ?? err}`;
  }
  running = false;
  const now = futureSettings();
  if (reply?.type === "sampled" && onScreen() === p && now.samples === samples && now.seed === seed) {
    const steps = len - from;
    const futures = (p.futures = {
      id: p.id,
      model: p.model,
      samples,
      seed,
      from,
      steps,
      jointCount,
      joints: reply.joints,
      frames: reply.frames,
      size: sequence.size,
      mean: p.jointMean.slice(from * jointCount, len * jointCount),
      outcomes: p.mode === "imitate" ? new Array(samples).fill(null) : null,
      ms: reply.ms,
    });
    log("imagined", { id: p.id });
    ui.futuresInfo.textContent = `${samples} futures, seed ${seed}, in ${Math.round(reply.ms)} ms${coincide(futures) ? why(blend) : ""}`;
    render();
    if (p.mode === "imitate") await performAll(p, futures);
    if (p.futures === futures && onScreen() === p) futuresImagined();
  }
  const next = waiting;
  waiting = null;
  if (next) imagine(next);
}

/** Whether every future of `futures` is the first (S > 1). */
function coincide({ samples, steps, jointCount, joints }) {
  const rows = steps * jointCount;
  for (let i = rows; i < samples * rows; i++) if (joints[i] !== joints[i % rows]) return false;
  return samples > 1;
}

/** The note on futures that coincide: with frames only, the joints drawn step by step weigh nothing. */
function why(blend) {
  if (blend !== 1) return ": they coincide";
  return ": they coincide — frames only (blend 1): the joints drawn step by step weigh nothing in what the model conditions on; observe images + joints to see them differ";
}

/**
 * Imitate mode: the arm performs each future of `futures` (of prediction `p`), one a task, so
 * that the page stays responsive, and the strip shows each outcome as it comes.
 */
async function performAll(p, futures) {
  const rows = futures.steps * futures.jointCount;
  const observed = Uint32Array.from(p.steps);
  for (let s = 0; s < futures.samples; s++) {
    await new Promise((resolve) => setTimeout(resolve, 0));
    if (p.futures !== futures || onScreen() !== p) return;
    const trajectory = futures.joints.slice(s * rows, (s + 1) * rows);
    try {
      const performance = performFuture(trajectory, observed, { future: s, of: futures.samples, seed: futures.seed });
      futures.outcomes[s] = { label: outcomeLabel(performance.outcome), summary: performance.outcome.summary, performance };
    } catch (err) {
      futures.outcomes[s] = { label: "failed", summary: `could not be performed: ${err.message ?? err}`, performance: null };
    }
    render();
  }
}

/**
 * An outcome in a word: a grasp `carried` (its success: lifted and carried to the
 * demonstration's spot), `lifted` (elsewhere), a push `landed` (its success), `pushed` (a valid
 * push that ended elsewhere), or `missed`.
 */
function outcomeLabel(outcome) {
  if (outcome.success) return outcome.action === "grasp" ? "carried" : "landed";
  // (10 cm: what a grasp must lift, crate/sim's Outcome::LIFT_CM.)
  if (outcome.action === "grasp" && outcome.lift_cm >= 10) return "lifted";
  if (outcome.action !== "grasp" && outcome.valid) return "pushed";
  return "missed";
}

/** Imitate mode: a click on future `s` in the strip performs it (again: back to the imagined joints). */
export function chooseFuture(s) {
  const performance = onScreen()?.futures?.outcomes?.[s]?.performance;
  if (!performance) return;
  showFuture(performance);
  render();
}

/**
 * For bench/page.mjs: samples `samples` futures (seed `seed`) of `n` evenly spaced target steps
 * with the chosen model from the current observations, through a worker as the page does
 * (every observation encoded each time), without drawing; resolves to {wall_ms, worker_ms,
 * encode_ms}.
 */
export async function timeFutures(n = 100, samples = 8, seed = 0) {
  const model = ui.model.value;
  await loadModel(model);
  const { frames, joints, times } = observations(observedSteps());
  const targets = Float32Array.from({ length: n }, (_, i) => (n > 1 ? i / (n - 1) : 0.5));
  const t0 = performance.now();
  const request = { model, frames, joints, times, targets, blend: BLENDS[ui.observe.value], samples, seed };
  const reply = await state.inference.sample(request).done;
  return { wall_ms: performance.now() - t0, worker_ms: reply.ms, encode_ms: reply.encodeMs };
}
