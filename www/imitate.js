// Imitate mode: the simulated arm performs the joints a model imagined from the
// demonstration's observed steps (the wasm `enact`), or for comparison the demonstration's own
// recorded joints (`replay`), or one of the futures it imagined (futures.js), with the object
// where the demonstration had it. The performance's frames are drawn beside the
// demonstration's, step for step (draw.js), and its outcome — judged in Rust against the
// demonstration — in a badge.

import { performanceDone, performed, timings } from "./hooks.js";
import { state } from "./state.js";
import { showError } from "./status.js";
import { ui } from "./ui.js";

/** What the model saw of the observed steps, by the `#observe` value. */
const SEEN = { both: "frames and joints", images: "frames only", joints: "joints only" };

/**
 * Whether the arm can perform the episode on screen: a simulator episode, or a folder of
 * simulator data. The original DMBN data was recorded on a real arm whose joints the simulated
 * one does not share: its message otherwise. (Another robot's data, of a joint count no
 * simulated arm has, is refused by `enact` itself, naming the counts the arms take.)
 */
function performable() {
  if (state.episode?.folder && state.folder?.data === "2020") {
    return "The robot performs in the simulator, and this sequence is the original DMBN data, recorded on a real arm with other joints: imitate mode needs a simulator episode (the simulator, or a folder `dmbn simulate` wrote).";
  }
  return null;
}

/**
 * The arm performs the joint means of the finished prediction `p` (a row per step of the
 * demonstration). Shows why not, instead, when the episode or the model's joints cannot be
 * performed; the page carries on.
 */
export function performImagined(p) {
  state.imagined = perform("imagined", () => {
    const rows = p.jointMean.slice(0, p.len * state.episode.jointCount);
    return state.wasm.enact(state.episode.handle, state.episode.action, rows, Uint32Array.from(p.steps));
  });
  if (state.imagined) state.imagined.observe = p.observe;
  show(state.imagined);
}

/** The demonstration's own joints performed (the ceiling), or back to the imagined performance. */
export function toggleDemonstration() {
  if (state.performance?.source === "demonstration" && state.imagined) {
    show(state.imagined);
    return;
  }
  state.demonstration ??= perform("demonstration", () => state.wasm.replay(state.episode.handle, state.episode.action));
  show(state.demonstration);
}

/**
 * The episode, observations or model changed: no performance is current. Called by every
 * cancelled prediction (live mode: every forecast), so it touches the page only when there
 * was one: a change of `body`'s data attributes restyles the whole page.
 */
export function clearPerformances() {
  if (!state.imagined && !state.demonstration && !state.performance) return;
  state.imagined = state.demonstration = state.performance = null;
  describe();
}

/** Runs `enactment` (a wasm call returning an `Imitation`) and keeps what the page draws of it. */
function perform(source, enactment) {
  const why = performable();
  if (why) {
    showError(why);
    return null;
  }
  let result;
  try {
    result = enacted(source, enactment);
  } catch (err) {
    const whose = source === "imagined" ? "The joints the model imagined" : "The demonstration's joints";
    showError(new Error(`${whose} could not be performed: ${err.message ?? err}`));
    return null;
  }
  timings.imitation = {
    source,
    success: result.outcome.success,
    summary: result.outcome.summary,
    joint_rmse: result.jointRmse,
    ms: result.ms,
  };
  performanceDone();
  return result;
}

/** What the page keeps of the Imitation that `enactment` returns (its frames, outcome, …); throws as it does. */
function enacted(source, enactment) {
  const t0 = performance.now();
  const imitation = enactment();
  const episode = imitation.performance();
  const result = {
    source,
    len: episode.len,
    frames: episode.frames(),
    outcome: imitation.outcome,
    jointRmse: imitation.jointRmse,
    observed: imitation.observed(),
    ms: performance.now() - t0,
  };
  episode.free();
  imitation.free();
  return result;
}

/**
 * The arm performs future `future` of `of` (seeded `seed`): `rows`, a row of joints per step of
 * the demonstration, imagined from its `observed` steps. Returns the performance, not drawn
 * (`showFuture`); throws why it cannot be performed. Neither counted nor timed: the hooks'
 * performance is the imagined mean's or the demonstration's.
 */
export function performFuture(rows, observed, { future, of, seed }) {
  const why = performable();
  if (why) throw new Error(why);
  const { handle, action } = state.episode;
  const result = enacted("future", () => state.wasm.enact(handle, action, rows, observed));
  return Object.assign(result, { future, of, seed });
}

/** Draws a future's performance; the one drawn already: back to the imagined joints'. */
export function showFuture(performance) {
  show(state.performance === performance && state.imagined ? state.imagined : performance);
}

/** Makes `performance` (or none) the one drawn. */
function show(performance) {
  state.performance = performance;
  describe();
}

/** The badge, the button and the note of imitate mode's panel (entering the mode: episodes.js). */
export function describe() {
  const p = state.performance;
  performed(p);
  ui.outcome.textContent = p ? p.outcome.summary : "no performance yet";
  ui.outcome.className = `outcome ${p ? (p.outcome.success ? "success" : "missed") : ""}`;
  ui.replay.textContent =
    p?.source === "demonstration" && state.imagined ? "perform the imagined joints" : "perform the demonstration's joints";
  const rmse = p && `joint RMSE ${p.jointRmse.toFixed(3)} rad against the demonstration's (${Math.round(p.ms)} ms).`;
  ui.imitateInfo.textContent = !p
    ? "Predict: the robot sees the chosen steps (frames only by default), imagines its joints at every step and performs them."
    : p.source === "demonstration"
      ? `The demonstration's recorded joints, performed (${Math.round(p.ms)} ms).`
      : p.source === "future"
        ? `Future ${p.future + 1} of the ${p.of} it imagined (seed ${p.seed}), performed: ${rmse}`
        : `The joints it imagined from ${p.observed.length} observed steps (${SEEN[p.observe]}), performed: ${rmse}`;
}
