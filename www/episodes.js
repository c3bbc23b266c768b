// Episodes: simulating one on the main thread (or one read from an opened folder, folder.js),
// and the sequence shown to the model under the mode.

import { IMAGE_SIZE } from "./config.js";
import { drawTableMap } from "./draw.js";
import { log, timings } from "./hooks.js";
import { describe } from "./imitate.js";
import { chooseEven, chooseRandom, clampInt, mulberry32, updateObsInfo } from "./observations.js";
import { play, show } from "./playback.js";
import { cancelPrediction } from "./prediction.js";
import { state } from "./state.js";
import { clearError, showError } from "./status.js";
import { ui } from "./ui.js";
import { writeUrl } from "./url.js";
import { rgbImage } from "./views.js";

/**
 * Simulates an episode of the chosen arm; `place` [x, y] puts the object there, otherwise the
 * seed places it.
 */
export function generate(place = state.episode?.placed ? state.episode.object : null) {
  const { action, arm } = { action: ui.action.value, arm: ui.arm.value };
  const seed = Number(ui.seed.value === "" ? NaN : ui.seed.value);
  const t0 = performance.now();
  let ep;
  try {
    if (place) {
      const sim = state.wasm.Simulator.withObject(action, place[0], place[1], seed, IMAGE_SIZE, arm);
      ep = sim.run();
    } else {
      ep = state.wasm.runEpisode(action, seed, IMAGE_SIZE, arm);
    }
  } catch (err) {
    showError(err);
    return false;
  }
  const ms = performance.now() - t0;
  ui.sequence.value = "sim";
  const episode = setEpisode(ep, { action, seed, placed: Boolean(place), ms, folder: null });
  ui.objectInfo.textContent =
    `${episode.len} steps simulated in ${ms < 10 ? ms.toFixed(1) : Math.round(ms)} ms · object at ` +
    `(${episode.object[0].toFixed(3)}, ${episode.object[1].toFixed(3)}) m`;
  return true;
}

/**
 * Makes the wasm Episode `ep` the one on screen — simulated, or read from a folder (`folder`:
 * {root, id}; `seed` then the id, for the p permutation and random observations) — and plays it.
 */
export function setEpisode(ep, { action, seed, placed, ms, folder }) {
  clearError();
  cancelPrediction();
  state.episode?.handle.free();
  // A folder's data may have no object positions (no object_<id>.txt): then none is drawn.
  const object = ep.object();
  const len = ep.len;
  const hasObject = object.length >= len * 3 && len > 0;
  const episode = {
    handle: ep,
    action,
    seed,
    placed,
    folder,
    len,
    object: hasObject ? [object[0], object[1]] : null,
    end: hasObject ? [object[(len - 1) * 3], object[(len - 1) * 3 + 1]] : null,
    jointCount: ep.jointCount,
    joints: ep.joints(),
    digest: ep.digest(),
    ms,
  };
  state.episode = episode;
  timings.episode_ms = ms;
  log("episode", { digest: episode.digest });
  ui.simControls.hidden = Boolean(folder);
  ui.freezeFrom.max = ui.freezeTo.max = String(len);
  if (!(Number(ui.freezeTo.value) > 0) || Number(ui.freezeTo.value) > len) ui.freezeTo.value = String(len);
  if (Number(ui.freezeFrom.value) >= len) ui.freezeFrom.value = String(Math.floor(len / 2));
  ui.objectInfo.title = `episode sha256 ${episode.digest}`;
  drawTableMap();
  // Keep the chosen steps that the new episode has; otherwise "random k", seeded by the seed.
  // Imitate mode observes k evenly spaced frames, as the benchmark does, on every new episode.
  const imitate = ui.mode.value === "imitate";
  const kept = state.pendingObserved ?? (imitate ? [] : state.observed);
  state.observed = new Set([...kept].filter((k) => k < len));
  state.pendingObserved = null;
  if (!state.observed.size && imitate) chooseEven(ui.k.value);
  else if (!state.observed.size) chooseRandom(Number(ui.k.value), mulberry32(seed >>> 0));
  updateObsInfo();
  buildShown();
  ui.scrubber.max = String(len - 1);
  show(0);
  writeUrl();
  play();
  return episode;
}

/** Numbers the shown sequences: the workers keep encoded observations per sequence (`source`). */
let shownCount = 0;

/** The sequence shown to the model under the chosen mode (the p permutation uses the episode seed). */
export function buildShown() {
  const { episode } = state;
  const mode = ui.mode.value;
  ui.freeze.hidden = mode !== "f";
  ui.live.hidden = ui.errorPanel.hidden = mode !== "live";
  const imitate = mode === "imitate";
  ui.imitatePanel.hidden = !imitate;
  ui.futuresControls.hidden = !(imitate || mode === "live");
  if (imitate) describe();
  ui.sigmaPanel.hidden = imitate;
  ui.trueCaption.textContent = imitate ? "Demonstration" : "True frame";
  ui.predCaption.textContent = imitate ? "The robot's performance" : "Predicted mean ";
  if (!imitate) ui.predCaption.insertAdjacentHTML("beforeend", '<span class="muted">+ σ heat map</span>');
  // Live mode observes the episode as it is (t), step by step; imitate mode shows it as is.
  const sequence = mode === "live" || imitate ? "t" : mode;
  let ev;
  try {
    const from = clampInt(ui.freezeFrom.value, 0, episode.len - 1);
    const to = clampInt(ui.freezeTo.value, from + 1, episode.len);
    ev = mode === "f" ? episode.handle.evalSequence(mode, episode.seed, from, to) : episode.handle.evalSequence(sequence, episode.seed);
  } catch (err) {
    showError(err);
    return false;
  }
  const frames = ev.frames();
  const size = IMAGE_SIZE;
  const px = size * size * 3;
  const images = [];
  const sprite = document.createElement("canvas");
  sprite.width = size * ev.len;
  sprite.height = size;
  const sg = sprite.getContext("2d");
  for (let k = 0; k < ev.len; k++) {
    images.push(rgbImage(frames, size, k * px));
    sg.putImageData(images[k], k * size, 0);
  }
  const { jointCount } = episode;
  state.shown = { id: ++shownCount, mode, len: ev.len, size, frames, jointCount, joints: ev.joints(), times: ev.times(), images, sprite };
  ev.free();
  return true;
}
