// The page's state badge (`body[data-state]`), the error banner and fatal failures.

import { emit } from "./events.js";
import { pageState } from "./hooks.js";
import { state } from "./state.js";
import { ui } from "./ui.js";

export function setState(name) {
  pageState(name);
  ui.badge.textContent = name;
}

export function showError(err) {
  const message = err instanceof Error ? err.message : String(err);
  ui.error.textContent = message;
  ui.error.hidden = false;
  setState("error");
  console.error(err);
}

/** Hides the error banner, unless the page has failed for good; says whether it did. */
export function clearError() {
  if (state.fatal) return false;
  ui.error.hidden = true;
  ui.error.textContent = "";
  return true;
}

/** A failure the page cannot recover from: the error stays and every control is disabled. */
export function failFatal(err) {
  state.fatal = true;
  // (Playback stops: main.js connects it.)
  emit("fatal", err);
  for (const el of document.querySelectorAll("#controls button, #controls select, #controls input, .transport button, .transport input")) {
    el.disabled = true;
  }
  showError(err);
}

/** The state when nothing is running: what the page shows. */
export function settle() {
  if (state.fatal) return;
  if (!state.episode || !state.loadedModels.has(ui.model.value)) return;
  setState(state.prediction?.complete ? "predicted" : "ready");
}
