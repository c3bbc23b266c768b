// The web package's whole JS API under any JS value (issue: "no trap from any JavaScript
// value"): every exported function, constructor, static and method (found by walking the
// module, so a new entry point without a row here fails) is called with a table of wrong
// values in each parameter in turn, the others valid. Each call must throw an `Error` that
// names the parameter (never a `WebAssembly.RuntimeError`, a trap that can leave the instance
// half-written), every method must throw on a freed object, and afterwards the same instance
// must still predict exactly what it predicted before. Runs under Node on pkg/ (`node --test
// tests/browser/`), with the shipped default weights.
import assert from "node:assert/strict";
import { existsSync, readFileSync } from "node:fs";
import { dirname, join } from "node:path";
import { before, test } from "node:test";
import { fileURLToPath, pathToFileURL } from "node:url";

import { folderFiles } from "./folders.mjs";

const ROOT = join(dirname(fileURLToPath(import.meta.url)), "..", "..");
const S = 64;
let wasm;
/** Valid objects of every class, made once; `fresh` makes ones a call may consume. */
let v;

before(async () => {
  assert.ok(existsSync(join(ROOT, "pkg", "dmbn.js")), "no web package in pkg/: build it with `wasm-pack build --release --target web --out-dir pkg --no-typescript`");
  wasm = await import(pathToFileURL(join(ROOT, "pkg", "dmbn.js")).href);
  await wasm.default({ module_or_path: readFileSync(join(ROOT, "pkg", "dmbn_bg.wasm")) });
  const episode = wasm.runEpisode("grasp", 7, S);
  const model = wasm.Model.fromBytes(readFileSync(join(ROOT, "assets", "models", "attn-sim.dmbn")));
  const steps = [0, 14, 28, 42];
  const px = S * S * 3;
  const frames = Uint8Array.from(steps.flatMap((k) => Array.from(episode.frame(k))));
  const joints = Float32Array.from(steps.flatMap((k) => Array.from(episode.joints().subarray(k * 7, k * 7 + 7))));
  const times = Float32Array.from(steps.map((k) => episode.times()[k]));
  const targets = Float32Array.of(0, 0.25, 0.5, 1);
  const prediction = model.predict(frames, joints, times, targets, 0.5);
  const { files } = folderFiles(wasm, "data", [{ action: "grasp", seed: 3, id: 0 }]);
  v = {
    episode,
    model,
    frames,
    joints,
    times,
    targets,
    prediction,
    contexts: model.encodeContexts(frames, joints, times),
    encoding: model.encode(frames, joints, times, 0.5),
    trajectory: episode.joints(),
    files,
    folder: () => new wasm.Folder(Object.keys(files)),
    onePx: prediction.pixelSigma().subarray(0, S * S),
    frame0: episode.frames().subarray(0, px),
  };
});

/** A freed object of every class the API hands out (and one of another class), made per use. */
const freed = () => {
  const e = wasm.runEpisode("move", 1, S);
  e.free();
  return e;
};

/**
 * The wrong values, by name: [name, value]. `handle` is an object of another class than the
 * parameter's (an `Episode`, or a `Prediction` where an `Episode` is wanted).
 */
function wrongValues(handle) {
  return [
    ["undefined", undefined],
    ["null", null],
    ["NaN", NaN],
    ["Infinity", Infinity],
    ["-Infinity", -Infinity],
    ["-1", -1],
    ["2^53", 2 ** 53],
    ['""', ""],
    ["a 1 MB string", "x".repeat(1 << 20)],
    ["{}", {}],
    ["[]", []],
    ["a wrong typed array", new Int16Array(7)],
    ["a freed object", freed()],
    ["an object of another class", handle],
  ];
}

/** The optional arm ("ur5" or "panda"): left out (undefined) or null is the UR5. */
const ARM = ["arm", null, ["undefined", "null"]];

/**
 * Every entry point with parameters: `call(args)` and valid `args()`; `params` names each
 * parameter (as the docs do) with the class it takes, if any, and the wrong values it accepts
 * (an omitted optional argument).
 */
