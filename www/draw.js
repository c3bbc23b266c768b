// Drawing the current step as the state says: true and predicted frames, σ map, timeline, joint
// plot (with the sampled futures' fan), error plot, table map, the futures' strip.

import { redrawErrors } from "./error_plot.js";
import { log } from "./hooks.js";
import { clampInt, observedSteps } from "./observations.js";
import { defaultJointNames, drawJoints } from "./plot.js";
import { heldForecast, state } from "./state.js";
import { drawStrip } from "./strip.js";
import { ui } from "./ui.js";
import { clearFrame, drawTable, drawTimeline, rgbImage } from "./views.js";

/** What waits for the next animation frame: nothing, the frames alone, or everything. */
let drawSoon = null;

/**
 * Draws at the next animation frame: once, however many chunks arrive before it. `framesOnly`:
 * only the frames (true, predicted, ghost, σ) need it, as for a live forecast's first chunk
 * (the panels keep the last finished forecast until this one finishes); each canvas redrawn
 * is main-thread and compositor time that the workers lack on 2 cores.
 */
export function renderSoon({ framesOnly = false } = {}) {
  const pending = drawSoon;
  drawSoon = framesOnly && pending !== "all" ? "frames" : "all";
  if (pending) return;
  requestAnimationFrame(() => {
    const wanted = drawSoon;
    drawSoon = null;
    if (wanted === "frames") {
      drawFrames();
      if (state.prediction?.count) firstDrawn(state.prediction);
    } else if (wanted) render();
  });
}

/** The prediction's first steps are drawn: when, for its timings. */
export function firstDrawn(p) {
  if (p.firstAt !== undefined) return;
  p.firstAt = performance.now();
  p.firstMs = p.firstAt - p.start;
}

/** The step whose prediction is drawn at `step`: that one, or in live mode the forecast some steps ahead of it. */
export function shownStep(step = state.step) {
  const { shown } = state;
  return shown.mode === "live" ? Math.min(shown.len - 1, step + clampInt(ui.ahead.value, 1, 100)) : step;
}

export function render() {
  // Everything drawn now: a draw waiting for the next animation frame is not needed.
  drawSoon = null;
  const { shown, prediction: p, step } = state;
  if (!shown) {
    drawJoints(ui.plot, ui.plotCursor, null);
    drawStrip(ui.futuresStrip, null);
    return;
  }
  drawFrames();
  const live = shown.mode === "live";
  // Live mode's panels show the last finished forecast until the next one finishes.
  const panels = live ? heldForecast() : p;
  ui.counter.textContent = `step ${step} / ${shown.len - 1} · t = ${shown.times[step].toFixed(3)}`;
  ui.trueLabel.textContent = ["t", "imitate"].includes(shown.mode) ? "" : `mode ${shown.mode}`;
  state.timelineAt = drawTimeline(ui.timeline, {
    len: shown.len,
    size: shown.size,
    sprite: shown.sprite,
    observed: state.observed,
    done: panels?.done,
    step,
  });
  if (live) redrawErrors();
  state.stepAt = drawJoints(ui.plot, ui.plotCursor, {
    len: shown.len,
    names: jointNames(shown.jointCount),
    joints: shown.joints,
    observed: (live && panels?.steps) || observedSteps(),
    step,
    prediction: panels,
    futures: panels?.futures,
    labels: shown.mode === "imitate" ? { truth: "demonstrated", mean: "imagined mean" } : undefined,
  });
  drawFutures(shown.mode, panels?.futures ?? null);
  if (p?.count) firstDrawn(p);
}

/** Live and imitate modes, futures on: their strip (final frames; outcomes), the one performed marked. */
function drawFutures(mode, futures) {
  const hidden = !["live", "imitate"].includes(mode) || !(Number(ui.futures.value) > 0);
  if (ui.futuresPanel.hidden !== hidden) ui.futuresPanel.hidden = hidden;
  const perf = state.performance;
  drawStrip(ui.futuresStrip, hidden ? null : futures, perf?.source === "future" ? perf.future : -1);
}

/**
 * The names of the `d` joint values a step of the sequence on screen: the chosen model's
 * (`Model.jointNames`) when it reads as many, otherwise the defaults (`joint 0`, …, `gripper`).
 */
function jointNames(d) {
  const info = state.modelInfo.get(ui.model.value);
  return info?.jointCount === d && info.jointNames?.length === d ? info.jointNames : defaultJointNames(d);
}

