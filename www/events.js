// What flows up the layers: a lower module announces, the wiring (main.js) connects a higher
// one, so that no module imports one above it (README: "Layers").
//
//   step (k)           playback.js: step k is on screen; live mode forecasts from what it has seen
//   predicted (p)      prediction.js: prediction p is complete, before it is counted and drawn
//   dropped ()         prediction.js: no prediction is on screen or coming any more
//   fatal (err)        status.js: the page has failed for good; playback stops

const listeners = new Map();

/** Calls `fn(...args)` at every `emit(name, ...args)`, in the order they were connected. */
export function on(name, fn) {
  if (!listeners.has(name)) listeners.set(name, []);
  listeners.get(name).push(fn);
}

/** Calls the listeners of `name` now, synchronously: the order of the page's steps stays as it was. */
export function emit(name, ...args) {
  for (const fn of listeners.get(name) ?? []) fn(...args);
}
