// What a change of settings does: once a prediction has been asked for, predict again (live
// mode: forecast again), otherwise drop the outdated prediction (and say so when the chosen
// model cannot read the episode's joints).

import { render } from "./draw.js";
import { forecastNow } from "./live.js";
import { jointMismatch, refuse } from "./models.js";
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
    // A model of another number of joint values a step than the episode's: the page says so.
    const why = jointMismatch();
    if (why) refuse(why);
    else settle();
  }
}

/** The observed steps changed: list them, link them, and predict again when live. */
export function observationsChanged() {
  updateObsInfo();
  writeUrl();
  invalidate();
}
