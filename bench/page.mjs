#!/usr/bin/env node
// The demo page in headless Chromium (the browser tests' setup): time from navigation to
// `ready` on localhost, the wasm size (raw and gzip), one predicted frame and a 100-step
// sequence for the attentive model (the page's default), DMBN and DMBN-PTE through the page's
// worker, the page's own progressive prediction of a whole episode (and the longest main-thread
// task meanwhile), and live mode's latency (new observation → first frames / whole forecast of
// the rest, with the other observations kept encoded in the workers and with nothing kept;
// longest main-thread task while playing), and sampling 8 futures of a 100-step sequence
// through a worker (live and imitate modes' "imagine S futures"). The browser tests assert no duration: the
// main thread's figures and their goals are here. Saves
// screenshots of the page mid-prediction to docs/page.png, in live mode to docs/live.png and
// in imitate mode to docs/imitate.png.
//
// Usage: node bench/page.mjs [--runs N] [--no-screenshot | --screenshots-only | --futures-only]
//   Needs the web package: wasm-pack build --release --target web --out-dir pkg --no-typescript
//   Figures are medians: N cold page loads (default 7, own browser context and empty cache
//   each), 5N one-frame and N 100-step predictions per model. Prints a table and one `json:` line.
import { existsSync, readFileSync, statSync } from "node:fs";
import { cpus, loadavg } from "node:os";
import { dirname, join } from "node:path";
import { fileURLToPath } from "node:url";
import { gzipSync } from "node:zlib";

import { launch } from "../tests/browser/browser.mjs";
import { serve } from "../tests/browser/server.mjs";

const ROOT = join(dirname(fileURLToPath(import.meta.url)), "..");
const args = process.argv.slice(2);
let runs = 7;
let screenshot = true;
let measure = true;
let futuresOnly = false;
for (let i = 0; i < args.length; i++) {
  if (args[i] === "--runs") runs = Number(args[++i]);
  else if (args[i] === "--no-screenshot") screenshot = false;
  else if (args[i] === "--screenshots-only") measure = false;
  else if (args[i] === "--futures-only") futuresOnly = true;
  else {
    console.log("usage: node bench/page.mjs [--runs N] [--no-screenshot | --screenshots-only | --futures-only]");
    process.exit(args[i] === "-h" || args[i] === "--help" ? 0 : 2);
  }
}
if (!Number.isInteger(runs) || runs < 3) {
  console.error("--runs must be an integer >= 3");
  process.exit(2);
}
const wasmFile = join(ROOT, "pkg", "dmbn_bg.wasm");
if (!existsSync(wasmFile)) {
  console.error("no web package in pkg/: build it with\n  wasm-pack build --release --target web --out-dir pkg --no-typescript");
  process.exit(2);
}

const median = (xs) => {
  const s = [...xs].sort((a, b) => a - b);
  const m = Math.floor(s.length / 2);
  return s.length % 2 ? s[m] : (s[m - 1] + s[m]) / 2;
};
const round = (v, d = 1) => Number(v.toFixed(d));
const TIMEOUT = 120_000;

/** Starts recording the page's long main-thread tasks (over 50 ms; the browser reports them). */
async function watchLongTasks(page) {
  const observable = await page.evaluate(() => {
    window.longTasks = [];
    new PerformanceObserver((list) => window.longTasks.push(...list.getEntries().map((e) => e.duration))).observe({ type: "longtask" });
    return PerformanceObserver.supportedEntryTypes.includes("longtask");
  });
  // (Else "0 ms" would mean nothing.)
  if (!observable) throw new Error("this Chromium does not report long tasks");
}

/** The longest task recorded so far, in ms (0 when none exceeded 50 ms). */
async function longestTask(page) {
  // The observer reports after the tasks: a task of its own lets the last reports in.
  await page.evaluate(() => new Promise((ok) => setTimeout(ok, 100)));
  return Math.max(0, ...(await page.evaluate(() => window.longTasks)));
}
/** The models timed: [page model id, weight file]; the first is the page's default. */
const MODELS = [["attn", "attn-sim.dmbn"], ["dmbn", "dmbn-sim.dmbn"], ["pte", "pte-sim.dmbn"]];
const DEFAULT = MODELS[0][0];
const NAMES = { attn: "Attentive", dmbn: "DMBN", pte: "DMBN-PTE" };

