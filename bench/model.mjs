#!/usr/bin/env node
// DMBN / DMBN-PTE inference in WebAssembly (simd128) under Node: one target and a 100-step
// sequence from 5 observed steps of a simulated grasp, on the shipped weights.
//
// Usage: node bench/model.mjs [PKG_DIR] [--reps N]
//   PKG_DIR: a `wasm-pack build --release --target nodejs` output (default pkg-node/, as
//   `npm run bench:wasm` builds it). Prints medians in ms and one `json:` line.
import { createRequire } from "node:module";
import { existsSync, readFileSync } from "node:fs";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath } from "node:url";

const root = join(dirname(fileURLToPath(import.meta.url)), "..");
const args = process.argv.slice(2);
let reps = 10;
let pkgDir = join(root, "pkg-node");
for (let i = 0; i < args.length; i++) {
  if (args[i] === "--reps") reps = Number(args[++i]);
  else pkgDir = resolve(args[i]);
}
if (!Number.isInteger(reps) || reps < 3) {
  console.error("--reps must be an integer >= 3");
  process.exit(2);
}
const entry = join(pkgDir, "dmbn.js");
if (!existsSync(entry)) {
  console.error(`no wasm package at ${pkgDir}: build it with\n  wasm-pack build --release --target nodejs --out-dir pkg-node`);
  process.exit(2);
}
const wasm = createRequire(import.meta.url)(entry);

function median(fn, n) {
  fn();
  fn();
  const times = [];
  for (let i = 0; i < n; i++) {
    const start = process.hrtime.bigint();
    fn();
    times.push(Number(process.hrtime.bigint() - start) / 1e6);
  }
  times.sort((a, b) => a - b);
  return times[Math.floor(times.length / 2)];
}

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

console.log(`model benchmark (wasm, node ${process.version}): 64x64, median of ${reps} runs`);
const out = [];
for (const [kind, file] of [["dmbn", "dmbn-sim.dmbn"], ["pte", "pte-sim.dmbn"]]) {
  const model = wasm.Model.fromBytes(readFileSync(join(root, "assets", "models", file)));
  const one = median(() => model.predict(frames, joints, times, new Float32Array([0.5]), 0.5).free(), reps * 5);
  const sequence = median(() => model.predict(frames, joints, times, seq100, 0.5).free(), reps);
  console.log(`${kind.padStart(5)}: infer 1 target ${one.toFixed(2)} ms   infer 100 steps ${sequence.toFixed(1)} ms`);
  out.push({ model: kind, infer_one_ms: +one.toFixed(3), infer_sequence100_ms: +sequence.toFixed(2) });
  model.free();
}
console.log(`json: ${JSON.stringify(out)}`);
