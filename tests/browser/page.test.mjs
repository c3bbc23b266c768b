// Browser tests of the demo page (www/) in headless Chromium, driven by playwright-core.
// Needs the web package: `wasm-pack build --release --target web --out-dir pkg`, then
// `node --test tests/browser/` (`.ci/run` does both). Screenshots go to artifacts/browser/.
import assert from "node:assert/strict";
import { existsSync, mkdirSync } from "node:fs";
import { dirname, join } from "node:path";
import { after, before, describe, test } from "node:test";
import { fileURLToPath } from "node:url";

import { launch } from "./browser.mjs";
import { serve } from "./server.mjs";

const ROOT = join(dirname(fileURLToPath(import.meta.url)), "..", "..");
const ARTIFACTS = join(ROOT, "artifacts", "browser");
/** Generous: the machine may be busy, and a cold start compiles a few MB of wasm. */
const TIMEOUT = 60_000;

let browser;
let server;

before(async () => {
  assert.ok(
    existsSync(join(ROOT, "pkg", "dmbn.js")),
    "no web package in pkg/: build it with `wasm-pack build --release --target web --out-dir pkg --no-typescript`",
  );
  mkdirSync(ARTIFACTS, { recursive: true });
  browser = await launch();
  // 200 random-looking bytes: not a model file.
  const corrupt = Buffer.from(Array.from({ length: 200 }, (_, i) => (i * 73 + 41) % 256));
  server = await serve(ROOT, { files: { "/test/corrupt.dmbn": corrupt } });
});

after(async () => {
  await browser?.close();
  await server?.close();
});

