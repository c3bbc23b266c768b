// Shared set-up and helpers of the browser tests: one Chromium and one static server per test
// file, pages that record their problems, waits on the page's hooks, pixel statistics.
import assert from "node:assert/strict";
import { existsSync, mkdirSync } from "node:fs";
import { dirname, join } from "node:path";
import { after, before } from "node:test";
import { fileURLToPath } from "node:url";

import { launch } from "./browser.mjs";
import { serve } from "./server.mjs";

export const ROOT = join(dirname(fileURLToPath(import.meta.url)), "..", "..");
export const ARTIFACTS = join(ROOT, "artifacts", "browser");
/** Generous: the machine may be busy, and a cold start compiles a few MB of wasm. */
export const TIMEOUT = 60_000;

let browser;
/** The server's virtual files by path: a test may add its own before it opens a page. */
export const virtualFiles = {};
/** The static server of the repository root (its `url` ends with a slash). */
export let server;

before(async () => {
  assert.ok(
    existsSync(join(ROOT, "pkg", "dmbn.js")),
    "no web package in pkg/: build it with `wasm-pack build --release --target web --out-dir pkg --no-typescript`",
  );
  mkdirSync(ARTIFACTS, { recursive: true });
  browser = await launch();
  // 200 random-looking bytes: not a model file.
  const corrupt = Buffer.from(Array.from({ length: 200 }, (_, i) => (i * 73 + 41) % 256));
  virtualFiles["/test/corrupt.dmbn"] = corrupt;
  server = await serve(ROOT, { files: virtualFiles });
});

after(async () => {
  await browser?.close();
  await server?.close();
});

/** A fresh page (own context, empty cache) that records console errors and uncaught exceptions. */
export async function open(url, { init, viewport = { width: 1280, height: 940 } } = {}) {
  const context = await browser.newContext({ viewport });
  const page = await context.newPage();
  page.setDefaultTimeout(TIMEOUT);
  page.problems = [];
  page.on("pageerror", (err) => page.problems.push(`pageerror: ${err.message}`));
  page.on("console", (msg) => {
    if (msg.type() === "error") page.problems.push(`console: ${msg.text()}`);
  });
  if (init) await page.addInitScript(init);
  await page.goto(url);
  return page;
}

export const close = (page) => page.context().close();
export const shot = (page, name) => page.screenshot({ path: join(ARTIFACTS, `${name}.png`) });
export const state = (page) => page.evaluate(() => document.body.dataset.state);
export const errorText = (page) => page.locator("#error").textContent();

/** Waits for `wanted`; fails at once, with the page's message, when the page shows an error instead. */
export async function waitState(page, wanted) {
  // The state that ended the wait, not one read after it: live mode's playback moves on.
  const reached = await page.waitForFunction(
    (w) => [w, "error"].includes(document.body.dataset.state) && document.body.dataset.state,
    wanted,
    { timeout: TIMEOUT },
  );
  const now = await reached.jsonValue();
  if (now !== wanted) assert.fail(`expected state ${wanted}, got ${now}: ${await errorText(page)}`);
}

/** Predicts (button) and waits until a new prediction has finished. */
export async function predict(page, trigger = () => page.click("#predict")) {
  const before = await page.evaluate(() => Number(document.body.dataset.predictions ?? 0));
  await trigger();
  await page.waitForFunction(
    (n) => Number(document.body.dataset.predictions ?? 0) > n || document.body.dataset.state === "error",
    before,
    { timeout: TIMEOUT },
  );
  await waitState(page, "predicted");
}

/** Statistics of a canvas's pixels: mean and standard deviation of the RGB values, and a hash. */
export function pixels(page, id) {
  return page.evaluate((id) => {
    const c = document.getElementById(id);
    const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
    let sum = 0;
    let sq = 0;
    let n = 0;
    let hash = 2166136261;
    for (let i = 0; i < d.length; i++) {
      if (i % 4 === 3) continue;
      sum += d[i];
      sq += d[i] * d[i];
      n++;
      hash = Math.imul(hash ^ d[i], 16777619) >>> 0;
    }
    const mean = sum / n;
    return { mean, std: Math.sqrt(Math.max(0, sq / n - mean * mean)), hash };
  }, id);
}

/** The predicted output at a fixed step: frame, σ map and joint plot. */
export async function output(page, step = 20) {
  await page.locator("#scrubber").fill(String(step));
  const frame = await pixels(page, "frame-pred");
  const sigma = await pixels(page, "sigma-map");
  const plot = await pixels(page, "joints-plot");
  return `${frame.hash}/${sigma.hash}/${plot.hash}`;
}

/** Polls a Node-side condition (what page.waitForFunction does in the page). */
export async function waitFor(condition, what, timeout = TIMEOUT) {
  const end = Date.now() + timeout;
  while (!condition()) {
    if (Date.now() > end) assert.fail(`timed out waiting for ${what}`);
    await new Promise((ok) => setTimeout(ok, 50));
  }
}

/**
 * Runs in the page or in a worker: counts the calls of the wasm package's `Model.encode`,
 * `decode` and `predict` in that thread (into `self.inferenceCalls`), by patching the package
 * instance the thread imported (the same URL resolves to the same module). In the page, that
 * it is the initialised instance shows in `placementRegion` answering without an init call;
 * in the workers, in the calls counted.
 */
