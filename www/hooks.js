// Every hook the page offers to automation (the browser tests, bench/page.mjs), in one place:
// what it tells (data attributes, window.dmbnTimings, the event log window.dmbnEvents) and what
// it lets a script do (window.dmbn). Page modules call these functions; none writes a hook
// itself. README: "Automation hooks".

const { body } = document;

/** Numbers for automation and the page benchmark (README: `window.dmbnTimings`). */
export const timings = (window.dmbnTimings = { models: {}, prediction: null, live: [] });

/** The page's module script runs (index.html's inline script reports a page that never does). */
export function started() {
  window.dmbnStarted = true;
}

/** `body[data-state]`: loading, ready, predicting, predicted or error (it also styles the badge). */
export function pageState(name) {
  body.dataset.state = name;
}

/** Adds one to the counter `body[data-<name>]`: predictions, compared or performances. */
function count(name) {
  body.dataset[name] = String(Number(body.dataset[name] ?? 0) + 1);
}

/** A prediction finished (live mode: a forecast): `body[data-predictions]`. */
export const predictionFinished = () => count("predictions");
/** A model comparison finished or stopped: `body[data-compared]`. */
export const comparisonEnded = () => count("compared");
/** Imitate mode: the arm performed (imagined or demonstrated joints): `body[data-performances]`. */
export const performanceDone = () => count("performances");
/** A set of futures is complete (imitate mode: each one performed too): `body[data-imagined]`. */
export const futuresImagined = () => count("imagined");

/** `body[data-progress]`: the steps the prediction on screen has so far. */
export function progress(steps) {
  body.dataset.progress = String(steps);
}

/** Live mode, `body[data-seen]`: the forecast on screen (or coming) is of the steps from `from` on. */
export function seen(from) {
  body.dataset.seen = String(from);
}

/**
 * Imitate mode: which performance is drawn (`imagined`, `demonstration`, `future`, "") and its
 * outcome; `body[data-future]`: which future (0 …) when it is one.
 */
export function performed(performance) {
  body.dataset.performed = performance?.source ?? "";
  body.dataset.future = performance?.source === "future" ? String(performance.future) : "";
  body.dataset.outcome = performance ? (performance.outcome.success ? "success" : "missed") : "";
}

/** `#error-plot[data-models]`, `[data-points]`: the curves drawn (model id → points). */
export function errorPlotHolds(canvas, byModel) {
  canvas.dataset.models = [...byModel.keys()].join(",");
  canvas.dataset.points = String([...byModel.values()].reduce((n, points) => n + points.length, 0));
}

/**
 * `#joints-plot[data-columns]`: the panels per row (4, or 2 on a phone); `[data-panels]`: the
 * panels, one per joint value a step (D: 7 for the simulator's arm).
 */
export function plotGrid(canvas, cols, panels) {
  canvas.dataset.columns = String(cols);
  canvas.dataset.panels = String(panels);
}

/** The futures drawn (futures.js), for `window.dmbn.futures()`. */
let futuresOnScreen = null;

/** `body[data-futures]`: how many futures are drawn (0: none); `futures` is what is drawn, or null. */
export function futuresShown(futures) {
  futuresOnScreen = futures;
  body.dataset.futures = String(futures?.samples ?? 0);
}

/**
 * `window.dmbn.futures()`: the futures drawn, as plain arrays, or null: {id (the prediction's,
 * as the event log numbers it), model, samples, seed,
 * from (their first step), steps, jointCount, joints (a T' × D row list per future), mean (the
 * prediction's rows over the same steps), outcomes (imitate mode: per future its label —
 * carried, lifted, landed, pushed, missed — or null until performed; live mode: null)}.
 */
function describeFutures() {
  const f = futuresOnScreen;
  if (!f) return null;
  const rows = f.steps * f.jointCount;
  return {
    id: f.id,
    model: f.model,
    samples: f.samples,
    seed: f.seed,
    from: f.from,
    steps: f.steps,
    jointCount: f.jointCount,
    joints: Array.from({ length: f.samples }, (_, s) => Array.from(f.joints.subarray(s * rows, (s + 1) * rows))),
    mean: Array.from(f.mean),
    outcomes: f.outcomes ? f.outcomes.map((o) => o?.label ?? null) : null,
  };
}

/**
 * The event log, `window.dmbnEvents`: what happened, in order, for tests that check order, not
 * time. Each entry is {n (counts up from 1), type, ...}; types: `episode` {digest}, `step` {step}
 * (shown), `start` {id, mode, model, from} (a prediction asked of the workers), `chunk` {id,
 * count} (stored), `drawn` {id, step} (its frame of that step drawn), and its end: `finished`,
 * `cancelled` or `failed` {id, from}; `imagine` {id, samples, seed} (futures of prediction id
 * asked of a worker) and `imagined` {id} (stored). Only the latest few thousand are kept.
 */
const events = (window.dmbnEvents = []);
const KEEP = 4000;
let logged = 0;

export function log(type, fields = {}) {
  events.push({ n: ++logged, type, ...fields });
  if (events.length > KEEP) events.splice(0, KEEP / 2);
}

/** Replies held back (window.dmbn.hold), or null: they pass. */
let held = null;

/**
 * The workers' replies to a prediction pass through here (inference.js): held back while a
 * script holds them, so that it can look at a prediction mid-way whatever the machine's speed.
 */
export function pass(deliver) {
  if (held) held.push(deliver);
  else deliver();
}

/**
 * `window.dmbn`: `hold()` holds the workers' prediction replies (chunks and ends) from now on,
 * `release(n = 1)` hands on the first n held and keeps holding, `resume()` hands on all and
 * stops holding, `held()` counts those waiting; `futures()` describes the futures drawn; the
 * page adds its own (`expose`).
 */
window.dmbn = {
  hold: () => {
    held ??= [];
  },
  release: (n = 1) => {
    for (const deliver of held?.splice(0, n) ?? []) deliver();
  },
  resume: () => {
    const waiting = held ?? [];
    held = null;
    for (const deliver of waiting) deliver();
  },
  held: () => held?.length ?? 0,
  futures: describeFutures,
};

/** Adds `fns` to `window.dmbn` (main.js: timePrediction, predict, forgetEncodings). */
export function expose(fns) {
  Object.assign(window.dmbn, fns);
}
