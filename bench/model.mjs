#!/usr/bin/env node
// Attentive / DMBN / DMBN-PTE inference in WebAssembly (simd128) under Node: one target and a 100-step
// sequence from 5 observed steps of a simulated grasp, on the shipped weights. The 100 steps
// are timed on one thread and split over N worker threads (each with its own instance, as
// the page's inference workers: WebAssembly here has no shared-memory threads).
//
// Usage: node bench/model.mjs [PKG_DIR] [--reps N] [--workers N] [--model FILE]...
//   PKG_DIR: a `wasm-pack build --release --target nodejs` output (default pkg-node/, as
//   `npm run bench:wasm` builds it). --workers: default the number of cores (at least 2).
//   --model: time these model files instead of the shipped ones (repeatable).
//   Prints medians in ms and one `json:` line.
import { createRequire } from "node:module";
import { existsSync, readFileSync } from "node:fs";
import { availableParallelism } from "node:os";
import { basename, dirname, join, resolve } from "node:path";
import { fileURLToPath } from "node:url";
import { Worker, isMainThread, parentPort, workerData } from "node:worker_threads";

/** The shipped models timed by default. */
const SHIPPED = ["attn-sim.dmbn", "dmbn-sim.dmbn", "pte-sim.dmbn"];
const root = join(dirname(fileURLToPath(import.meta.url)), "..");
const load = (pkgDir) => createRequire(import.meta.url)(join(pkgDir, "dmbn.js"));

if (!isMainThread) {
  // A worker: one model instance; predicts the target times it is sent.
  const wasm = load(workerData.pkgDir);
  const model = wasm.Model.fromBytes(readFileSync(workerData.modelPath));
  const { frames, joints, times } = workerData.observations;
  parentPort.on("message", (targets) => {
    model.predict(frames, joints, times, targets, 0.5).free();
    parentPort.postMessage(null);
  });
} else {
  await main();
}

async function main() {
  const args = process.argv.slice(2);
  let reps = 10;
  let workers = Math.max(2, availableParallelism());
  let pkgDir = join(root, "pkg-node");
  const files = [];
  for (let i = 0; i < args.length; i++) {
    if (args[i] === "--reps") reps = Number(args[++i]);
    else if (args[i] === "--model") files.push(resolve(args[++i] ?? ""));
    else if (args[i] === "--workers") workers = Number(args[++i]);
    else pkgDir = resolve(args[i]);
  }
  if (!Number.isInteger(reps) || reps < 3) fail("--reps must be an integer >= 3");
  if (!Number.isInteger(workers) || workers < 1 || workers > 16) fail("--workers must be an integer from 1 to 16");
  if (!existsSync(join(pkgDir, "dmbn.js"))) {
    fail(`no wasm package at ${pkgDir}: build it with\n  wasm-pack build --release --target nodejs --out-dir pkg-node`);
  }
  const wasm = load(pkgDir);

  const episode = wasm.runEpisode("grasp", 0, 64);
  const steps = [0, 10, 20, 30, 40];
  const size = 64 * 64 * 3;
  const all = episode.frames();
  const frames = new Uint8Array(steps.length * size);
  steps.forEach((k, i) => frames.set(all.subarray(k * size, (k + 1) * size), i * size));
  const jointsAll = episode.joints();
  const joints = new Float32Array(steps.flatMap((k) => Array.from(jointsAll.subarray(k * 7, k * 7 + 7))));
  const times = new Float32Array(steps.map((k) => episode.times()[k]));
  const seq100 = new Float32Array(100).map((_, k) => k / 99);
  // Contiguous shares of the 100 steps, one per worker.
  const shares = Array.from({ length: workers }, (_, w) =>
    seq100.slice(Math.floor((w * 100) / workers), Math.floor(((w + 1) * 100) / workers)),
  );

  console.log(`model benchmark (wasm, node ${process.version}): 64x64, median of ${reps} runs, ${workers} workers`);
  const out = [];
  const custom = files.length > 0;
  if (!custom) files.push(...SHIPPED.map((file) => join(root, "assets", "models", file)));
  for (const modelPath of files) {
    if (!existsSync(modelPath)) fail(`no model file at ${modelPath}`);
    const model = wasm.Model.fromBytes(readFileSync(modelPath));
    const kind = custom ? basename(modelPath, ".dmbn") : model.kind;
    const one = await median(() => model.predict(frames, joints, times, new Float32Array([0.5]), 0.5).free(), reps * 5);
    const sequence = await median(() => model.predict(frames, joints, times, seq100, 0.5).free(), reps);
    model.free();
    const pool = shares.map(() =>
      start(new Worker(fileURLToPath(import.meta.url), { workerData: { pkgDir, modelPath, observations: { frames, joints, times } } })),
    );
    const parallel = await median(() => Promise.all(pool.map((w, i) => w.run(shares[i]))), reps);
    await Promise.all(pool.map((w) => w.worker.terminate()));
    console.log(
      `${kind.padStart(5)}: infer 1 target ${one.toFixed(2)} ms   infer 100 steps ${sequence.toFixed(1)} ms (1 thread), ${parallel.toFixed(1)} ms (${workers} workers)`,
    );
    out.push({
      model: kind,
      infer_one_ms: +one.toFixed(3),
      infer_sequence100_ms: +sequence.toFixed(2),
      infer_sequence100_workers_ms: +parallel.toFixed(2),
      workers,
    });
  }
  console.log(`json: ${JSON.stringify(out)}`);
}

/**
 * A worker with `run(targets)`: a promise that resolves when it has predicted them. Its first
 * run also waits for the worker to load the model: `median`'s untimed runs take that.
 */
function start(worker) {
  let done = null;
  worker.on("message", () => done());
  worker.on("error", (err) => fail(`a benchmark worker failed: ${err.message}`));
  const run = (targets) =>
    new Promise((resolve) => {
      done = resolve;
      worker.postMessage(targets);
    });
  return { worker, run };
}

async function median(fn, n) {
  await fn();
  await fn();
  const times = [];
  for (let i = 0; i < n; i++) {
    const begin = process.hrtime.bigint();
    await fn();
    times.push(Number(process.hrtime.bigint() - begin) / 1e6);
  }
  times.sort((a, b) => a - b);
  return times[Math.floor(times.length / 2)];
}

function fail(message) {
  console.error(message);
  process.exit(2);
}
