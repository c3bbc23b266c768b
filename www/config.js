// The page's constants: the models offered, frame size, chunking, playback, and the URL's test settings.

/** Frame size of the shipped models; episodes are simulated at this size. */
export const IMAGE_SIZE = 64;
/** Playback: one recorded step is 3 physics substeps of 1/60 s, so 20 steps/s is real time. */
export const STEPS_PER_SECOND = 20;
/**
 * Target times per predict call: the sequence fills in by this many steps at a time (live mode
 * too: the step shown ahead comes alone first, and smaller chunks only add round trips).
 */
export const CHUNK = 10;
export const BLENDS = { images: 1, joints: 0, both: 0.5 };
/**
 * The models the page offers, by id (the `#model` option values, the `model=` URL state, and
 * the key of the weights, loading and caching): the label, the kind the file must hold (what
 * `Model.kind` says), the shipped file and the data it was trained on (`sim`: the simulator's UR5;
 * `panda`: the simulator's Panda-like arm; `2020`: the original DMBN data, offered for an
 * opened folder whose joints fit its normalisation). The first of each data is its default: the
 * best model.
 */
export const MODELS = {
  attn: { name: "Attentive (DMBN-PTE + attention)", kind: "attn", file: "attn-sim.dmbn", data: "sim" },
  dmbn: { name: "DMBN", kind: "dmbn", file: "dmbn-sim.dmbn", data: "sim" },
  pte: { name: "DMBN-PTE", kind: "pte", file: "pte-sim.dmbn", data: "sim" },
  "pte-aug": { name: "DMBN-PTE + time warps", kind: "pte", file: "pte-aug-sim.dmbn", data: "sim" },
  "attn-2020": { name: "Attentive · original data", kind: "attn", file: "attn-2020.dmbn", data: "2020" },
  "pte-2020": { name: "DMBN-PTE · original data", kind: "pte", file: "pte-2020.dmbn", data: "2020" },
  "dmbn-2020": { name: "DMBN · original data", kind: "dmbn", file: "dmbn-2020.dmbn", data: "2020" },
  "pte-aug-2020": { name: "DMBN-PTE + time warps · original data", kind: "pte", file: "pte-aug-2020.dmbn", data: "2020" },
  "attn-panda": { name: "Attentive · Panda arm", kind: "attn", file: "attn-panda.dmbn", data: "panda" },
};
/** The data of the simulator's `arm` (the Arm select's value): "sim" (the UR5's) or "panda". */
export const armData = (arm) => (arm === "panda" ? "panda" : "sim");
/** The ids of the models trained on `data` ("sim", "panda" or "2020"), the default first. */
export const modelsOf = (data) => Object.keys(MODELS).filter((id) => MODELS[id].data === data);
export const MODEL_NAMES = Object.fromEntries(Object.entries(MODELS).map(([id, m]) => [id, m.name]));
/** What a model file holds (`Model.kind`), in words, for the mismatch note. */
export const KIND_NAMES = { attn: "attentive", dmbn: "DMBN", pte: "DMBN-PTE" };

/** The page's query at load; the URL state (url.js) is read from it once. */
export const params = new URLSearchParams(location.search);
/**
 * Weight files by model id, each overridable for tests and experiments by a parameter named
 * after the id: `?attn=URL`, `?dmbn=URL`, `?pte=URL`, `?pte-aug=URL` (relative to the page).
 */
export const WEIGHTS = Object.fromEntries(
  Object.entries(MODELS).map(([id, m]) => [id, new URL(params.get(id) ?? `../assets/models/${m.file}`, location.href).href]),
);
/** Inference workers: one per core, at most 4 (`?workers=N`, 1 to 8). */
export const WORKERS = Math.min(8, Math.max(1, Math.round(Number(params.get("workers"))) || Math.min(4, navigator.hardwareConcurrency || 2)));
/** Debugging / screenshots: a pause in ms between predicted chunks (`?chunkDelay=200`). */
export const CHUNK_DELAY = Math.max(0, Number(params.get("chunkDelay")) || 0);