/** A fresh page (own context, empty cache) that records console errors and uncaught exceptions. */
async function open(url, { init, viewport = { width: 1280, height: 940 } } = {}) {
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

const close = (page) => page.context().close();
const shot = (page, name) => page.screenshot({ path: join(ARTIFACTS, `${name}.png`) });
const state = (page) => page.evaluate(() => document.body.dataset.state);
const errorText = (page) => page.locator("#error").textContent();

/** Waits for `wanted`; fails at once, with the page's message, when the page shows an error instead. */
async function waitState(page, wanted) {
  await page.waitForFunction(
    (w) => document.body.dataset.state === w || document.body.dataset.state === "error",
    wanted,
    { timeout: TIMEOUT },
  );
  const now = await state(page);
  if (now !== wanted) assert.fail(`expected state ${wanted}, got ${now}: ${await errorText(page)}`);
}

/** Predicts (button) and waits until a new prediction has finished. */
async function predict(page, trigger = () => page.click("#predict")) {
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
function pixels(page, id) {
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
async function output(page, step = 20) {
  await page.locator("#scrubber").fill(String(step));
  const frame = await pixels(page, "frame-pred");
  const sigma = await pixels(page, "sigma-map");
  const plot = await pixels(page, "joints-plot");
  return `${frame.hash}/${sigma.hash}/${plot.hash}`;
}

/** Polls a Node-side condition (what page.waitForFunction does in the page). */
async function waitFor(condition, what, timeout = TIMEOUT) {
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
async function countInference() {
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
function drawnAgainstWasm(page, k, file, { otherStep, otherModel }) {
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

/** Stops playback, so frames only change when a test asks. */
async function pause(page) {
  if ((await page.getAttribute("#play", "aria-pressed")) === "true") await page.click("#play");
}

describe("demo page", () => {
  test("loads to ready, with every control labelled", async () => {
    const page = await open(`${server.url}www/`);
    await waitState(page, "ready");
    for (const id of ["action", "model", "mode", "observe", "predict", "scrubber", "frame-true", "frame-pred", "sigma-map", "joints-plot", "error"]) {
      assert.equal(await page.locator(`#${id}`).count(), 1, `#${id} is on the page`);
    }
    assert.equal(await page.locator("#error").isHidden(), true);
    const unlabelled = await page.evaluate(() =>
      [...document.querySelectorAll("input, select, button")]
        .filter((el) => !(el.labels?.length || el.getAttribute("aria-label") || el.textContent.trim()))
        .map((el) => el.id),
    );
    assert.deepEqual(unlabelled, []);
    // Four models, the attentive one first and chosen: the page loads it.
    const options = await page.evaluate(() => [...document.getElementById("model").options].map((o) => o.value));
    assert.deepEqual(options, ["attn", "dmbn", "pte", "pte-aug"]);
    assert.equal(await page.inputValue("#model"), "attn");
    const timings = await page.evaluate(() => window.dmbnTimings);
    assert.ok(timings.ready_ms > 0 && timings.models.attn.bytes > 0);
    assert.equal(timings.models.attn.fileKind, "attn");
    assert.deepEqual(Object.keys(timings.models), ["attn"], "only the default model is loaded");
    const status = await page.textContent("#status");
    assert.match(status, /^Attentive \(DMBN-PTE \+ attention\) ready: attn-sim\.dmbn, [\d.]+ MB/);
    assert.doesNotMatch(status, /note/);
    await shot(page, "ready");
    assert.deepEqual(page.problems, []);
    await close(page);
  });

  test("the server root leads to the page", async () => {
    const page = await open(server.url);
    await page.waitForURL(/\/www\/(\?.*)?$/);
    await waitState(page, "ready");
    await close(page);
  });

  test("works under a path prefix", async () => {
    const prefixed = await serve(ROOT, { prefix: "/some/prefix/" });
    try {
      const page = await open(`${prefixed.url}www/`);
      await waitState(page, "ready");
      await predict(page);
      await close(page);
    } finally {
      await prefixed.close();
    }
  });

  test("an episode animates; action, seed and table clicks make new episodes", async () => {
    const page = await open(`${server.url}www/`);
    await waitState(page, "ready");
    // Playing from step 0 at 20 steps/s.
    const a = await pixels(page, "frame-true");
    const s0 = Number(await page.inputValue("#scrubber"));
    await page.waitForFunction((s) => Number(document.getElementById("scrubber").value) > s + 5, s0);
    const b = await pixels(page, "frame-true");
    assert.notEqual(a.hash, b.hash, "the true frame changes while playing");
    assert.ok(b.std > 5, "the true frame is not blank");
    await shot(page, "animating");

    const episode = () => page.getAttribute("#object-info", "title");
    const first = await episode();
    const switched = Date.now();
    await page.selectOption("#action", "move");
    const moved = await episode();
    assert.notEqual(moved, first, "a new episode for another action");
    // Back to step 0, then playing at 20 steps/s: at most the steps played since the switch (a
    // loaded machine takes longer to answer; a fixed bound failed under load).
    const step = Number(await page.inputValue("#scrubber"));
    const since = Math.ceil((Date.now() - switched) / 50) + 2;
    assert.ok(step <= since, `it plays from the start (step ${step}, ${since} steps since the switch)`);
    await page.fill("#seed", "3");
    await page.press("#seed", "Enter");
    await page.locator("#seed").blur();
    await page.waitForFunction((m) => document.getElementById("object-info").title !== m, moved);
    const seeded = await episode();
    // Click near the left edge of the table map: the object goes there.
    const box = await page.locator("#table").boundingBox();
    await page.mouse.click(box.x + box.width * 0.2, box.y + box.height * 0.5);
    await page.waitForFunction((m) => document.getElementById("object-info").title !== m, seeded);
    const info = await page.textContent("#object-info");
    const x = Number(/object at \((-?[\d.]+),/.exec(info)[1]);
    assert.ok(x < -0.05, `object placed on the left (x = ${x})`);
    assert.match(page.url(), /[?&]x=-0\.\d+/, "the placement is in the URL");
    assert.equal(await state(page), "ready");
    assert.deepEqual(page.problems, []);
    await close(page);
  });

  test("reads at phone width: the joint panels go 2 × 4 and nothing overflows", async () => {
    // The plot's panel grid as drawn (plot.js: gaps of 14 × 12 px, 7 joints + the legend).
    const layout = (page) =>
      page.evaluate(() => {
        const plot = document.getElementById("joints-plot");
        const cols = Number(plot.dataset.columns);
        const rows = Math.ceil(8 / cols);
        return {
          cols,
          width: (plot.clientWidth - 14 * (cols - 1)) / cols,
          height: (plot.clientHeight - 12 * (rows - 1)) / rows,
          overflow: document.documentElement.scrollWidth - window.innerWidth,
        };
      });
    const phone = await open(`${server.url}www/`, { viewport: { width: 390, height: 844 } });
    await waitState(phone, "ready");
    const small = await layout(phone);
    await shot(phone, "phone");
    const wide = await phone.evaluate(() =>
      [...document.querySelectorAll("body *")]
        .filter((el) => el.getBoundingClientRect().right > window.innerWidth + 0.5)
        .map((el) => `${el.tagName.toLowerCase()}${el.id ? "#" + el.id : ""}.${el.className}`)
        .slice(0, 8),
    );
    assert.equal(small.cols, 2, "two columns of panels on a phone");
    assert.ok(small.width >= 150 && small.height >= 100, `each panel ${small.width} × ${small.height} px`);
    assert.ok(small.overflow <= 0, `the page is ${small.overflow} px wider than the screen: ${wide.join(", ")}`);
    assert.deepEqual(phone.problems, []);
    await close(phone);
    const desk = await open(`${server.url}www/`);
    await waitState(desk, "ready");
    assert.equal((await layout(desk)).cols, 4, "four columns on a desktop");
    await close(desk);
  });

  test("keyboard: space plays and pauses, arrows scrub", async () => {
    const page = await open(`${server.url}www/`);
    await waitState(page, "ready");
    await pause(page);
    await page.locator("body").click({ position: { x: 5, y: 5 } });
    await page.keyboard.press("Home");
    assert.equal(await page.inputValue("#scrubber"), "0");
    await page.keyboard.press("ArrowRight");
    await page.keyboard.press("ArrowRight");
    assert.equal(await page.inputValue("#scrubber"), "2");
    await page.keyboard.press("ArrowLeft");
    assert.equal(await page.inputValue("#scrubber"), "1");
    await page.keyboard.press("Space");
    assert.equal(await page.getAttribute("#play", "aria-pressed"), "true");
    await page.keyboard.press("Space");
    assert.equal(await page.getAttribute("#play", "aria-pressed"), "false");
    // Playing moved the step on (how far depends on the machine's speed): back to step 1.
    await page.keyboard.press("Home");
    await page.keyboard.press("ArrowRight");
    assert.equal(await page.inputValue("#scrubber"), "1");
    // Enter on the focused timeline observes the current step (1), and stops observing it.
    const observed = () => page.evaluate(() => new URLSearchParams(location.search).get("obs").split(",").map(Number));
    const before = await observed();
    await page.focus("#timeline");
    await page.keyboard.press("Enter");
    assert.equal((await observed()).includes(1), !before.includes(1));
    await page.keyboard.press("Enter");
    assert.deepEqual(await observed(), before);
    await close(page);
  });

  test("a prediction fills in and shows a predicted frame, a σ map and joint bands", async () => {
    const page = await open(`${server.url}www/?chunkDelay=150`);
    await waitState(page, "ready");
    await pause(page);
    await page.fill("#k", "6");
    await page.click("#random-k");
    await page.click("#predict");
    // Part of the sequence in, the rest still to come, and the page responsive meanwhile.
    await page.waitForFunction(() => Number(document.body.dataset.progress) > 0);
    assert.equal(await state(page), "predicting");
    const progress = Number(await page.evaluate(() => document.body.dataset.progress));
    const len = Number(await page.getAttribute("#scrubber", "max")) + 1;
    assert.ok(progress < len, `progressive: ${progress} of ${len} steps`);
    await page.keyboard.press("Home");
    assert.equal(await page.inputValue("#scrubber"), "0", "the page answers keys while predicting");
    await shot(page, "predicting");
    await waitState(page, "predicted");

    const k = Math.floor(len / 2);
    await page.locator("#scrubber").fill(String(k));
    const frame = await pixels(page, "frame-pred");
    const sigma = await pixels(page, "sigma-map");
    assert.ok(frame.std > 5, `predicted frame is not blank (std ${frame.std.toFixed(1)})`);
    // The drawn frame is the wasm API's mean frame k for the same model and observations, and
    // neither another step's nor another model's.
    // (A tolerance of a few units per channel: the workers decode in chunks, the canvas rounds.)
    const tol = 3;
    const d = await drawnAgainstWasm(page, k, "attn-sim.dmbn", { otherStep: k + 1, otherModel: "dmbn-sim.dmbn" });
    assert.ok(d.expected <= tol, `the drawn frame is Model.predict(…).meanFrame(${k}) (largest channel difference ${d.expected})`);
    assert.ok(d.otherStep > tol, `the next step's frame is told apart (largest difference ${d.otherStep})`);
    assert.ok(d.otherModel > tol, `another model's frame is told apart (largest difference ${d.otherModel})`);
    assert.ok(sigma.std > 1 && sigma.mean > 2, `σ map is not blank (mean ${sigma.mean.toFixed(1)}, std ${sigma.std.toFixed(1)})`);
    const timing = await page.textContent("#timing");
    assert.match(timing, /\d+ steps in \d+ ms \([\d.]+ ms per frame\)/);
    const t = await page.evaluate(() => window.dmbnTimings.prediction);
    assert.equal(t.steps, len);
    assert.ok(t.total_ms > 0 && t.per_frame_ms > 0);
    // The overlay toggles and fades.
    await page.uncheck("#sigma-toggle");
    assert.equal(await page.locator("#sigma-map").isHidden(), true);
    await page.check("#sigma-toggle");
    await page.locator("#sigma-opacity").fill("80");
    assert.equal(await page.evaluate(() => document.getElementById("sigma-map").style.opacity), "0.8");
    await shot(page, "predicted");
    assert.deepEqual(page.problems, []);
    await close(page);
  });

  test("inference runs in the workers and never blocks the page for long", async () => {
    const workers = 2;
    const page = await open(`${server.url}www/?workers=${workers}`);
    await waitState(page, "ready");
    await pause(page);
    // Every worker is up once the page is ready; the counters go into all of them.
    await waitFor(() => page.workers().length === workers, `${workers} workers`);
    await Promise.all(page.workers().map((w) => w.evaluate(countInference)));
    await page.evaluate(countInference);
    const observable = await page.evaluate(() => {
      window.longTasks = [];
      new PerformanceObserver((list) => window.longTasks.push(...list.getEntries().map((e) => [e.startTime, e.duration]))).observe({
        type: "longtask",
      });
      return PerformanceObserver.supportedEntryTypes.includes("longtask");
    });
    assert.ok(observable, "the browser reports long tasks");
    await predict(page);
    const len = await page.evaluate(() => window.dmbnTimings.prediction.steps);
    const inWorkers = await Promise.all(page.workers().map((w) => w.evaluate(() => self.inferenceCalls)));
    const decoded = inWorkers.reduce((n, c) => n + c.decodedTargets, 0);
    // (The workers that have loaded the model by then share the prediction.)
    assert.ok(inWorkers.some((c) => c.decode > 0), `decode calls in the workers: ${JSON.stringify(inWorkers)}`);
    assert.ok(inWorkers.every((c) => (c.decode > 0) === (c.encode > 0) && c.predict === 0), `each worker encodes, then decodes: ${JSON.stringify(inWorkers)}`);
    assert.equal(decoded, len, "the workers decode every step of the sequence, once");
    assert.deepEqual(await page.evaluate(() => window.inferenceCalls), { encode: 0, decode: 0, predict: 0, decodedTargets: 0 }, "the main thread runs no model");

    // A known long task after the prediction shows that the observer records them, and
    // delivers what it saw before.
    // (A task of its own: the observer does not see the test's evaluate calls.)
    const probe = await page.evaluate(
      () =>
        new Promise((ok) =>
          setTimeout(() => {
            const t0 = performance.now();
            while (performance.now() - t0 < 400);
            ok(t0);
          }),
        ),
    );
    await page.waitForFunction(() => window.longTasks.some(([, d]) => d >= 400));
    const tasks = await page.evaluate(() => window.longTasks);
    const longest = Math.max(0, ...tasks.filter(([start, d]) => start + d < probe).map(([, d]) => d));
    assert.ok(longest < 300, `longest main-thread task during a prediction: ${longest} ms`);
    await close(page);
  });

  test("switching model, mode or observed modality changes the output", async () => {
    const page = await open(`${server.url}www/?action=grasp&seed=11&obs=0,8,16,30,44`);
    await waitState(page, "ready");
    await pause(page);
    assert.equal(await page.inputValue("#model"), "attn", "the attentive model is the default");
    await predict(page);
    assert.equal(await page.evaluate(() => window.dmbnTimings.prediction.model), "attn");
    const seen = new Map([["attn t both", await output(page)]]);
    // Each change predicts again (the page is live after the first prediction); a new setting
    // gives a new output, a setting seen before gives the same output again (deterministic).
    const change = async (select, value, label) => {
      await predict(page, () => page.selectOption(select, value));
      const out = await output(page);
      if (seen.has(label)) {
        assert.equal(out, seen.get(label), `${label} again gives the same output`);
        return;
      }
      for (const [other, o] of seen) assert.notEqual(out, o, `${label} differs from ${other}`);
      seen.set(label, out);
      await shot(page, `switch-${label.replaceAll(" ", "-")}`);
    };
    await change("#model", "pte-aug", "pte-aug t both");
    assert.match(page.url(), /model=pte-aug/);
    await change("#model", "pte", "pte t both");
    await change("#mode", "p", "pte p both");
    await change("#mode", "f", "pte f both");
    await change("#model", "dmbn", "dmbn f both");
    await change("#mode", "t", "dmbn t both");
    await change("#model", "attn", "attn t both");
    assert.match(page.url(), /model=attn/);
    await change("#model", "dmbn", "dmbn t both");
    await change("#observe", "joints", "dmbn t joints");
    await change("#observe", "images", "dmbn t images");
    assert.match(page.url(), /model=dmbn.*mode=t.*observe=images/);
    // Clicking a frame on the timeline observes it, and predicts again.
    const box = await page.locator("#timeline").boundingBox();
    const len = Number(await page.getAttribute("#scrubber", "max")) + 1;
    await predict(page, () => page.mouse.click(box.x + box.width * (24.5 / len), box.y + box.height / 2));
    assert.match(page.url(), /obs=0%2C8%2C16%2C24%2C30%2C44/);
    assert.notEqual(await output(page), seen.get("dmbn t images"));
    assert.deepEqual(page.problems, []);
    await close(page);
  });

  test("corrupt weights show a clear error", async () => {
    const page = await open(`${server.url}www/?model=dmbn&dmbn=/test/corrupt.dmbn`);
    await waitState(page, "error");
    const text = await errorText(page);
    assert.match(text, /DMBN weights .*corrupt\.dmbn are corrupt or not a model file/);
    assert.equal(await page.locator("#error").isVisible(), true);
    await shot(page, "error-corrupt-weights");
    await close(page);
    // The default model's file is overridable too (`?attn=`).
    const attn = await open(`${server.url}www/?attn=/test/corrupt.dmbn`);
    await waitState(attn, "error");
    assert.match(await errorText(attn), /Attentive \(DMBN-PTE \+ attention\) weights .*corrupt\.dmbn are corrupt or not a model file/);
    await close(attn);
  });

  test("a file of another kind than the model's is noted", async () => {
    // pte-aug expects a DMBN-PTE file: the shipped DMBN-PTE weights are no mismatch, DMBN's are.
    const page = await open(`${server.url}www/?model=pte-aug&pte-aug=../assets/models/pte-sim.dmbn`);
    await waitState(page, "ready");
    const status = await page.textContent("#status");
    assert.match(status, /^DMBN-PTE \+ time warps ready: pte-sim\.dmbn/);
    assert.doesNotMatch(status, /note/);
    await close(page);
    const other = await open(`${server.url}www/?model=pte-aug&pte-aug=../assets/models/dmbn-sim.dmbn`);
    await waitState(other, "ready");
    assert.match(await other.textContent("#status"), /^DMBN-PTE \+ time warps ready: dmbn-sim\.dmbn.* — note: the file holds a DMBN model$/);
    await close(other);
  });

  test("missing weights show a clear error, and the page recovers with the other model", async () => {
    const page = await open(`${server.url}www/?pte=../assets/models/no-such-file.dmbn&pte-aug=../assets/models/no-such-file-either.dmbn`);
    await waitState(page, "ready");
    await page.selectOption("#model", "pte");
    await waitState(page, "error");
    assert.match(await errorText(page), /DMBN-PTE weights.*HTTP 404/);
    await shot(page, "error-missing-weights");
    await page.selectOption("#model", "pte-aug");
    await waitState(page, "error");
    assert.match(await errorText(page), /DMBN-PTE \+ time warps weights.*no-such-file-either\.dmbn.*HTTP 404/);
    await page.selectOption("#model", "dmbn");
    await waitState(page, "ready");
    assert.equal(await page.locator("#error").isHidden(), true);
    await predict(page);
    await close(page);
  });

  test("a missing wasm package shows a clear error", async () => {
    const broken = await serve(ROOT, { missing: ["/pkg/"] });
    try {
      const page = await open(`${broken.url}www/`);
      await waitState(page, "error");
      assert.match(await errorText(page), /Could not load the WebAssembly package.*wasm-pack build/s);
      await shot(page, "error-no-wasm");
      await close(page);
    } finally {
      await broken.close();
    }
  });

  test("a browser without WebAssembly SIMD gets a clear error", async () => {
    const page = await open(`${server.url}www/`, {
      init: () => {
        const validate = WebAssembly.validate;
        // Reject any module using v128 (the 0x7b value type), like a browser without SIMD.
        WebAssembly.validate = (bytes) => !new Uint8Array(bytes.buffer ?? bytes).includes(0xfd) && validate(bytes);
      },
    });
    await waitState(page, "error");
    assert.match(await errorText(page), /SIMD/);
    await close(page);
  });

  test("a worker that cannot start shows a clear error", async () => {
    const broken = await serve(ROOT, { missing: ["/www/worker.js"] });
    try {
      const page = await open(`${broken.url}www/`);
      await waitState(page, "error");
      assert.match(await errorText(page), /inference worker failed/);
      await close(page);
    } finally {
      await broken.close();
    }
  });
});