async function waitState(page, wanted) {
  // The state that ended the wait, not one read after it: live mode's playback moves on.
  const reached = await page.waitForFunction(
    (w) => [w, "error"].includes(document.body.dataset.state) && document.body.dataset.state,
    wanted,
    { timeout: TIMEOUT },
  );
  const state = await reached.jsonValue();
  if (state !== wanted) throw new Error(`page: ${await page.locator("#error").textContent()}`);
}

/** The README's screenshots: mid-prediction, live mode and imitate mode. */
async function screenshots() {
  // Mid-prediction (chunks slowed down so the moment is easy to catch).
  const context = await browser.newContext({ viewport: { width: 1280, height: 900 } });
  const page = await context.newPage();
  await page.goto(`${server.url}www/?action=move&seed=5&model=attn&obs=0,14,29,44,58,72&chunkDelay=250`);
  await waitState(page, "ready");
  await page.click("#play");
  await page.click("#predict");
  const len = Number(await page.getAttribute("#scrubber", "max")) + 1;
  await page.waitForFunction((n) => Number(document.body.dataset.progress) >= n, Math.floor(len * 0.45), { timeout: TIMEOUT });
  await page.locator("#scrubber").fill(String(Math.floor(len * 0.3)));
  await page.screenshot({ path: join(ROOT, "docs", "page.png"), fullPage: true });
  await context.close();
  // Live mode, every model's error curve, 40% into a grasp.
  const live = await browser.newContext({ viewport: { width: 1280, height: 1100 } });
  const lp = await live.newPage();
  await lp.goto(`${server.url}www/?mode=live&action=grasp&seed=11&every=5`);
  await lp.waitForFunction(() => document.body.dataset.state === "predicted", null, { timeout: TIMEOUT });
  if ((await lp.getAttribute("#play", "aria-pressed")) === "true") await lp.click("#play");
  await lp.click("#compare");
  await lp.waitForFunction(() => Number(document.body.dataset.compared ?? 0) > 0, null, { timeout: 4 * TIMEOUT });
  const n = Number(await lp.getAttribute("#scrubber", "max")) + 1;
  await lp.locator("#scrubber").fill(String(Math.floor(n * 0.4)));
  await lp.waitForFunction(() => document.body.dataset.state === "predicted", null, { timeout: TIMEOUT });
  await lp.screenshot({ path: join(ROOT, "docs", "live.png"), fullPage: true });
  await live.close();
  // Imitate mode: a grasp seen through 5 evenly spaced frames, performed by the arm, near its end.
  const im = await browser.newContext({ viewport: { width: 1280, height: 940 } });
  const ip = await im.newPage();
  await ip.goto(`${server.url}www/?mode=imitate&action=grasp&seed=11&obs=0,12,24,35,47`);
  await waitState(ip, "ready");
  if ((await ip.getAttribute("#play", "aria-pressed")) === "true") await ip.click("#play");
  await ip.click("#predict");
  await ip.waitForFunction(() => document.body.dataset.performed === "imagined", null, { timeout: TIMEOUT });
  await ip.locator("#scrubber").fill("40");
  await ip.screenshot({ path: join(ROOT, "docs", "imitate.png"), fullPage: true });
  await im.close();
}

/**
 * Sampling futures through the page's path (`window.dmbn.timeFutures`: a worker, the default
 * model, every observation encoded each time): 8 futures of a 100-step sequence (evenly spaced
 * targets) from 5 observed steps of grasp seed 7, both modalities; `runs` seeds after a warm-up.
 */
async function measureFutures() {
  const context = await browser.newContext({ viewport: { width: 1280, height: 940 } });
  const page = await context.newPage();
  await page.goto(`${server.url}www/?action=grasp&seed=7&obs=0,10,20,30,40`);
  await waitState(page, "ready");
  await page.click("#play"); // pause the animation
  await new Promise((r) => setTimeout(r, 1000)); // the other workers load the weights
  const time = (seed) => page.evaluate((seed) => window.dmbn.timeFutures(100, 8, seed), seed);
  await time(0);
  const times = [];
  for (let i = 1; i <= runs; i++) times.push(await time(i));
  await context.close();
  return {
    samples: 8,
    steps: 100,
    wall_ms: round(median(times.map((t) => t.wall_ms))),
    worker_ms: round(median(times.map((t) => t.worker_ms))),
    encode_ms: round(median(times.map((t) => t.encode_ms))),
  };
}

