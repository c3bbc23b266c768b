// The page's worker API (Model.encode once, Model.decode in chunks; the observations kept
// encoded per step, www/encoded_steps.js) on the web package itself, under Node: it must give
// what Model.predict gives, and refuse bad input with a JS Error. Runs with the browser tests (`node --test tests/browser/`), on pkg/ and the shipped weights.
import assert from "node:assert/strict";
import { existsSync, readFileSync } from "node:fs";
import { dirname, join } from "node:path";
import { before, describe, test } from "node:test";
import { fileURLToPath, pathToFileURL } from "node:url";

import { EncodedSteps } from "../../www/encoded_steps.js";

const ROOT = join(dirname(fileURLToPath(import.meta.url)), "..", "..");
const S = 64;
let wasm;
let episode;

before(async () => {
  assert.ok(existsSync(join(ROOT, "pkg", "dmbn.js")), "no web package in pkg/: build it with `wasm-pack build --release --target web --out-dir pkg --no-typescript`");
  wasm = await import(pathToFileURL(join(ROOT, "pkg", "dmbn.js")).href);
  await wasm.default({ module_or_path: readFileSync(join(ROOT, "pkg", "dmbn_bg.wasm")) });
  episode = wasm.runEpisode("move", 3, S);
});

const weights = (file) => readFileSync(join(ROOT, "assets", "models", file));

/** Steps `steps` of the episode as model input. */
function observe(steps) {
  const px = S * S * 3;
  const all = episode.frames();
  const joints = episode.joints();
  const times = episode.times();
  return {
    frames: Uint8Array.from(steps.flatMap((k) => Array.from(all.subarray(k * px, (k + 1) * px)))),
    joints: Float32Array.from(steps.flatMap((k) => Array.from(joints.subarray(k * 7, k * 7 + 7)))),
    times: Float32Array.from(steps.map((k) => times[k])),
  };
}

function close(a, b, tol, what) {
  assert.equal(a.length, b.length, `${what}: lengths`);
  let worst = 0;
  for (let i = 0; i < a.length; i++) worst = Math.max(worst, Math.abs(a[i] - b[i]));
  assert.ok(worst <= tol, `${what}: largest difference ${worst} > ${tol}`);
}