export async function countInference() {
  const base = self.document ? document.baseURI : self.location.href;
  const pkg = await import(new URL("../pkg/dmbn.js", base).href);
  if (self.document) pkg.placementRegion();
  const calls = (self.inferenceCalls = { encode: 0, decode: 0, predict: 0, decodedTargets: 0 });
  const proto = pkg.Model.prototype;
  for (const name of ["encode", "decode", "predict"]) {
    const original = proto[name];
    proto[name] = function (...args) {
      calls[name]++;
      if (name === "decode") calls.decodedTargets += args[1].length;
      return original.apply(this, args);
    };
  }
}

/**
 * The largest per-channel difference between the #frame-pred canvas (drawn at the model's
 * resolution, so no scaling) and the wasm API's mean frame `k`, predicted in the page from the
 * weights `file` and the observations the URL names (episode by action and seed, mode t,
 * images + joints); also against another step's frame and another model's, which must differ.
 */
export function drawnAgainstWasm(page, k, file, { otherStep, otherModel }) {
  return page.evaluate(
    async ({ k, file, otherStep, otherModel }) => {
      const pkg = await import(new URL("../pkg/dmbn.js", document.baseURI).href);
      await pkg.default({ module_or_path: new URL("../pkg/dmbn_bg.wasm", document.baseURI) });
      const q = new URLSearchParams(location.search);
      if (q.get("mode") !== "t" || q.get("observe") !== "both" || q.has("x")) throw new Error(`not the inputs computed here: ${q}`);
      const seed = Number(q.get("seed"));
      const steps = q.get("obs").split(",").map(Number);
      const canvas = document.getElementById("frame-pred");
      const episode = pkg.runEpisode(q.get("action"), seed, canvas.width);
      const ev = episode.evalSequence("t", seed);
      const S = canvas.width;
      const px = S * S * 3;
      const all = { frames: ev.frames(), joints: ev.joints(), times: ev.times() };
      const frames = new Uint8Array(steps.length * px);
      const joints = new Float32Array(steps.length * 7);
      steps.forEach((s, i) => {
        frames.set(all.frames.subarray(s * px, (s + 1) * px), i * px);
        joints.set(all.joints.subarray(s * 7, (s + 1) * 7), i * 7);
      });
      const times = Float32Array.from(steps, (s) => all.times[s]);
      const predict = async (name) => {
        const bytes = new Uint8Array(await (await fetch(`../assets/models/${name}`)).arrayBuffer());
        const model = pkg.Model.fromBytes(bytes);
        if (model.imageSize !== S) throw new Error(`${name} predicts ${model.imageSize}×${model.imageSize} frames, the canvas is ${S}×${S}`);
        const p = model.predict(frames, joints, times, all.times, 0.5);
        model.free();
        return p;
      };
      const drawn = canvas.getContext("2d").getImageData(0, 0, S, S).data;
      const largest = (rgb) => {
        let worst = 0;
        for (let i = 0; i < S * S; i++) {
          for (let c = 0; c < 3; c++) worst = Math.max(worst, Math.abs(drawn[4 * i + c] - rgb[3 * i + c]));
        }
        return worst;
      };
      const same = await predict(file);
      const other = await predict(otherModel);
      const out = { expected: largest(same.meanFrame(k)), otherStep: largest(same.meanFrame(otherStep)), otherModel: largest(other.meanFrame(k)) };
      same.free();
      other.free();
      ev.free();
      episode.free();
      return out;
    },
    { k, file, otherStep, otherModel },
  );
}

/** The number of the page's latest logged event (www/hooks.js: `window.dmbnEvents`), 0 before any. */
export const lastEvent = (page) => page.evaluate(() => window.dmbnEvents.at(-1)?.n ?? 0);

/** The page's logged events after event number `since`, in order. */
export const eventsSince = (page, since = 0) => page.evaluate((n) => window.dmbnEvents.filter((e) => e.n > n), since);

/** How a prediction ended, in the event log. */
export const ENDS = ["finished", "cancelled", "failed"];

/**
 * Checks the life of every prediction in the event log `log` (from the page's start): one runs
 * at a time (a prediction starts only after the one before ended), its chunks are stored only
 * while it runs, and only the latest one started is drawn, never once it was cancelled.
 * Returns {id → {start, end, chunks, drawn}}.
 */
export function lifecycles(log) {
  const lives = new Map();
  let running = null;
  let latest = null;
  for (const e of log) {
    if (e.type === "start") {
      assert.equal(running, null, `prediction ${e.id} started while ${running} was running (event ${e.n})`);
      running = latest = e.id;
      lives.set(e.id, { start: e, end: null, chunks: 0, drawn: 0 });
    } else if (ENDS.includes(e.type)) {
      assert.equal(e.id, running, `prediction ${e.id} ${e.type} while ${running} was the one running (event ${e.n})`);
      lives.get(e.id).end = e;
      running = null;
    } else if (e.type === "chunk") {
      assert.equal(e.id, running, `a chunk of prediction ${e.id} stored while ${running} was the one running (event ${e.n})`);
      lives.get(e.id).chunks++;
    } else if (e.type === "drawn") {
      assert.equal(e.id, latest, `prediction ${e.id} drawn after ${latest} started (event ${e.n})`);
      assert.notEqual(lives.get(e.id).end?.type, "cancelled", `prediction ${e.id} drawn after it was cancelled (event ${e.n})`);
      lives.get(e.id).drawn++;
    }
  }
  return lives;
}

/** Stops playback, so frames only change when a test asks. */
export async function pause(page) {
  if ((await page.getAttribute("#play", "aria-pressed")) === "true") await page.click("#play");
}