/** The futures' row of the table. */
const futuresRow = (f) =>
  `| futures: ${f.samples} sampled futures of a ${f.steps}-step sequence (${NAMES[DEFAULT]}, one worker; page round trip) | ` +
  `${Math.round(f.wall_ms)} ms (worker ${Math.round(f.worker_ms)} ms, of which encoding ${Math.round(f.encode_ms)} ms) | ≤ 1000 ms |`;

const load = loadavg()[0];
const server = await serve(ROOT);
const browser = await launch();
const result = {};
if (futuresOnly) {
  try {
    result.futures = await measureFutures();
    result.chromium = browser.version();
  } finally {
    await browser.close();
    await server.close();
  }
  console.log(`page benchmark: headless Chromium ${result.chromium}, ${cpus().length}× ${cpus()[0].model}, load average ${round(load, 2)} at the start`);
  console.log(`  medians of ${runs} samplings\n\n| measure | value | goal |\n|---|---|---|\n${futuresRow(result.futures)}`);
  console.log(`\njson: ${JSON.stringify(result)}`);
  process.exit(0);
}
if (!measure) {
  try {
    await screenshots();
  } finally {
    await browser.close();
    await server.close();
  }
  process.exit(0);
}
try {
  // Sizes.
  const wasm = readFileSync(wasmFile);
  const glue = readFileSync(join(ROOT, "pkg", "dmbn.js"));
  result.wasm_bytes = wasm.length;
  result.wasm_gzip_bytes = gzipSync(wasm, { level: 9 }).length;
  result.glue_bytes = glue.length;
  result.glue_gzip_bytes = gzipSync(glue, { level: 9 }).length;
  for (const [kind, file] of MODELS) {
    const path = join(ROOT, "assets", "models", file);
    if (existsSync(path)) {
      result[`${kind}_weights_bytes`] = statSync(path).size;
      result[`${kind}_weights_gzip_bytes`] = gzipSync(readFileSync(path), { level: 9 }).length;
    }
  }

  // Cold loads to `ready` (wasm compiled, episode simulated, the default model's weights fetched
  // and parsed).
  const ready = [];
  const wasmMs = [];
  const modelMs = [];
  for (let i = 0; i < runs; i++) {
    const context = await browser.newContext({ viewport: { width: 1280, height: 940 } });
    const page = await context.newPage();
    await page.goto(`${server.url}www/`);
    await waitState(page, "ready");
    const t = await page.evaluate(() => window.dmbnTimings);
    ready.push(t.ready_ms);
    wasmMs.push(t.wasm_ms);
    modelMs.push(t.models[DEFAULT].fetchMs + t.models[DEFAULT].parseMs);
    await context.close();
  }
  result.ready_ms = round(median(ready));
  result.wasm_load_ms = round(median(wasmMs));
  result.model_load_ms = round(median(modelMs));

  // Inference through the page's workers: 5 observed steps of grasp seed 7 (both modalities).
  const context = await browser.newContext({ viewport: { width: 1280, height: 940 } });
  const page = await context.newPage();
  const open = async (query) => {
    await page.goto(`${server.url}www/?action=grasp&seed=7&obs=0,10,20,30,40&${query}`);
    await waitState(page, "ready");
    await page.click("#play"); // pause the animation
  };
  for (const [kind] of MODELS) {
    await open(`model=${kind}`);
    const time = (n) => page.evaluate(([n, kind]) => window.dmbn.timePrediction(n, kind), [n, kind]);
    // Warm-up; also lets the other workers finish loading the weights in the background.
    await new Promise((r) => setTimeout(r, 1000));
    await time(1);
    const warm = await time(100);
    const one = [];
    for (let i = 0; i < runs * 5; i++) one.push(await time(1));
    const seq = [];
    for (let i = 0; i < runs; i++) seq.push(await time(100));
    // The page's own path: Predict → every step of the episode drawn, state `predicted`; and
    // the longest main-thread task meanwhile (the page stays responsive).
    const whole = [];
    await watchLongTasks(page);
    for (let i = 0; i < 3; i++) {
      const before = await page.evaluate(() => Number(document.body.dataset.predictions ?? 0));
      await page.click("#predict");
      await page.waitForFunction((n) => Number(document.body.dataset.predictions ?? 0) > n, before, { timeout: TIMEOUT });
      whole.push(await page.evaluate(() => window.dmbnTimings.prediction));
    }
    const pageLongestTask = await longestTask(page);
    // The same 100 steps in one worker.
    await open(`model=${kind}&workers=1`);
    await time(100);
    const single = [];
    for (let i = 0; i < runs; i++) single.push((await time(100)).wall_ms);
    result[kind] = {
      one_frame_ms: round(median(one.map((r) => r.wall_ms)), 2),
      one_frame_decode_ms: round(median(one.map((r) => r.decode_ms)), 2),
      encode_ms: round(median(one.map((r) => r.encode_ms))),
      sequence100_ms: round(median(seq.map((r) => r.wall_ms))),
      sequence100_first_chunk_ms: round(median(seq.map((r) => r.first_chunk_ms))),
      sequence100_workers: warm.workers,
      sequence100_one_worker_ms: round(median(single)),
      page_sequence_steps: whole[0].steps,
      page_sequence_ms: round(median(whole.map((w) => w.total_ms))),
      page_first_chunk_ms: round(median(whole.map((w) => w.first_chunk_ms))),
      page_longest_task_ms: round(pageLongestTask),
    };
  }
  await context.close();
  result.chromium = browser.version();

  // Live mode, the default model, 2 workers, every step observed: from a new observation to the
  // first frames of the new forecast and to the whole forecast of a 60-step remainder; and the
  // longest main-thread task while the episode plays live (every 10th step observed, the
  // page's default).
  {
    const context = await browser.newContext({ viewport: { width: 1280, height: 940 } });
    const page = await context.newPage();
    // (A push: long enough for a 60-step remainder.)
    await page.goto(`${server.url}www/?mode=live&action=move&seed=7&every=1&workers=2`);
    await page.waitForFunction(() => ["predicted", "error"].includes(document.body.dataset.state), null, { timeout: TIMEOUT });
    await waitState(page, "predicted");
    if ((await page.getAttribute("#play", "aria-pressed")) === "true") await page.click("#play");
    await new Promise((r) => setTimeout(r, 1000)); // the second worker loads the weights
    const len = Number(await page.getAttribute("#scrubber", "max")) + 1;
    if (len < 62) throw new Error(`move seed 7 has ${len} steps: too short for a 60-step remainder`);
    const forecastAt = async (step) => {
      await page.locator("#scrubber").fill(String(step));
      await page.waitForFunction(
        (from) => window.dmbnTimings.live.at(-1)?.from === from && document.body.dataset.state === "predicted",
        step + 1,
        { timeout: TIMEOUT },
      );
      return page.evaluate(() => window.dmbnTimings.live.at(-1));
    };
    // Each round: the workers forget the observations they keep encoded, so the forecast
    // from step len − 62 encodes all of them (from scratch); the next step's forecast encodes
    // its one new observation, as playing live does.
    const remainder = [];
    const scratch = [];
    for (let i = 0; i < runs * 2; i++) {
      await page.evaluate(() => window.dmbn.forgetEncodings());
      scratch.push(await forecastAt(len - 62));
      remainder.push(await forecastAt(len - 61));
    }
    await page.locator("#live-every").fill("10");
    await page.locator("#live-every").dispatchEvent("change");
    await page.keyboard.press("Home");
    await watchLongTasks(page);
    const played = await page.evaluate(() => window.dmbnTimings.live.length);
    await page.click("#play");
    await page.waitForFunction(() => document.getElementById("play").getAttribute("aria-pressed") === "false", null, { timeout: TIMEOUT });
    await page.waitForFunction(() => document.body.dataset.state === "predicted", null, { timeout: TIMEOUT });
    const playing = (await page.evaluate(() => window.dmbnTimings.live)).slice(played);
    result.live = {
      remainder_steps: remainder[0].steps,
      first_frames_ms: round(median(remainder.map((r) => r.first_chunk_ms))),
      remainder_ms: round(median(remainder.map((r) => r.total_ms))),
      remainder_worker_ms: round(median(remainder.map((r) => r.worker_ms))),
      remainder_encode_ms: round(median(remainder.map((r) => r.encode_ms))),
      remainder_observed: remainder[0].observed,
      remainder_encoded: remainder[0].encoded,
      scratch_steps: scratch[0].steps,
      scratch_first_frames_ms: round(median(scratch.map((r) => r.first_chunk_ms))),
      scratch_ms: round(median(scratch.map((r) => r.total_ms))),
      scratch_encode_ms: round(median(scratch.map((r) => r.encode_ms))),
      scratch_observed: scratch[0].observed,
      played_steps: len,
      played_forecasts: playing.length,
      played_first_frames_ms: round(median(playing.map((r) => r.first_chunk_ms))),
      longest_task_ms: round(await longestTask(page)),
    };
    await context.close();
  }

  result.futures = await measureFutures();

  if (screenshot) await screenshots();
  result.load_average = [round(load, 2), round(loadavg()[0], 2)];
} finally {
  await browser.close();
  await server.close();
}

