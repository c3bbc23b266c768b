// The page's mutable state, in one object that the modules above read and write.

export const state = {
  /** The wasm-bindgen glue, initialised on the main thread (the simulator). */
  wasm: null,
  /** The pool of inference workers (inference.js). */
  inference: null,
  /** Where an object may be placed: {x: [x0, x1], y: [y0, y1]} in metres. */
  region: null,
  /**
   * The simulated episode (or one read from a folder): the wasm Episode (kept to derive t/p/f
   * sequences), what it was made from, `jointCount` (D, joint values a step) and `object` /
   * `end` (null where the data has no object positions).
   */
  episode: null,
  /** The sequence shown to the model (the episode under the mode): frames, joints (T × jointCount), times, images. */
  shown: null,
  /** Observed steps of the shown sequence. */
  observed: new Set(),
  /** Steps from the URL, used by the first episode. */
  pendingObserved: null,
  /** The prediction on screen (or filling in). */
  prediction: null,
  /**
   * Live mode: the last finished forecast, which the joint panels, the timeline's marks and the
   * error plot show until the next one finishes (a forecast takes about 0.1 s: redrawing them
   * for each new observation, then for its forecast, would flicker and take the main thread
   * and compositor from the inference workers).
   */
  forecast: null,
  /** Live mode: the observation rule, every k-th step (taken from its field on change: live.js `takeRule`). */
  every: 10,
  /** Live mode: the seen observations the forecast on screen was made from ("0,5,10"). */
  seenKey: "",
  /** Live mode: the error curves of the episode on screen, {key, byModel: Map(model → points), version}. */
  curves: { key: "", byModel: new Map(), version: 0 },
  /** Live mode: the running model comparison, {stop}, or null. */
  comparing: null,
  /**
   * Imitate mode: the arm's performances, {source, len, frames, outcome, jointRmse, observed, ms}
   * (imitate.js): of the joints the model imagined, of the demonstration's own, and the one drawn.
   */
  imagined: null,
  demonstration: null,
  performance: null,
  /** Once a prediction has been asked for, any change of settings predicts again. */
  live: false,
  /** Model ids whose weights the workers hold. */
  loadedModels: new Set(),
  /**
   * Model id → the first worker's report on its weights, once loaded (models.js): `fileKind`,
   * `imageSize`, `jointCount` (D, joint values a step), `jointNames`, `normalization`, …
   */
  modelInfo: new Map(),
  /** The step on screen. */
  step: 0,
  playing: false,
  /** Playback's clock: the time the current step was reached. */
  lastTick: 0,
  /** A failure the page cannot recover from: the controls stay disabled. */
  fatal: false,
  /** Client coordinates → step, timeline step, table point: set by each redraw. */
  stepAt: () => 0,
  timelineAt: () => -1,
  tableAt: () => null,
};

/** Live mode: the last finished forecast of the sequence on screen (see `state.forecast`), or null. */
export function heldForecast() {
  const { shown, forecast } = state;
  return shown?.mode === "live" && forecast?.sequence === shown ? forecast : null;
}
