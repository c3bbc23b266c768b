// What a change of settings does: once a prediction has been asked for, predict again (live
// mode: forecast again), otherwise drop the outdated prediction.

import { render } from "./draw.js";
import { forecastNow } from "./live.js";
import { updateObsInfo } from "./observations.js";
import { cancelPrediction, predict } from "./prediction.js";
import { state } from "./state.js";
import { settle } from "./status.js";
import { writeUrl } from "./url.js";

/** Settings changed: predict again when live, otherwise drop the outdated prediction. */
export function invalidate() {
  if (state.shown?.mode === "live") {
    forecastNow();
    return;
  }
  if (state.live && state.episode && state.observed.size) {
    predict();
  } else {
    cancelPrediction();
    render();
    settle();
  }
}

/** The observed steps changed: list them, link them, and predict again when live. */
export function observationsChanged() {
  updateObsInfo();
  writeUrl();
  invalidate();
}