const ENTRIES = {
  "Contexts.cat": { call: ([o]) => v.contexts.cat(o), args: () => [v.contexts], params: [["other", "Contexts"]] },
  "Contexts.select": { call: ([i]) => v.contexts.select(i), args: () => [Uint32Array.of(0, 2)], params: ["indices"] },
  "Episode.evalSequence": {
    call: (a) => v.episode.evalSequence(...a),
    args: () => ["f", 1, 2, 10],
    params: ["mode", "seed", ["freezeFrom", null, ["undefined", "null"]], ["freezeTo", null, ["undefined", "null"]]],
  },
  "Episode.frame": { call: ([k]) => v.episode.frame(k), args: () => [3], params: ["k"] },
  "Episode.jointDistance": {
    call: (a) => v.episode.jointDistance(...a),
    args: () => [new Float32Array(7), Float32Array.from({ length: 7 }, () => 1)],
    params: ["mean", "std"],
  },
  "new Folder": { call: ([p]) => new wasm.Folder(p), args: () => [Object.keys(v.files)], params: ["paths"] },
  "Folder.filesOf": { call: (a) => v.folder().filesOf(...a), args: () => [0, "grasp"], params: ["id", "action"] },
  "Folder.put": {
    call: (a) => v.folder().put(...a),
    args: () => ["data/0/grasp/joint_0.txt", v.files["data/0/grasp/joint_0.txt"]],
    params: ["path", "bytes"],
  },
  "Folder.read": {
    call: (a) => {
      const folder = v.folder();
      for (const p of folder.filesOf(0, "grasp")) folder.put(p, v.files[p]);
      return folder.read(...a);
    },
    args: () => [0, "grasp", S],
    params: ["id", "action", "imageSize"],
  },
  "Model.decode": { call: (a) => v.model.decode(...a), args: () => [v.encoding, v.targets], params: [["encoding", "Encoding"], "targetTimes"] },
  "Model.encodeContexts": { call: (a) => v.model.encodeContexts(...a), args: () => [v.frames, v.joints, v.times], params: ["frames", "joints", "times"] },
  "Model.encode": { call: (a) => v.model.encode(...a), args: () => [v.frames, v.joints, v.times, 0.5], params: ["frames", "joints", "times", "blend"] },
  "Model.fromBytes": { call: ([b]) => wasm.Model.fromBytes(b), args: () => [readFileSync(join(ROOT, "assets", "models", "attn-sim.dmbn"))], params: ["bytes"] },
  "Model.imitate": {
    call: (a) => v.model.imitate(...a),
    args: () => [v.episode, "grasp", "frames", 5, 1],
    params: [["episode", "Episode"], "action", "task", "observations", "blend"],
  },
  "Model.predict": {
    call: (a) => v.model.predict(...a),
    args: () => [v.frames, v.joints, v.times, v.targets, 0.5],
    params: ["frames", "joints", "times", "targetTimes", "blend"],
  },
  "Model.sample": {
    call: (a) => v.model.sample(...a),
    args: () => [v.contexts, v.targets, 0.5, 2, 3],
    params: [["contexts", "Contexts"], "targetTimes", "blend", "samples", "seed"],
  },
  "Model.sampleWithFrames": {
    call: (a) => v.model.sampleWithFrames(...a),
    args: () => [v.contexts, v.targets, 0.5, 2, 3],
    params: [["contexts", "Contexts"], "targetTimes", "blend", "samples", "seed"],
  },
  "Model.represent": { call: (a) => v.model.represent(...a), args: () => [v.contexts, 0.5], params: [["contexts", "Contexts"], "blend"] },
  "Model.score": {
    call: (a) => v.model.score(...a),
    args: () => [v.episode, "interp", 5, 0.5],
    params: [["episode", "Episode"], "scenario", "observations", "blend"],
  },
  "Prediction.meanFrame": { call: ([k]) => v.prediction.meanFrame(k), args: () => [1], params: ["k"] },
  "Prediction.sigmaMap": { call: (a) => v.prediction.sigmaMap(...a), args: () => [1, 0.1], params: ["k", ["scale", null, ["2^53"]]] },
  "new Simulator": { call: (a) => new wasm.Simulator(...a), args: () => ["grasp", 1, S, "panda"], params: ["action", "seed", "imageSize", ARM] },
  "Simulator.withObject": {
    call: (a) => wasm.Simulator.withObject(...a),
    args: () => ["move", 0, 0.55, 1, S, "panda"],
    params: ["action", "x", "y", "seed", "imageSize", ARM],
  },
  enact: {
    call: (a) => wasm.enact(...a),
    args: () => [v.episode, "grasp", v.trajectory, Uint32Array.of(0, 10)],
    params: [["episode", "Episode"], "action", "trajectory", "observed"],
  },
  forecastError: {
    call: (a) => wasm.forecastError(...a),
    args: () => [v.frame0, v.trajectory.subarray(0, 7), v.frame0, v.trajectory.subarray(0, 7)],
    params: ["trueFrames", "trueJoints", "frames", "joints"],
  },
  heatMap: { call: (a) => wasm.heatMap(...a), args: () => [v.onePx, 0.1], params: ["sigma", ["scale", null, ["2^53"]]] },
  perform: {
    call: (a) => wasm.perform(...a),
    args: () => [v.trajectory.subarray(0, 70), 0, 0.55, S, "ur5"],
    params: ["trajectory", "x", "y", "imageSize", ARM],
  },
  replay: { call: (a) => wasm.replay(...a), args: () => [v.episode, "grasp"], params: [["episode", "Episode"], "action"] },
  runEpisode: { call: (a) => wasm.runEpisode(...a), args: () => ["grasp", 1, S, "panda"], params: ["action", "seed", "imageSize", ARM] },
};

