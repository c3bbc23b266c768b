// The controls, pointer and keys: what each input changes.

import { invalidate, observationsChanged } from "./changes.js";
import { drawTableMap, render, sigmaOverlay } from "./draw.js";
import { buildShown, generate } from "./episodes.js";
import { redrawErrors } from "./error_plot.js";
import { droppedFiles, openFolder, pickedFiles, sequenceChosen } from "./folder.js";
import { chooseFuture, futuresChanged } from "./futures.js";
import { toggleDemonstration } from "./imitate.js";
import { compareModels, forecastNow, takeRule } from "./live.js";
import { selectModel } from "./models.js";
import { chooseEven, chooseFirst, chooseRandom, updateObsInfo } from "./observations.js";
import { pause, play, show, toggle } from "./playback.js";
import { cancelPrediction, predict } from "./prediction.js";
import { state } from "./state.js";
import { clearError, settle } from "./status.js";
import { ui } from "./ui.js";
import { writeUrl } from "./url.js";
import { watchSize } from "./views.js";

function toggleObserved(k) {
  if (k < 0 || !state.shown) return;
  // Live mode: the rule chooses the observations; the timeline seeks.
  if (state.shown.mode === "live") {
    pause();
    show(k);
    return;
  }
  if (state.observed.has(k)) state.observed.delete(k);
  else state.observed.add(k);
  observationsChanged();
}

function isTyping(el) {
  return (
    (el instanceof HTMLInputElement && !["range", "checkbox", "button"].includes(el.type)) ||
    el instanceof HTMLSelectElement ||
    el instanceof HTMLTextAreaElement
  );
}

function onKey(e) {
  const { shown } = state;
  if (!shown || state.fatal || isTyping(e.target) || e.ctrlKey || e.metaKey || e.altKey) return;
  const jump = e.shiftKey ? 10 : 1;
  const keys = {
    " ": toggle,
    ArrowLeft: () => (pause(), show(state.step - jump)),
    ArrowRight: () => (pause(), show(state.step + jump)),
    Home: () => (pause(), show(0)),
    End: () => (pause(), show(shown.len - 1)),
  };
  if (e.target === ui.timeline && e.key === "Enter") {
    if (e.type === "keydown") toggleObserved(state.step);
    e.preventDefault();
    return;
  }
  const action = keys[e.key];
  if (!action) return;
  // Handled here, so a focused button or the scrubber does not act on the key as well.
  e.preventDefault();
  if (e.type === "keydown") action();
}

