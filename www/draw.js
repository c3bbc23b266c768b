// Drawing the current step: true and predicted frames, σ map, timeline, joint plot, table map.

import { follow, redrawErrors } from "./live.js";
import { clampInt, observedSteps } from "./observations.js";
import { drawJoints } from "./plot.js";
import { firstDrawn } from "./prediction.js";
import { state } from "./state.js";
import { ui } from "./ui.js";
import { clearFrame, drawTable, drawTimeline, rgbImage } from "./views.js";

/** Shows step `k` (clamped to the shown sequence). */
export function show(k) {
  if (!state.shown) return;
  state.step = Math.max(0, Math.min(state.shown.len - 1, k));
  ui.scrubber.value = String(state.step);
  follow(state.step);
  render();
}

/** Whether a draw waits for the next animation frame. */
let drawSoon = false;

/** Draws at the next animation frame: once, however many chunks arrive before it. */
export function renderSoon() {
  if (drawSoon) return;
  drawSoon = true;
  requestAnimationFrame(() => {
    if (drawSoon) render();
  });
}

/** The step whose prediction is drawn: the current one, or in live mode the forecast some steps ahead of it. */
export function shownStep() {
  const { shown, step } = state;
  return shown.mode === "live" ? Math.min(shown.len - 1, step + clampInt(ui.ahead.value, 1, 100)) : step;
}

export function render() {
  drawSoon = false;
  const { shown, prediction: p, step } = state;
  if (!shown) {
    drawJoints(ui.plot, ui.plotCursor, null);
    return;
  }
  const live = shown.mode === "live";
  const at = shownStep();
  const has = p && p.done[at];
  const trueFrame = ui.frameTrue.getContext("2d");
  trueFrame.putImageData(shown.images[step], 0, 0);
  if (has) {
    const px = p.size * p.size;
    const mean = rgbImage(p.mean, p.size, at * px * 3);
    ui.framePred.getContext("2d").putImageData(mean, 0, 0);
    if (live && ui.ghost.checked) drawGhost(trueFrame, mean);
    const heat = state.wasm.heatMap(p.sigma.subarray(at * px, (at + 1) * px), p.maxSigma);
    ui.sigmaMap.getContext("2d").putImageData(rgbImage(heat, p.size), 0, 0);
    ui.sigmaScale.textContent = p.maxSigma.toFixed(3);
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
  ui.counter.textContent = `step ${step} / ${shown.len - 1} · t = ${shown.times[step].toFixed(3)}`;
  ui.trueLabel.textContent = shown.mode === "t" ? "" : `mode ${shown.mode}`;
  state.timelineAt = drawTimeline(ui.timeline, {
    len: shown.len,
    size: shown.size,
    sprite: shown.sprite,
    observed: state.observed,
    done: p?.done,
    step,
  });
  if (live) redrawErrors();
  state.stepAt = drawJoints(ui.plot, ui.plotCursor, {
    len: shown.len,
    joints: shown.joints,
    observed: observedSteps(),
    step,
    prediction: p,
  });
  if (p?.count) firstDrawn(p);
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

export function drawTableMap() {
  state.tableAt = drawTable(ui.table, state.region, state.episode?.object, state.episode?.end);
}

export function sigmaOverlay() {
  ui.sigmaMap.hidden = !ui.sigmaToggle.checked;
  ui.sigmaMap.style.opacity = String(Number(ui.sigmaOpacity.value) / 100);
  ui.sigmaOpacity.disabled = state.fatal || !ui.sigmaToggle.checked;
}
