// Drawing the current step: true and predicted frames, σ map, timeline, joint plot, table map.

import { observedSteps } from "./observations.js";
import { drawJoints } from "./plot.js";
import { state } from "./state.js";
import { ui } from "./ui.js";
import { clearFrame, drawTable, drawTimeline, rgbImage } from "./views.js";

/** Shows step `k` (clamped to the shown sequence). */
export function show(k) {
  if (!state.shown) return;
  state.step = Math.max(0, Math.min(state.shown.len - 1, k));
  ui.scrubber.value = String(state.step);
  render();
}

export function render() {
  const { shown, prediction: p, step } = state;
  if (!shown) {
    drawJoints(ui.plot, null);
    return;
  }
  ui.frameTrue.getContext("2d").putImageData(shown.images[step], 0, 0);
  const has = p && p.done[step];
  if (has) {
    const px = p.size * p.size;
    ui.framePred.getContext("2d").putImageData(rgbImage(p.mean, p.size, step * px * 3), 0, 0);
    const heat = state.wasm.heatMap(p.sigma.subarray(step * px, (step + 1) * px), p.maxSigma);
    ui.sigmaMap.getContext("2d").putImageData(rgbImage(heat, p.size), 0, 0);
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
  state.timelineAt = drawTimeline(ui.timeline, {
    len: shown.len,
    size: shown.size,
    sprite: shown.sprite,
    observed: state.observed,
    done: p?.done,
    step,
  });
  state.stepAt = drawJoints(ui.plot, {
    len: shown.len,
    joints: shown.joints,
    observed: observedSteps(),
    step,
    prediction: p,
  });
}

export function drawTableMap() {
  state.tableAt = drawTable(ui.table, state.region, state.episode?.object, state.episode?.end);
}

export function sigmaOverlay() {
  ui.sigmaMap.hidden = !ui.sigmaToggle.checked;
  ui.sigmaMap.style.opacity = String(Number(ui.sigmaOpacity.value) / 100);
  ui.sigmaOpacity.disabled = state.fatal || !ui.sigmaToggle.checked;
}
