// The page's entry: connects what flows up the layers, starts WebAssembly and the workers, then
// the first episode and the chosen model.

import { observationsChanged } from "./changes.js";
import { armData, MODEL_NAMES, params, WORKERS } from "./config.js";
import { generate } from "./episodes.js";
import { on } from "./events.js";
import { imagine, timeFutures } from "./futures.js";
import { expose, started, timings } from "./hooks.js";
import { clearPerformances, performImagined } from "./imitate.js";
import { Inference } from "./inference.js";
import { follow, forecastDone, takeRule } from "./live.js";
import { jointMismatch, offerModels, refuse, selectModel } from "./models.js";
import { pause } from "./playback.js";
import { predict, timePrediction } from "./prediction.js";
import { state } from "./state.js";
import { failFatal, setState, settle } from "./status.js";
import { ui } from "./ui.js";
import { readUrl } from "./url.js";
import { heatGradient } from "./views.js";
import { checkSupport, loadWasm } from "./wasm.js";
import { wire } from "./wire.js";

// The lower layers announce, the modes above act (events.js).
on("step", follow);
on("predicted", (p) => {
  if (p.mode === "live") forecastDone(p);
  if (p.mode === "imitate") performImagined(p);
  // Live and imitate modes with futures on: sampled once the prediction is complete.
  imagine(p);
});
on("dropped", clearPerformances);
on("fatal", pause);

async function main() {
  started();
  setState("loading");
  wire();
  offerModels(armData(params.get("arm")));
  const place = readUrl();
  takeRule();
  ui.status.textContent = "Loading WebAssembly…";
  try {
    checkSupport();
    const t0 = performance.now();
    const { glue, module } = await loadWasm();
    state.wasm = glue;
    ui.heatLegend.style.background = heatGradient(glue.heatMap);
    timings.wasm_ms = performance.now() - t0;
    state.inference = new Inference(module, WORKERS);
  } catch (err) {
    ui.status.textContent = "";
    failFatal(err);
    return;
  }
  // forgetEncodings: the workers encode every observation again (bench/page.mjs).
  expose({ timePrediction, timeFutures, predict: () => predict(), forgetEncodings: () => state.inference.forget() });
  // The chosen model loads in the worker while the episode is simulated here.
  const modelReady = selectModel();
  // Simulating blocks this thread for a moment: first let the worker start (its start needs
  // this thread), so that it downloads and parses the weights meanwhile.
  try {
    await state.inference.started;
  } catch {
    return; // shown by Inference.fail
  }
  state.region = state.wasm.placementRegion();
  if (!generate(place)) {
    // A bad seed or object position from the URL: fall back to the defaults.
    ui.seed.value = "7";
    generate(null);
  }
  observationsChanged();
  // (The weights may be in already: then selectModel has described them.)
  if (!state.loadedModels.has(ui.model.value)) ui.status.textContent = `Loading the ${MODEL_NAMES[ui.model.value]} weights…`;
  if (await modelReady) {
    timings.ready_ms = performance.now();
    // (A weight override of another robot's model: it cannot predict the simulator's episodes.)
    const why = jointMismatch();
    if (why) refuse(why);
    else settle();
  }
}

addEventListener("error", (e) => {
  // A benign browser notice, not a failure of the page.
  if (/ResizeObserver loop/.test(e.message ?? "")) return;
  if (!state.fatal) failFatal(new Error(`Error: ${e.message}`));
});
addEventListener("unhandledrejection", (e) => {
  if (!state.fatal) failFatal(new Error(`Error: ${e.reason?.message ?? e.reason}`));
});

main();