/** Entry points without parameters (getters included): each must throw on a freed object. */
const NO_PARAMETERS = {
  Contexts: ["isEmpty", "len"],
  Encoding: [],
  Episode: ["digest", "endpoint", "frames", "imageSize", "jointCount", "joints", "len", "object", "times"],
  EvalEpisode: ["frames", "joints", "len", "times"],
  Folder: ["root", "sequences"],
  Imitation: ["jointRmse", "observed", "outcome", "performance", "predictedFrom", "trajectory"],
  Model: ["imageSize", "jointCount", "jointNames", "kind", "normalization"],
  Prediction: ["imageMean", "imageSigma", "jointMean", "jointSigma", "len", "maxImageSigma", "meanFrame", "meanFrames", "pixelSigma", "sigmaMap"],
  Simulator: ["arm", "endpoint", "frame", "imageSize", "joints", "len", "object", "run", "stepIndex", "step"],
};
const FUNCTIONS_WITHOUT_PARAMETERS = ["placementRegion"];

/** A fresh, then freed, object of class `name`, made with valid arguments. */
function freedInstance(name) {
  const make = {
    Contexts: () => v.model.encodeContexts(v.frames, v.joints, v.times),
    Encoding: () => v.model.encode(v.frames, v.joints, v.times, 0.5),
    Episode: () => wasm.runEpisode("grasp", 2, S),
    EvalEpisode: () => v.episode.evalSequence("t", 1),
    Folder: () => v.folder(),
    Imitation: () => wasm.replay(v.episode, "grasp"),
    Model: () => wasm.Model.fromBytes(readFileSync(join(ROOT, "assets", "models", "attn-sim.dmbn"))),
    Prediction: () => v.model.predict(v.frames, v.joints, v.times, v.targets, 0.5),
    Simulator: () => new wasm.Simulator("grasp", 1, S),
  }[name];
  const object = make();
  object.free();
  return object;
}