describe("Model.encode / Model.decode (the page's worker API)", () => {
  // Every model the page offers (its ids: attn, dmbn, pte, pte-aug), with the kind its file holds.
  for (const [kind, file] of [["attn", "attn-sim.dmbn"], ["dmbn", "dmbn-sim.dmbn"], ["pte", "pte-sim.dmbn"], ["pte", "pte-aug-sim.dmbn"]]) {
    test(`${file} (${kind}): chunked encode/decode equals Model.predict`, () => {
      const bytes = weights(file);
      const model = wasm.Model.fromBytes(bytes);
      // A second instance of the same weights: encode/decode need not be the predicting one.
      const stream = wasm.Model.fromBytes(bytes);
      assert.equal(stream.kind, kind);
      assert.equal(stream.imageSize, S);
      const { frames, joints, times } = observe([0, 9, 18, 40, episode.len - 1]);
      const targets = episode.times();
      const whole = model.predict(frames, joints, times, targets, 0.5);
      const encoding = stream.encode(frames, joints, times, 0.5);
      const parts = [];
      for (let start = 0; start < targets.length; start += 10) {
        parts.push(stream.decode(encoding, targets.subarray(start, start + 10)));
      }
      const cat = (key, Type) => {
        const arrays = parts.map((p) => p[key]());
        const out = new Type(arrays.reduce((n, a) => n + a.length, 0));
        let at = 0;
        for (const a of arrays) {
          out.set(a, at);
          at += a.length;
        }
        return out;
      };
      assert.equal(parts.reduce((n, p) => n + p.len, 0), targets.length);
      close(cat("jointMean", Float32Array), whole.jointMean(), 1e-4, "joint mean");
      close(cat("jointSigma", Float32Array), whole.jointSigma(), 1e-4, "joint σ");
      const means = cat("meanFrames", Uint8Array);
      const expected = new Uint8Array(targets.length * S * S * 3);
      for (let k = 0; k < targets.length; k++) expected.set(whole.meanFrame(k), k * S * S * 3);
      close(means, expected, 1, "mean frames (bytes)");
      // σ per pixel is the mean over the channels of imageSigma.
      const sigma3 = whole.imageSigma();
      const sigma = cat("pixelSigma", Float32Array);
      close(sigma, Float32Array.from(sigma, (_, i) => (sigma3[3 * i] + sigma3[3 * i + 1] + sigma3[3 * i + 2]) / 3), 1e-4, "pixel σ");
      const largest = sigma.reduce((m, v) => Math.max(m, v), 0);
      assert.ok(Math.abs(Math.max(...parts.map((p) => p.maxImageSigma)) - largest) < 1e-6, "maxImageSigma");
      assert.ok(sigma.every((v) => v > 0 && Number.isFinite(v)));
      for (const p of parts) p.free();
      encoding.free();
      whole.free();
      stream.free();
      model.free();
    });
  }

  test("kept encodings (EncodedSteps) predict as Model.predict, encoding each step once", () => {
    for (const file of ["attn-sim.dmbn", "dmbn-sim.dmbn"]) {
      const model = wasm.Model.fromBytes(weights(file));
      const kept = new EncodedSteps(model);
      const targets = episode.times().subarray(30, 40);
      const forecast = (source, steps) => {
        const { frames, joints, times } = observe(steps);
        const { contexts, encoded } = kept.contextsOf(source, steps, frames, joints, times);
        const encoding = model.represent(contexts, 0.5);
        assert.equal(contexts.len, steps.length);
        const p = model.decode(encoding, targets);
        const whole = model.predict(frames, joints, times, targets, 0.5);
        close(p.jointMean(), whole.jointMean(), 1e-4, `${file} ${steps}: joint mean`);
        close(p.imageMean(), whole.imageMean(), 1e-4, `${file} ${steps}: image mean`);
        for (const o of [contexts, encoding, p, whole]) o.free();
        return encoded;
      };
      assert.equal(forecast("a", [0, 10]), 2);
      assert.equal(forecast("a", [0, 10, 20]), 1, "only the new step is encoded");
      assert.equal(forecast("a", [20, 0]), 0, "any subset, in any order");
      assert.equal(forecast("b", [0, 10]), 2, "another sequence: encoded again");
      kept.forget();
      assert.equal(forecast("b", [0]), 1);
      // Past the limit only the steps observed now stay.
      const small = new EncodedSteps(model, 3);
      const add = (steps) => {
        const { frames, joints, times } = observe(steps);
        const { contexts, encoded } = small.contextsOf("a", steps, frames, joints, times);
        contexts.free();
        return encoded;
      };
      assert.equal(add([0, 10, 20]), 3);
      assert.equal(add([20, 30]), 1);
      assert.deepEqual(small.steps, [20, 30]);
      assert.equal(add([20, 30, 40]), 1);
      assert.deepEqual(small.steps, [20, 30, 40]);
      small.forget();
      model.free();
    }
  });

  test("bad input throws a JS Error", () => {
    const dmbn = wasm.Model.fromBytes(weights("dmbn-sim.dmbn"));
    const pte = wasm.Model.fromBytes(weights("pte-sim.dmbn"));
    const { frames, joints, times } = observe([0, 5]);
    const encoding = dmbn.encode(frames, joints, times, 1);
    assert.throws(() => pte.decode(encoding, new Float32Array([0.5])), /another model/);
    assert.throws(() => dmbn.decode(encoding, new Float32Array([NaN])), /finite/);
    assert.throws(() => dmbn.encode(frames, joints, times, 2), /blend/);
    assert.throws(() => dmbn.encode(new Uint8Array(0), new Float32Array(0), new Float32Array(0), 0.5), Error);
    assert.throws(() => dmbn.encode(frames.subarray(1), joints, times, 0.5), /frames/);
    assert.throws(() => wasm.Model.fromBytes(new Uint8Array([1, 2, 3, 4])), Error);
    assert.equal(dmbn.decode(encoding, new Float32Array(0)).len, 0);
    encoding.free();
    dmbn.free();
    pte.free();
  });
});
