// The models' weights: loading each once into the workers, and the status line describing them.

import { IMAGE_SIZE, KIND_NAMES, MODEL_NAMES, MODELS, modelsOf, WEIGHTS } from "./config.js";
import { timings } from "./hooks.js";
import { state } from "./state.js";
import { clearError, setState, showError } from "./status.js";
import { ui } from "./ui.js";

/** Model id → promise of the workers' report on its weights; a failure is dropped, to retry. */
const requests = new Map();

/** Loads model `id` (a key of MODELS) into the workers once; resolves with the first worker's report. */
export function loadModel(id) {
  let p = requests.get(id);
  if (!p) {
    p = state.inference.load(id, WEIGHTS[id]).then((info) => {
      if (info.imageSize !== IMAGE_SIZE) {
        throw new Error(
          `The ${MODEL_NAMES[id]} weights (${WEIGHTS[id]}) are for ${info.imageSize}×${info.imageSize} frames; this page simulates ${IMAGE_SIZE}×${IMAGE_SIZE}.`,
        );
      }
      state.modelInfo.set(id, info);
      timings.models[id] = info;
      state.loadedModels.add(id);
      return info;
    });
    // Failures are not kept: choosing the model again retries.
    p.catch(() => requests.delete(id));
    requests.set(id, p);
  }
  return p;
}

function describeModel(id) {
  const info = state.modelInfo.get(id);
  if (!info) return "";
  const file = decodeURIComponent(new URL(WEIGHTS[id]).pathname.split("/").pop());
  // The file should hold the kind of model the id names (pte-aug: a DMBN-PTE).
  const mismatch =
    info.fileKind !== MODELS[id].kind ? ` — note: the file holds a ${KIND_NAMES[info.fileKind] ?? info.fileKind} model` : "";
  return `${MODEL_NAMES[id]} ready: ${file}, ${(info.bytes / 1e6).toFixed(1)} MB, loaded in ${Math.round(info.fetchMs + info.parseMs)} ms${mismatch}`;
}

/** Makes the chosen model available; shows progress and errors. Resolves to whether it is still the chosen one. */
export async function selectModel() {
  const id = ui.model.value;
  if (!state.loadedModels.has(id)) {
    setState("loading");
    ui.status.textContent = `Loading the ${MODEL_NAMES[id]} weights…`;
  }
  try {
    await loadModel(id);
  } catch (err) {
    if (ui.model.value === id) {
      ui.status.textContent = "";
      showError(err);
    }
    return false;
  }
  if (ui.model.value !== id) return false;
  ui.status.textContent = describeModel(id);
  // A model of another robot's joints predicts nothing of this one's.
  const why = jointMismatch(id);
  if (why) {
    refuse(why);
    return false;
  }
  clearError();
  return true;
}

/**
 * Why model `id` (the chosen one by default) cannot predict the episode on screen: it reads
 * another number of joint values a step (D) than the episode has. Null when they agree, or
 * while the model is not loaded (its count is not known yet: `selectModel` asks again).
 */
export function jointMismatch(id = ui.model.value, episode = state.episode) {
  const info = state.modelInfo.get(id);
  if (!info || !episode || info.jointCount === episode.jointCount) return null;
  const data = episode.folder ? "the folder's sequences have" : "the simulator's episodes have";
  return (
    `The ${MODEL_NAMES[id]} model reads ${info.jointCount} joint values a step, ${data} ${episode.jointCount}: ` +
    "choose a model trained on this robot."
  );
}

/**
 * Shows `why` (jointMismatch's message) in the error banner (state error) instead of
 * predicting; once, however often it is asked again (live mode asks at every step it would
 * forecast).
 */
export function refuse(why) {
  if (!ui.error.hidden && ui.error.textContent === why) return;
  showError(why);
}

/**
 * Offers the models trained on `data` ("sim" or "2020") in the Model select, the first chosen,
 * unless they are offered already. Says whether the choice changed (the caller then loads it).
 * (A folder that no data's models fit keeps the models offered: folder.js.)
 */
export function offerModels(data) {
  const ids = modelsOf(data);
  const offered = [...ui.model.options].map((o) => o.value);
  if (ids.join() === offered.join()) return false;
  ui.model.replaceChildren(...ids.map((id) => new Option(MODEL_NAMES[id], id)));
  ui.model.value = ids[0];
  return true;
}