export function wire() {
  document.getElementById("controls").addEventListener("submit", (e) => e.preventDefault());
  ui.sequence.addEventListener("change", sequenceChosen);
  ui.openDataset.addEventListener("click", () => ui.dataset.click());
  ui.dataset.addEventListener("change", () => {
    if (ui.dataset.files.length) openFolder(pickedFiles(ui.dataset.files));
    ui.dataset.value = "";
  });
  // A folder dropped anywhere on the page opens like a chosen one.
  addEventListener("dragover", (e) => {
    if (e.dataTransfer?.types.includes("Files")) e.preventDefault();
  });
  addEventListener("drop", async (e) => {
    if (!e.dataTransfer?.items.length || !state.wasm || state.fatal) return;
    e.preventDefault();
    openFolder(await droppedFiles(e.dataTransfer.items));
  });
  ui.arm.addEventListener("change", sequenceChosen);
  ui.action.addEventListener("change", () => generate() && invalidate());
  ui.seed.addEventListener("change", () => generate(null) && invalidate());
  ui.random.addEventListener("click", () => {
    ui.seed.value = String(Math.floor(Math.random() * 2 ** 31));
    generate(null) && invalidate();
  });
  ui.table.addEventListener("click", (e) => {
    const at = state.tableAt(e.clientX, e.clientY);
    if (at && !state.fatal) generate(at) && invalidate();
  });
  ui.firstK.addEventListener("click", () => {
    chooseFirst(ui.k.value);
    observationsChanged();
  });
  ui.randomK.addEventListener("click", () => {
    chooseRandom(ui.k.value);
    observationsChanged();
  });
  ui.clearObs.addEventListener("click", () => {
    state.observed = new Set();
    observationsChanged();
  });
  ui.model.addEventListener("change", async () => {
    writeUrl();
    if (state.live) invalidate();
    else {
      cancelPrediction();
      render();
      if (await selectModel()) settle();
    }
  });
  const modeChanged = () => {
    if (!state.episode) return;
    const wasLive = state.shown?.mode === "live";
    // Imitate mode sees frames only unless the viewer says otherwise, k evenly spaced ones (the
    // imitation benchmark's).
    if (ui.mode.value === "imitate" && state.shown?.mode !== "imitate") {
      ui.observe.value = "images";
      chooseEven(ui.k.value);
    }
    if (buildShown()) {
      clearError();
      updateObsInfo();
      writeUrl();
      // Entering live mode plays the episode from its start, forecasting as it goes.
      if (state.shown.mode === "live" && !wasLive) {
        show(0);
        play();
      } else show(state.step);
      invalidate();
    }
  };
  ui.mode.addEventListener("change", modeChanged);
  ui.freezeFrom.addEventListener("change", modeChanged);
  ui.freezeTo.addEventListener("change", modeChanged);
  ui.observe.addEventListener("change", () => {
    writeUrl();
    invalidate();
  });
  ui.predict.addEventListener("click", () => (state.shown?.mode === "live" ? forecastNow() : predict()));
  ui.liveEvery.addEventListener("change", () => {
    takeRule();
    writeUrl();
    forecastNow();
    redrawErrors();
  });
  ui.ahead.addEventListener("change", () => (writeUrl(), render()));
  ui.ghost.addEventListener("change", () => (writeUrl(), render()));
  ui.compare.addEventListener("click", () => compareModels());
  const futures = () => (writeUrl(), futuresChanged());
  ui.futures.addEventListener("change", futures);
  ui.futuresSeed.addEventListener("change", futures);
  ui.futuresStrip.addEventListener("click", (e) => {
    const cell = e.target.closest?.("button.future");
    if (cell && !state.fatal) chooseFuture(Number(cell.dataset.future));
  });
  ui.replay.addEventListener("click", () => {
    if (!state.episode || state.fatal) return;
    clearError();
    toggleDemonstration();
    render();
    if (state.performance) settle();
  });
  ui.sigmaToggle.addEventListener("change", sigmaOverlay);
  ui.sigmaOpacity.addEventListener("input", sigmaOverlay);
  ui.play.addEventListener("click", toggle);
  ui.scrubber.addEventListener("input", () => {
    pause();
    show(Number(ui.scrubber.value));
  });
  ui.timeline.addEventListener("click", (e) => toggleObserved(state.timelineAt(e.clientX)));
  ui.timeline.addEventListener("mousemove", (e) => {
    const k = state.timelineAt(e.clientX);
    const verb = state.shown?.mode === "live" ? "go there" : state.observed.has(k) ? "stop observing it" : "observe it";
    ui.timeline.title = k < 0 ? "" : `step ${k}: click to ${verb}`;
  });
  const scrubPlot = (e) => {
    if (!state.shown || !(e.buttons & 1)) return;
    pause();
    show(state.stepAt(e.clientX));
  };
  ui.plot.addEventListener("pointerdown", (e) => {
    ui.plot.setPointerCapture(e.pointerId);
    scrubPlot(e);
  });
  ui.plot.addEventListener("pointermove", scrubPlot);
  addEventListener("keydown", onKey);
  addEventListener("keyup", onKey);
  const redraw = () => {
    render();
    if (state.region) drawTableMap();
  };
  watchSize([ui.plot, ui.plotCursor, ui.timeline, ui.errorPlot], redraw);
  sigmaOverlay();
}
