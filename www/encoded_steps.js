// The observations a worker keeps encoded, per loaded model: each step of the sequence on screen
// is encoded once (Model.encodeContexts), so that a live forecast encodes only its new
// observation, and the set observed is cut from the kept ones (Contexts.select).

/** Steps kept at most (more only while a single forecast observes more). */
export const LIMIT = 128;

export class EncodedSteps {
  /** For `model`, a wasm Model, keeping at most `limit` steps. */
  constructor(model, limit = LIMIT) {
    this.model = model;
    /** Joint values a step (D): the model's. */
    this.jointCount = model.jointCount;
    this.limit = limit;
    /** The sequence the kept steps are of (the page's name for it). */
    this.source = null;
    /** A Contexts: every kept step's encoding, in the order of `steps`. */
    this.contexts = null;
    this.steps = [];
    /** step → its index in `contexts`. */
    this.index = new Map();
  }

  /** Drops every kept encoding. */
  forget() {
    this.contexts?.free();
    this.contexts = null;
    this.steps = [];
    this.index.clear();
  }

  /**
   * The encoded observations of `steps` of sequence `source`, in that order, with
   * `frames`, `joints` and `times` holding each of those steps' observation: the steps not kept
   * yet are encoded (another `source` drops what was kept). Returns {contexts, encoded}: a
   * Contexts for Model.represent, which the caller frees, and how many steps were encoded.
   */
  contextsOf(source, steps, frames, joints, times) {
    const d = this.jointCount;
    if (steps.length !== times.length || joints.length !== steps.length * d) {
      throw new Error(
        `predict: ${steps.length} steps for ${times.length} times and ${joints.length / d} joint rows of ${d} values: expected one observation per step`,
      );
    }
    if (source !== this.source) {
      this.forget();
      this.source = source;
    }
    const missing = [];
    const wanted = new Set();
    steps.forEach((s, i) => {
      if (!this.index.has(s) && !wanted.has(s)) missing.push(i);
      wanted.add(s);
    });
    if (missing.length) {
      this.makeRoom(wanted, missing.length);
      const px = frames.length / steps.length;
      const pick = (values, width) => {
        const out = new values.constructor(missing.length * width);
        missing.forEach((i, j) => out.set(values.subarray(i * width, (i + 1) * width), j * width));
        return out;
      };
      const fresh = this.model.encodeContexts(pick(frames, px), pick(joints, d), pick(times, 1));
      this.add(fresh, missing.map((i) => steps[i]));
    }
    const contexts = this.contexts.select(Uint32Array.from(steps, (s) => this.index.get(s)));
    return { contexts, encoded: missing.length };
  }

  /** Keeps `fresh` (a Contexts, taken over) as the encodings of `steps`. */
  add(fresh, steps) {
    if (this.contexts) {
      try {
        const joined = this.contexts.cat(fresh);
        this.contexts.free();
        this.contexts = joined;
      } finally {
        fresh.free();
      }
    } else {
      this.contexts = fresh;
    }
    for (const s of steps) {
      this.index.set(s, this.steps.length);
      this.steps.push(s);
    }
  }

  /** Makes room for `adding` more steps: past the limit, only the steps in `wanted` stay. */
  makeRoom(wanted, adding) {
    if (!this.contexts || this.steps.length + adding <= this.limit) return;
    const kept = this.steps.filter((s) => wanted.has(s));
    if (!kept.length) {
      this.forget();
      return;
    }
    const contexts = this.contexts.select(Uint32Array.from(kept, (s) => this.index.get(s)));
    this.contexts.free();
    this.contexts = contexts;
    this.steps = kept;
    this.index = new Map(kept.map((s, i) => [s, i]));
  }
}
