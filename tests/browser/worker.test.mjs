// The page's inference worker (www/worker.js) under malformed messages, in headless Chromium:
// each is answered with an error reply carrying its id, and the worker keeps serving: a
// prediction afterwards equals the one made before, chunk for chunk.
import assert from "node:assert/strict";
import { test } from "node:test";

import { close, open, server, virtualFiles } from "./support.mjs";

virtualFiles["/test/blank.html"] = Buffer.from("<!doctype html><meta charset=utf-8><title>worker</title>");

test("the worker answers every malformed message with an error and keeps serving", async () => {
  const page = await open(`${server.url}test/blank.html`);
  const result = await page.evaluate(async () => {
    const module = await WebAssembly.compileStreaming(fetch("/pkg/dmbn_bg.wasm"));
    const pkg = await import("/pkg/dmbn.js");
    await pkg.default({ module_or_path: module });
    const worker = new Worker("/www/worker.js", { type: "module" });
    const queue = [];
    let wake = null;
    worker.onmessage = (e) => {
      queue.push(e.data);
      wake?.();
    };
    // The next reply, or {type: "none"} when none comes (a worker that died on a message).
    const reply = async () => {
      const give = new Promise((ok) => setTimeout(() => ok("none"), 15_000));
      while (!queue.length) if ((await Promise.race([new Promise((ok) => (wake = ok)), give])) === "none") return { type: "none" };
      return queue.shift();
    };
    let nextId = 1;
    /** Sends `msg` (with a fresh id if it is an object) and collects replies up to its last. */
    const send = async (msg) => {
      const id = nextId++;
      if (msg !== null && typeof msg === "object" && !Array.isArray(msg) && !("id" in msg)) msg = { ...msg, id };
      worker.postMessage(msg);
      const replies = [];
      for (;;) {
        const r = await reply();
        replies.push(r);
        if (r.type !== "chunk") return { id: msg?.id, replies };
      }
    };

    const ep = pkg.runEpisode("grasp", 7, 64);
    const px = 64 * 64 * 3;
    const steps = [0, 14, 28, 42];
    const frames = new Uint8Array(steps.length * px);
    steps.forEach((s, i) => frames.set(ep.frame(s), i * px));
    const joints = Float32Array.from(steps.flatMap((s) => Array.from(ep.joints().subarray(s * 7, s * 7 + 7))));
    const times = Float32Array.from(steps, (s) => ep.times()[s]);
    const predict = (over = {}) => ({
      type: "predict", model: "attn", frames: frames.slice(), joints: joints.slice(), times: times.slice(),
      targets: Float32Array.of(0, 0.2, 0.4, 0.6, 0.8, 1), blend: 0.5, chunk: 4, delay: 0, ...over,
    });
    const joined = (replies) => replies.filter((r) => r.type === "chunk").flatMap((r) => [r.start, ...r.jointMean, ...r.mean.slice(0, 99)]);

    const setup = [await send({ type: "init", module }), await send({ type: "load", model: "attn", url: "/assets/models/attn-sim.dmbn" })];
    const before = await send(predict());

    const malformed = {
      null: null,
      number: 5,
      string: "predict",
      array: [],
      "no type": {},
      "unknown type": { type: "nope" },
      "inherited type": { type: "toString" },
      "init without a module": { type: "init", module: 5 },
      "load: model a number": { type: "load", model: 5, url: "/x.dmbn" },
      "load: url an object": { type: "load", model: "attn", url: {} },
      "load: a missing file": { type: "load", model: "gone", url: "/assets/models/gone.dmbn" },
      "predict: nothing": { type: "predict" },
      "predict: a model not loaded": predict({ model: "gone" }),
      "predict: frames a string": predict({ frames: "x" }),
      "predict: joints a plain array": predict({ joints: [1, 2, 3] }),
      "predict: targets a Float64Array": predict({ targets: new Float64Array(3) }),
      "predict: blend NaN": predict({ blend: NaN }),
      "predict: blend 2": predict({ blend: 2 }),
      "predict: chunk 0": predict({ chunk: 0 }),
      "predict: chunk 1.5": predict({ chunk: 1.5 }),
      "predict: delay -1": predict({ delay: -1 }),
      "predict: steps a string": predict({ source: "a", steps: "x" }),
      "predict: a negative step": predict({ source: "a", steps: [-1, 0, 1, 2] }),
      "predict: source an object": predict({ source: {}, steps: [0, 1, 2, 3] }),
      "predict: fewer steps than observations": predict({ source: "a", steps: [0, 1] }),
      "predict: frames of another size": predict({ frames: new Uint8Array(10) }),
      "predict: a NaN time": predict({ times: Float32Array.of(0, NaN, 0.5, 1) }),
      "cancel without a target": { type: "cancel" },
      "cancel: target a string": { type: "cancel", target: "x" },
    };
    const answers = {};
    for (const [name, msg] of Object.entries(malformed)) {
      const { id, replies } = await send(msg);
      answers[name] = { id, replies: replies.map((r) => ({ type: r.type, id: r.id, message: r.message })) };
    }
    const after = await send(predict());
    const forgotten = await send({ type: "forget" });
    worker.terminate();
    return {
      setup: setup.map((s) => s.replies.map((r) => r.type).join()),
      before: { types: before.replies.map((r) => r.type), values: joined(before.replies) },
      after: { types: after.replies.map((r) => r.type), values: joined(after.replies) },
      forgotten: forgotten.replies.map((r) => r.type),
      answers,
    };
  });
  assert.deepEqual(result.setup, ["inited", "loaded"]);
  assert.deepEqual(result.before.types, ["chunk", "chunk", "done"]);
  for (const [name, { id, replies }] of Object.entries(result.answers)) {
    assert.equal(replies.length, 1, `${name}: ${JSON.stringify(replies)}`);
    const [r] = replies;
    assert.equal(r.type, "error", `${name}: ${JSON.stringify(r)}`);
    assert.equal(r.id, id, `${name}: the reply's id`);
    assert.ok(typeof r.message === "string" && r.message.length > 10, `${name}: ${r.message}`);
  }
  // Fields are named: what was wrong, not a TypeError from deep inside.
  assert.match(result.answers["predict: frames a string"].replies[0].message, /frames must be a Uint8Array/);
  assert.match(result.answers["predict: blend 2"].replies[0].message, /blend/);
  assert.match(result.answers["unknown type"].replies[0].message, /unknown type "nope"/);
  assert.match(result.answers["predict: frames of another size"].replies[0].message, /frame/i);
  assert.deepEqual(result.after.types, result.before.types);
  assert.deepEqual(result.after.values, result.before.values, "the same prediction after the malformed messages");
  assert.deepEqual(result.forgotten, ["forgotten"]);
  // The deliberately missing file is the only problem the page logs.
  assert.deepEqual(page.problems.filter((p) => !p.includes("status of 404")), []);
  await close(page);
});