/** The true frame and the prediction of the step shown: predicted frame, ghost, σ map. */
function drawFrames() {
  const { shown, prediction: p, step } = state;
  if (!shown) return;
  const live = shown.mode === "live";
  const at = shownStep();
  const has = p && p.done[at];
  const trueFrame = ui.frameTrue.getContext("2d");
  trueFrame.putImageData(shown.images[step], 0, 0);
  if (shown.mode === "imitate") {
    drawPerformance();
    return;
  }
  if (has) {
    const px = p.size * p.size;
    const mean = rgbImage(p.mean, p.size, at * px * 3);
    ui.framePred.getContext("2d").putImageData(mean, 0, 0);
    if (live && ui.ghost.checked) drawGhost(trueFrame, mean);
    const heat = state.wasm.heatMap(p.sigma.subarray(at * px, (at + 1) * px), p.maxSigma);
    ui.sigmaMap.getContext("2d").putImageData(screenBlend(mean, heat), 0, 0);
    ui.sigmaScale.textContent = p.maxSigma.toFixed(3);
    log("drawn", { id: p.id, step: at });
  } else {
    clearFrame(ui.framePred);
    clearFrame(ui.sigmaMap);
  }
  const stack = ui.framePred.parentElement;
  stack.classList.toggle("empty", !has);
  stack.dataset.empty = live
    ? "forecasting…"
    : p
      ? "this step is not predicted yet"
      : "no prediction yet: choose observations, then Predict";
  if (live) ui.predLabel.textContent = has ? `forecast of step ${at}` : "";
}

/** Imitate mode: the frame of the arm's performance at the step shown, in step with the demonstration. */
function drawPerformance() {
  const { performance: perf, prediction: p, step } = state;
  const has = Boolean(perf) && step < perf.len;
  if (has) {
    const px = state.shown.size * state.shown.size * 3;
    ui.framePred.getContext("2d").putImageData(rgbImage(perf.frames, state.shown.size, step * px), 0, 0);
  } else clearFrame(ui.framePred);
  // No σ over a performance: the overlay left transparent.
  ui.sigmaMap.getContext("2d").clearRect(0, 0, ui.sigmaMap.width, ui.sigmaMap.height);
  const stack = ui.framePred.parentElement;
  stack.classList.toggle("empty", !has);
  stack.dataset.empty = p && !p.complete ? "imagining its joints…" : "no performance yet: choose observations, then Predict";
  const labels = { imagined: "imagined joints", demonstration: "demonstration's joints", future: `future ${perf?.future + 1}` };
  ui.predLabel.textContent = perf ? labels[perf.source] : "";
}

/** The forecast frame as a ghost over the true one: where the arm is going. */
const ghost = document.createElement("canvas");
function drawGhost(g, mean) {
  ghost.width = mean.width;
  ghost.height = mean.height;
  ghost.getContext("2d").putImageData(mean, 0, 0);
  g.save();
  g.globalAlpha = 0.45;
  g.drawImage(ghost, 0, 0);
  g.restore();
}

/**
 * The σ overlay as drawn over the predicted frame: its heat map screen-blended with `mean`
 * (1 − (1 − m)(1 − h)), where σ is low the frame itself. Blended here, not by CSS
 * `mix-blend-mode`, which makes the compositor draw the overlay in a pass of its own at every
 * frame (on a 2-core machine, time the inference workers lack); the canvas's CSS opacity then
 * mixes it with the frame as the blend mode did.
 */
function screenBlend(mean, heat) {
  const out = new ImageData(mean.width, mean.height);
  const m = mean.data;
  const o = out.data;
  for (let i = 0, j = 0; i < o.length; i += 4, j += 3) {
    for (let c = 0; c < 3; c++) o[i + c] = 255 - ((255 - m[i + c]) * (255 - heat[j + c])) / 255;
    o[i + 3] = 255;
  }
  return out;
}

export function drawTableMap() {
  state.tableAt = drawTable(ui.table, state.region, state.episode?.object, state.episode?.end);
}

export function sigmaOverlay() {
  ui.sigmaMap.hidden = !ui.sigmaToggle.checked;
  ui.sigmaMap.style.opacity = String(Number(ui.sigmaOpacity.value) / 100);
  ui.sigmaOpacity.disabled = state.fatal || !ui.sigmaToggle.checked;
}
