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

/** `body[data-progress]`: the steps the prediction on screen has so far. */
export function progress(steps) {
  body.dataset.progress = String(steps);
}

/** Live mode, `body[data-seen]`: the forecast on screen (or coming) is of the steps from `from` on. */
export function seen(from) {
  body.dataset.seen = String(from);
}

/** Imitate mode: which performance is drawn (`imagined`, `demonstration`, "") and its outcome. */
export function performed(performance) {
  body.dataset.performed = performance?.source ?? "";
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

/**
 * The event log, `window.dmbnEvents`: what happened, in order, for tests that check order, not
 * time. Each entry is {n (counts up from 1), type, ...}; types: `episode` {digest}, `step` {step}
 * (shown), `start` {id, mode, model, from} (a prediction asked of the workers), `chunk` {id,
 * count} (stored), `drawn` {id, step} (its frame of that step drawn), and its end: `finished`,
 * `cancelled` or `failed` {id, from}. Only the latest few thousand are kept.
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
 * stops holding, `held()` counts those waiting; the page adds its own (`expose`).
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
};

/** Adds `fns` to `window.dmbn` (main.js: timePrediction, predict, forgetEncodings). */
export function expose(fns) {
  Object.assign(window.dmbn, fns);
}
