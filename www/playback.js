// The step on screen: showing one, and playing the shown sequence at real time, one animation
// frame at a time.

import { STEPS_PER_SECOND } from "./config.js";
import { render } from "./draw.js";
import { emit } from "./events.js";
import { log } from "./hooks.js";
import { state } from "./state.js";
import { ui } from "./ui.js";

/** Shows step `k` (clamped to the shown sequence). */
export function show(k) {
  if (!state.shown) return;
  state.step = Math.max(0, Math.min(state.shown.len - 1, k));
  ui.scrubber.value = String(state.step);
  log("step", { step: state.step });
  // Live mode forecasts from what this step has seen, before it is drawn (main.js connects it).
  emit("step", state.step);
  render();
}

export function play() {
  if (!state.shown) return;
  if (state.step >= state.shown.len - 1) show(0);
  state.playing = true;
  ui.play.textContent = "❚❚ Pause";
  ui.play.setAttribute("aria-pressed", "true");
  state.lastTick = performance.now();
  requestAnimationFrame(tick);
}

export function pause() {
  state.playing = false;
  ui.play.textContent = "▶ Play";
  ui.play.setAttribute("aria-pressed", "false");
}

export function toggle() {
  state.playing ? pause() : play();
}

function tick(now) {
  if (!state.playing || !state.shown) return;
  const advance = Math.floor(((now - state.lastTick) * STEPS_PER_SECOND) / 1000);
  if (advance > 0) {
    state.lastTick += (advance * 1000) / STEPS_PER_SECOND;
    show(state.step + advance);
    if (state.step >= state.shown.len - 1) {
      pause();
      return;
    }
  }
  requestAnimationFrame(tick);
}