const kb = (b) => `${(b / 1024).toFixed(0)} KiB`;
const mb = (b) => `${(b / 1048576).toFixed(2)} MiB`;
const ms = (v) => `${v < 20 ? v.toFixed(1) : Math.round(v)} ms`;
console.log(
  `page benchmark: headless Chromium ${result.chromium}, ${cpus().length}× ${cpus()[0].model}, ` +
    `load average ${result.load_average[0]} at the start, ${result.load_average[1]} at the end`,
);
console.log(`  medians of ${runs} cold loads, ${runs * 5} one-frame and ${runs} 100-step predictions per model\n`);
console.log(`| measure | value | goal |`);
console.log(`|---|---|---|`);
console.log(`| time to \`ready\` (localhost, cold cache) | ${ms(result.ready_ms)} | ≤ 2000 ms |`);
console.log(`| … of which wasm fetch + compile + init | ${ms(result.wasm_load_ms)} | |`);
console.log(`| … of which ${NAMES[DEFAULT]} weights fetch + parse (worker, in parallel) | ${ms(result.model_load_ms)} | |`);
console.log(`| wasm size raw / gzip -9 | ${mb(result.wasm_bytes)} / ${mb(result.wasm_gzip_bytes)} | |`);
console.log(`| JS glue raw / gzip -9 | ${kb(result.glue_bytes)} / ${kb(result.glue_gzip_bytes)} | |`);
for (const [kind] of MODELS) {
  const r = result[kind];
  const name = NAMES[kind];
  const w = r.sequence100_workers;
  console.log(`| ${name}: one predicted frame (decode; observations encoded once) | ${ms(r.one_frame_decode_ms)} | ≤ 15 ms |`);
  console.log(`| ${name}: one frame from scratch (encode 5 observations + decode 1, round trip) | ${ms(r.one_frame_ms)} | |`);
  console.log(`| ${name}: … of which encoding the 5 observations | ${ms(r.encode_ms)} | |`);
  console.log(`| ${name}: 100-step sequence, ${w} worker${w > 1 ? "s" : ""} | ${ms(r.sequence100_ms)} (${ms(r.sequence100_ms / 100)} per frame) | ≤ 600 ms |`);
  console.log(`| ${name}: 100-step sequence, 1 worker | ${ms(r.sequence100_one_worker_ms)} | |`);
  console.log(`| ${name}: 100-step sequence, first chunk (10 steps) back | ${ms(r.sequence100_first_chunk_ms)} | |`);
  console.log(`| ${name}: page, Predict → all ${r.page_sequence_steps} steps drawn | ${ms(r.page_sequence_ms)} | |`);
  console.log(`| ${name}: page, longest main-thread task during those predictions | ${ms(r.page_longest_task_ms)} | < 300 ms |`);
}
const live = result.live;
console.log(`| live mode: new observation → first frames of the new forecast (${NAMES[DEFAULT]}, 2 workers) | ${ms(live.first_frames_ms)} | ≤ 50 ms |`);
console.log(`| live mode: new observation → whole forecast of a ${live.remainder_steps}-step remainder | ${ms(live.remainder_ms)} | ≤ 100 ms |`);
console.log(`| live mode: … of which the slowest worker's whole time (the rest: messages and drawing) | ${ms(live.remainder_worker_ms)} | |`);
console.log(`| live mode: … of which encoding ${live.remainder_encoded} of the ${live.remainder_observed} observations (slowest worker; the others kept) | ${ms(live.remainder_encode_ms)} | |`);
console.log(`| live mode, nothing kept encoded: ${live.scratch_observed} observations → first frames / whole ${live.scratch_steps}-step forecast | ${ms(live.scratch_first_frames_ms)} / ${ms(live.scratch_ms)} | |`);
console.log(`| live mode: … of which encoding the ${live.scratch_observed} observations (slowest worker) | ${ms(live.scratch_encode_ms)} | |`);
console.log(`| live mode: playing a ${live.played_steps}-step episode, every 10th step observed: forecasts finished, first frames | ${live.played_forecasts}, ${ms(live.played_first_frames_ms)} | |`);
console.log(`| live mode: longest main-thread task while playing | ${ms(live.longest_task_ms)} | ≤ 50 ms (never 300 ms) |`);
console.log(futuresRow(result.futures));
console.log(`\njson: ${JSON.stringify(result)}`);
