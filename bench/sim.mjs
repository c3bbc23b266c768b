#!/usr/bin/env node
// Simulator throughput in WebAssembly under Node: frames/s for whole episodes (simulate +
// render), for stepping alone (simulate) and for frame() alone (render), at 64 and 128 px.
//
// Usage: node bench/sim.mjs [PKG_DIR] [--reps N]
//   PKG_DIR: a `wasm-pack build --release --target nodejs` output (default: pkg-node/ at the
//   repository root, as `npm run bench:wasm` builds it). Every figure is the median of N
//   repetitions (default 7, at least 5), each over both actions and seeds 0..3.
import { createRequire } from "node:module";
import { existsSync, statSync } from "node:fs";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath } from "node:url";

const root = join(dirname(fileURLToPath(import.meta.url)), "..");
const args = process.argv.slice(2);
let reps = 7;
let pkgDir = join(root, "pkg-node");
for (let i = 0; i < args.length; i++) {
  if (args[i] === "--reps") reps = Number(args[++i]);
  else if (args[i] === "-h" || args[i] === "--help") {
    console.log("usage: node bench/sim.mjs [PKG_DIR] [--reps N]");
    process.exit(0);
  } else pkgDir = resolve(args[i]);
}
if (!Number.isInteger(reps) || reps < 5) {
  console.error("--reps must be an integer >= 5");
  process.exit(2);
}
const entry = join(pkgDir, "dmbn.js");
if (!existsSync(entry)) {
  console.error(
    `no wasm package at ${pkgDir}: build it with\n` +
      "  wasm-pack build --release --target nodejs --out-dir pkg-node",
  );
  process.exit(2);
}
const wasm = createRequire(import.meta.url)(entry);

const ACTIONS = ["grasp", "move"];
const SEEDS = [0, 1, 2, 3];
/** frame() calls per episode in the render-only case (at its middle step). */
const RENDERS = 20;

const median = (xs) => {
  const s = [...xs].sort((a, b) => a - b);
  const m = s.length >> 1;
  return s.length % 2 ? s[m] : (s[m - 1] + s[m]) / 2;
};

/** Run `body` (which returns the frames it produced) over every action and seed; frames/s. */
function rate(body) {
  let frames = 0;
  const t0 = process.hrtime.bigint();
  for (const action of ACTIONS) for (const seed of SEEDS) frames += body(action, seed);
  const s = Number(process.hrtime.bigint() - t0) / 1e9;
  return frames / s;
}

const cases = {
  /** runEpisode: simulate every step and render every frame. */
  episode: (size) => (action, seed) => {
    const ep = wasm.runEpisode(action, seed, size);
    const n = ep.len;
    ep.free();
    return n;
  },
  /** Simulator.step() to the end without rendering. */
  simulate: (size) => (action, seed) => {
    const sim = new wasm.Simulator(action, seed, size);
    let n = 1;
    while (sim.step()) n++;
    sim.free();
    return n;
  },
  /** Simulator.frame() repeatedly at the middle step: the renderer alone (plus the copy out). */
  render: (size) => (action, seed) => {
    const sim = new wasm.Simulator(action, seed, size);
    const mid = sim.len >> 1;
    while (sim.stepIndex < mid && sim.step());
    const t0 = process.hrtime.bigint();
    for (let i = 0; i < RENDERS; i++) sim.frame();
    renderSeconds += Number(process.hrtime.bigint() - t0) / 1e9;
    sim.free();
    return RENDERS;
  },
};
// The render case times only its frame() calls, not the stepping that reaches the middle.
let renderSeconds = 0;
function renderRate(size) {
  renderSeconds = 0;
  let frames = 0;
  for (const action of ACTIONS) for (const seed of SEEDS) frames += cases.render(size)(action, seed);
  return frames / renderSeconds;
}

const results = [];
for (const size of [64, 128]) {
  for (const name of Object.keys(cases)) {
    const once = () => (name === "render" ? renderRate(size) : rate(cases[name](size)));
    once(); // warm-up: lets the engine tier up the wasm code
    const samples = Array.from({ length: reps }, once);
    results.push({
      case: name,
      image_size: size,
      frames_per_s: Math.round(median(samples) * 10) / 10,
      min: Math.round(Math.min(...samples) * 10) / 10,
      max: Math.round(Math.max(...samples) * 10) / 10,
      reps,
    });
  }
}

const lengths = {};
for (const action of ACTIONS) {
  lengths[action] = SEEDS.map((seed) => {
    const sim = new wasm.Simulator(action, seed, 64);
    const n = sim.len;
    sim.free();
    return n;
  });
}

const header = ["case", "size", "frames/s (median)", "min", "max"];
const rows = results.map((r) => [r.case, String(r.image_size), r.frames_per_s.toFixed(1), r.min.toFixed(1), r.max.toFixed(1)]);
const widths = header.map((h, i) => Math.max(h.length, ...rows.map((r) => r[i].length)));
const line = (cells) => cells.map((c, i) => (i < 2 ? c.padEnd(widths[i]) : c.padStart(widths[i]))).join("  ");
console.log(`wasm simulator benchmark: node ${process.version}, ${pkgDir}/dmbn_bg.wasm (${(statSync(join(pkgDir, "dmbn_bg.wasm")).size / 1e6).toFixed(1)} MB)`);
console.log(`median of ${reps} repetitions, each over actions ${ACTIONS.join("/")} x seeds ${SEEDS.join(",")}`);
console.log(`  episode  = runEpisode (simulate + render every step)`);
console.log(`  simulate = Simulator.step() only;  render = Simulator.frame() only (${RENDERS}x at the middle step)\n`);
console.log(line(header));
console.log(widths.map((w) => "-".repeat(w)).join("  "));
for (const r of rows) console.log(line(r));
console.log();
console.log(JSON.stringify({ node: process.version, reps, episode_lengths: lengths, results }));
