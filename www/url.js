// The URL state: the settings read at load, and kept up to date so that a view can be linked.

import { params } from "./config.js";
import { observedSteps } from "./observations.js";
import { state } from "./state.js";
import { ui } from "./ui.js";

/**
 * Sets the controls from the URL (main.js offers the `arm=` arm's models first, so that
 * `model=` can name one of them); returns the object placement [x, y] it names, or null.
 */
export function readUrl() {
  const set = (el, key) => {
    if (!params.has(key)) return;
    const v = params.get(key);
    if (el instanceof HTMLSelectElement && ![...el.options].some((o) => o.value === v)) return;
    el.value = v;
  };
  set(ui.arm, "arm");
  set(ui.action, "action");
  set(ui.seed, "seed");
  set(ui.model, "model");
  set(ui.mode, "mode");
  if (ui.mode.value === "imitate") ui.observe.value = "images";
  set(ui.observe, "observe");
  set(ui.k, "k");
  set(ui.freezeFrom, "from");
  set(ui.freezeTo, "to");
  set(ui.liveEvery, "every");
  set(ui.ahead, "ahead");
  if (params.has("ghost")) ui.ghost.checked = params.get("ghost") !== "0";
  set(ui.futures, "futures");
  set(ui.futuresSeed, "fseed");
  if (params.has("obs")) {
    state.pendingObserved = params
      .get("obs")
      .split(",")
      .map(Number)
      .filter((k) => Number.isInteger(k) && k >= 0);
  }
  if (params.has("x") && params.has("y")) {
    const x = Number(params.get("x"));
    const y = Number(params.get("y"));
    if (Number.isFinite(x) && Number.isFinite(y)) return [x, y];
  }
  return null;
}

/** Writes the current settings into the URL (other parameters, such as weight overrides, stay). */
export function writeUrl() {
  const { episode } = state;
  if (!episode) return;
  const q = new URLSearchParams(location.search);
  const put = (key, value) => (value === null ? q.delete(key) : q.set(key, value));
  put("arm", ui.arm.value === "ur5" ? null : ui.arm.value);
  put("action", ui.action.value);
  put("seed", ui.seed.value);
  put("x", episode.placed ? episode.object[0].toFixed(4) : null);
  put("y", episode.placed ? episode.object[1].toFixed(4) : null);
  put("model", ui.model.value);
  put("mode", ui.mode.value);
  put("from", ui.mode.value === "f" ? ui.freezeFrom.value : null);
  put("to", ui.mode.value === "f" ? ui.freezeTo.value : null);
  const live = ui.mode.value === "live";
  put("every", live ? ui.liveEvery.value : null);
  put("ahead", live ? ui.ahead.value : null);
  put("ghost", live && !ui.ghost.checked ? "0" : null);
  // Live and imitate modes' futures: how many (left out: none) and their seed.
  const futures = (live || ui.mode.value === "imitate") && Number(ui.futures.value) > 0;
  put("futures", futures ? ui.futures.value : null);
  put("fseed", futures ? ui.futuresSeed.value : null);
  put("observe", ui.observe.value);
  put("obs", live ? null : observedSteps().join(","));
  history.replaceState(null, "", `${location.pathname}?${q}`);
}
