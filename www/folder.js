// A dataset folder opened in the page: the files the user chose (directory picker) or dropped are
// listed, validated and read by the Rust reader (the wasm `Folder`, the code `dmbn` runs), so its
// errors are the reader's, naming the file inside the folder; the page only hands over the bytes.
// Nothing is uploaded. The folder's sequences join the Sequence select.

import { invalidate } from "./changes.js";
import { armData, IMAGE_SIZE, modelsOf } from "./config.js";
import { generate, setEpisode } from "./episodes.js";
import { jointMismatch, loadModel, offerModels } from "./models.js";
import { state } from "./state.js";
import { setState, showError } from "./status.js";
import { ui } from "./ui.js";

/** Counts sequence reads, so that only the latest one shows. */
let reads = 0;

/** Opens the files `files` ([{path, file}], paths relative, under one folder). Resolves to whether it worked. */
export async function openFolder(files) {
  let handle;
  try {
    handle = new state.wasm.Folder(files.map((f) => f.path));
  } catch (err) {
    showError(err);
    return false;
  }
  state.folder?.handle.free();
  const sequences = handle.sequences();
  state.folder = { handle, byPath: new Map(files.map((f) => [f.path, f.file])), sequences, data: null };
  for (const group of ui.sequence.querySelectorAll("optgroup")) group.remove();
  const group = document.createElement("optgroup");
  group.label = handle.root;
  for (const { id, action } of sequences) group.append(new Option(`${id} · ${action}`, `${id}/${action}`));
  ui.sequence.append(group);
  const ids = new Set(sequences.map((s) => s.id)).size;
  ui.datasetInfo.textContent = `${handle.root}: ${sequences.length} sequences, ${ids} ids — read in this browser, nothing is uploaded.`;
  return readSequence(sequences[0].id, sequences[0].action);
}

/**
 * Reads sequence `id`/`action` of the open folder and shows it. On failure the reader's error
 * is shown and the sequence on screen stays. Resolves to whether it worked.
 */
export async function readSequence(id, action) {
  const { folder } = state;
  const read = ++reads;
  const t0 = performance.now();
  let ep;
  try {
    const paths = folder.handle.filesOf(id, action);
    const bytes = await Promise.all(paths.map(async (p) => new Uint8Array(await folder.byPath.get(p).arrayBuffer())));
    if (read !== reads || folder !== state.folder) return false;
    paths.forEach((p, i) => folder.handle.put(p, bytes[i]));
    ep = folder.handle.read(id, action, IMAGE_SIZE);
  } catch (err) {
    if (read === reads) {
      ui.sequence.value = state.episode?.folder ? `${state.episode.folder.id}/${state.episode.action}` : "sim";
      showError(err);
    }
    return false;
  }
  const ms = performance.now() - t0;
  ui.sequence.value = `${id}/${action}`;
  const episode = setEpisode(ep, { action, seed: id, placed: false, ms, folder: { root: folder.handle.root, id } });
  ui.objectInfo.textContent = `${folder.handle.root}/${id}/${action}: ${episode.len} steps read in ${Math.round(ms)} ms (frames at ${IMAGE_SIZE}×${IMAGE_SIZE})`;
  if (!folder.data) {
    // Not ready until the models that fit the folder are offered: a quick click must not
    // predict its sequence with the other data's models.
    setState("loading");
    ui.status.textContent = "Matching the folder's joints to the models…";
    folder.data = await fittingData(episode);
  }
  if (state.episode !== episode) return false;
  // No data's models read the folder's joint values: the models offered stay, and the page
  // says why it predicts nothing (as it does for any model of another count).
  if (folder.data === "none") {
    const d = episode.jointCount;
    ui.status.textContent = `The folder's sequences have ${d} joint values a step: none of the models offered reads ${d}.`;
  }
  if (folder.data !== "none" && (offerModels(folder.data) || jointMismatch())) {
    // The data's models, or the chosen one reads another count: its default (which fits).
    ui.model.value = modelsOf(folder.data)[0];
    ui.model.dispatchEvent(new Event("change"));
  } else invalidate();
  return true;
}

/**
 * The data whose models fit the folder: among the data whose models read as many joint values
 * a step as the sequence has (D, `Episode.jointCount`), the one whose models' joint
 * normalisation the sequence's joints lie nearest ("2020" for the original data or recordings
 * like it, "sim" for the simulator's UR5, "panda" for its Panda-like arm's 8 values); "none"
 * when none's do (another robot's data). Loads the default model of each (the one chosen next
 * anyway).
 */
async function fittingData(episode) {
  const defaults = await Promise.all(["sim", "2020", "panda"].map(async (data) => ({ data, info: await loadModel(modelsOf(data)[0]) })));
  if (state.episode !== episode) return null;
  // Episode.jointDistance takes a normalisation of D values only.
  const fitting = defaults.filter(({ info }) => info.jointCount === episode.jointCount);
  if (!fitting.length) return "none";
  const distance = ({ info: { normalization: n } }) => episode.handle.jointDistance(Float32Array.from(n.mean), Float32Array.from(n.std));
  return fitting.reduce((best, d) => (distance(d) < distance(best) ? d : best)).data;
}

/**
 * The Sequence select changed — the simulator (a new episode of the chosen arm, its models
 * offered) or a sequence of the folder — or the Arm select did.
 */
export function sequenceChosen() {
  const value = ui.sequence.value;
  if (value === "sim") {
    if (!generate(null)) return;
    if (offerModels(armData(ui.arm.value))) ui.model.dispatchEvent(new Event("change"));
    else invalidate();
    return;
  }
  const [id, action] = value.split("/");
  readSequence(Number(id), action);
}

/** The files of a chosen or dropped folder as [{path, file}]: the browser's relative paths. */
export function pickedFiles(fileList) {
  return [...fileList].map((file) => ({ path: file.webkitRelativePath || file.name, file }));
}

/** The files under the dropped items (folders walked), as [{path, file}]. */
export async function droppedFiles(items) {
  const entries = [...items].map((item) => item.webkitGetAsEntry?.()).filter(Boolean);
  const out = [];
  const walk = async (entry) => {
    if (entry.isFile) {
      const file = await new Promise((ok, fail) => entry.file(ok, fail));
      out.push({ path: entry.fullPath.replace(/^\/+/, ""), file });
    } else {
      const reader = entry.createReader();
      // readEntries answers in batches until an empty one.
      for (;;) {
        const batch = await new Promise((ok, fail) => reader.readEntries(ok, fail));
        if (!batch.length) break;
        for (const e of batch) await walk(e);
      }
    }
  };
  for (const e of entries) await walk(e);
  return out;
}
