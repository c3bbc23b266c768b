// The observed steps: choosing them (first k, random k, evenly spaced k) and listing them.

import { state } from "./state.js";
import { ui } from "./ui.js";

/** A small seeded generator, so "random k" for a given seed is reproducible. */
export function mulberry32(a) {
  return () => {
    a = (a + 0x6d2b79f5) | 0;
    let t = Math.imul(a ^ (a >>> 15), 1 | a);
    t = (t + Math.imul(t ^ (t >>> 7), 61 | t)) ^ t;
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

/** An input's value as an integer in [lo, hi] (lo when it is no number). */
export function clampInt(v, lo, hi) {
  const n = Math.round(Number(v));
  return Math.min(hi, Math.max(lo, Number.isFinite(n) ? n : lo));
}

export function chooseFirst(k) {
  const n = clampInt(k, 1, state.episode.len);
  state.observed = new Set(Array.from({ length: n }, (_, i) => i));
}

/**
 * k steps evenly spaced over the episode, the first and the last included: what `dmbn imitate`
 * observes (imitate mode's default).
 */
export function chooseEven(k) {
  const len = state.episode.len;
  const n = clampInt(k, 1, len);
  const at = (i) => (n === 1 ? len - 1 : Math.round((i * (len - 1)) / (n - 1)));
  state.observed = new Set(Array.from({ length: n }, (_, i) => at(i)));
}

export function chooseRandom(k, rand = Math.random) {
  const len = state.episode.len;
  const n = clampInt(k, 1, len);
  const steps = Array.from({ length: len }, (_, i) => i);
  for (let i = steps.length - 1; i > 0; i--) {
    const j = Math.floor(rand() * (i + 1));
    [steps[i], steps[j]] = [steps[j], steps[i]];
  }
  state.observed = new Set(steps.slice(0, n));
}

export function observedSteps() {
  return [...state.observed].sort((a, b) => a - b);
}

export function updateObsInfo() {
  const steps = observedSteps();
  const live = state.shown?.mode === "live";
  for (const el of [ui.k, ui.firstK, ui.randomK, ui.clearObs]) el.disabled = state.fatal || live;
  ui.predict.textContent = live ? "Forecast" : "Predict";
  if (live) {
    ui.obsInfo.textContent = `live: the ${steps.length} step${steps.length > 1 ? "s" : ""} seen so far, every ${state.every}: ${steps.length > 12 ? `…, ${steps.slice(-12).join(", ")}` : steps.join(", ")}`;
    ui.predict.disabled = state.fatal;
    return;
  }
  ui.obsInfo.textContent = steps.length
    ? `${steps.length} observed: ${steps.length > 12 ? `${steps.slice(0, 12).join(", ")}, …` : steps.join(", ")}`
    : "nothing observed: click frames on the timeline";
  ui.predict.disabled = state.fatal || steps.length === 0;
}