/** The module's API: "Class.member", "new Class" and function names. */
function exportedApi() {
  const names = [];
  for (const [name, value] of Object.entries(wasm)) {
    if (typeof value !== "function" || name === "default" || name === "initSync") continue;
    if (typeof value.prototype?.free !== "function") {
      names.push(name);
      continue;
    }
    const source = value.toString();
    if (/\bconstructor\s*\(/.test(source)) names.push(`new ${name}`);
    for (const member of Object.getOwnPropertyNames(value)) {
      if (!["length", "name", "prototype"].includes(member) && !member.startsWith("__")) names.push(`${name}.${member}`);
    }
    for (const member of Object.getOwnPropertyNames(value.prototype)) {
      if (!["constructor", "free"].includes(member) && !member.startsWith("__")) names.push(`${name}.${member}`);
    }
  }
  return names;
}

/** Asserts `call` throws a JS `Error` (not a trap) whose message mentions `parameter`. */
function assertRefused(call, what, parameter) {
  let thrown;
  try {
    call();
  } catch (err) {
    thrown = err;
  }
  assert.ok(thrown !== undefined, `${what}: accepted`);
  assert.ok(!(thrown instanceof WebAssembly.RuntimeError), `${what}: a wasm trap (${thrown})`);
  assert.ok(thrown instanceof Error, `${what}: threw a non-Error ${String(thrown)}`);
  if (parameter) {
    const flat = (s) => s.toLowerCase().replace(/[\s_]/g, "");
    assert.ok(flat(thrown.message).includes(flat(parameter)), `${what}: the message does not name ${parameter}: ${thrown.message}`);
  }
}

test("every exported entry point is in the table", () => {
  const api = exportedApi();
  const known = new Set([
    ...Object.keys(ENTRIES),
    ...Object.entries(NO_PARAMETERS).flatMap(([c, ms]) => ms.map((m) => `${c}.${m}`)),
    ...FUNCTIONS_WITHOUT_PARAMETERS,
  ]);
  const missing = api.filter((name) => !known.has(name));
  assert.deepEqual(missing, [], "entry points without a row in tests/browser/api.test.mjs");
  const stale = [...Object.keys(ENTRIES), ...FUNCTIONS_WITHOUT_PARAMETERS].filter((name) => !api.includes(name));
  assert.deepEqual(stale, [], "rows for entry points the package does not export");
  assert.ok(api.length > 60, `found only ${api.length} entry points`);
});

test("each entry point takes its valid arguments", () => {
  for (const [name, entry] of Object.entries(ENTRIES)) {
    assert.doesNotThrow(() => entry.call(entry.args()), `${name} with valid arguments`);
  }
});

test("any wrong value in any parameter throws an Error naming it, never a trap", () => {
  const before = v.model.predict(v.frames, v.joints, v.times, v.targets, 0.5);
  const expected = { mean: before.imageMean(), joints: before.jointMean(), sigma: before.jointSigma() };
  let calls = 0;
  for (const [name, entry] of Object.entries(ENTRIES)) {
    entry.params.forEach((param, at) => {
      const [parameter, handleClass = null, accepts = []] = Array.isArray(param) ? param : [param];
      const other = handleClass === "Episode" ? v.prediction : v.episode;
      for (const [label, value] of wrongValues(other)) {
        if (accepts.includes(label)) continue;
        const args = entry.args();
        args[at] = value;
        // A handle's wrong class or freed object is refused by the glue ("expected instance of
        // Episode", "null pointer passed to rust"): an Error, without the parameter's name.
        const named = handleClass === null ? parameter : null;
        assertRefused(() => entry.call(args), `${name}: ${parameter} = ${label}`, named);
        calls++;
      }
      // An argument left out is undefined: the same as passing it (checked above).
    });
  }
  assert.ok(calls > 700, `only ${calls} calls`);
  // The instance is intact: the same prediction, bit for bit.
  const after = v.model.predict(v.frames, v.joints, v.times, v.targets, 0.5);
  assert.deepEqual(after.imageMean(), expected.mean);
  assert.deepEqual(after.jointMean(), expected.joints);
  assert.deepEqual(after.jointSigma(), expected.sigma);
  assert.equal(wasm.runEpisode("grasp", 7, S).digest(), v.episode.digest());
});

test("every method and getter of a freed object throws an Error", () => {
  for (const [cls, members] of Object.entries(NO_PARAMETERS)) {
    for (const member of members) {
      const object = freedInstance(cls);
      const descriptor = Object.getOwnPropertyDescriptor(wasm[cls].prototype, member);
      const call = descriptor.get ? () => descriptor.get.call(object) : () => object[member](0, 0.1);
      assertRefused(call, `freed ${cls}.${member}`, null);
    }
  }
  for (const [name, entry] of Object.entries(ENTRIES)) {
    if (!name.includes(".") || name.startsWith("Model.fromBytes") || name.startsWith("Simulator.withObject")) continue;
    const cls = name.split(".")[0];
    const object = freedInstance(cls);
    const method = name.split(".")[1];
    assertRefused(() => object[method](...entry.args()), `freed ${name}`, null);
  }
  // Still usable afterwards.
  assert.equal(wasm.runEpisode("grasp", 7, S).digest(), v.episode.digest());
  for (const name of FUNCTIONS_WITHOUT_PARAMETERS) assert.doesNotThrow(() => wasm[name]());
});
