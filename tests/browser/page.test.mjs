// Browser tests of the demo page (www/) in headless Chromium, driven by playwright-core.
// Needs the web package: `wasm-pack build --release --target web --out-dir pkg`, then
// `node --test tests/browser/` (`.ci/run` does both). Screenshots go to artifacts/browser/.
import assert from "node:assert/strict";
import { describe, test } from "node:test";

import { serve } from "./server.mjs";
import {
  close,
  countInference,
  drawnAgainstWasm,
  errorText,
  eventsSince,
  lastEvent,
  open,
  output,
  pause,
  pixels,
  predict,
  ROOT,
  server,
  shot,
  state,
  waitFor,
  waitState,
} from "./support.mjs";

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
    // It played from step 0 at load; from step 0 again (a slow load may have played it all).
    const loaded = (await eventsSince(page)).filter((e) => e.type === "step");
    assert.equal(loaded[0]?.step, 0, "it plays from the start at load");
    await pause(page);
    await page.keyboard.press("Home");
    const a = await pixels(page, "frame-true");
    await page.click("#play");
    await page.waitForFunction(() => Number(document.getElementById("scrubber").value) > 5);
    const b = await pixels(page, "frame-true");
    assert.notEqual(a.hash, b.hash, "the true frame changes while playing");
    assert.ok(b.std > 5, "the true frame is not blank");
    await shot(page, "animating");

    const episode = () => page.getAttribute("#object-info", "title");
    const first = await episode();
    const mark = await lastEvent(page);
    await page.selectOption("#action", "move");
    const moved = await episode();
    assert.notEqual(moved, first, "a new episode for another action");
    // The new episode plays from step 0, forward (the page's event log, in order).
    await page.waitForFunction(() => Number(document.getElementById("scrubber").value) > 0);
    const log = (await eventsSince(page, mark)).filter((e) => ["episode", "step"].includes(e.type));
    assert.deepEqual(log.filter((e) => e.type === "episode").map((e) => `episode sha256 ${e.digest}`), [moved], "one new episode");
    const steps = log.slice(log.findIndex((e) => e.type === "episode") + 1).map((e) => e.step);
    assert.equal(steps[0], 0, `it plays from the start: ${steps.join(", ")}`);
    assert.ok(steps.length > 1 && steps.every((s, i) => i === 0 || s > steps[i - 1]), `and on: ${steps.join(", ")}`);
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
    const lastEvent = () => page.evaluate(() => window.dmbnEvents.at(-1)?.n ?? 0);
    await page.keyboard.press("Space");
    assert.equal(await page.getAttribute("#play", "aria-pressed"), "true");
    const since = await lastEvent();
    await page.keyboard.press("Space");
    // Space pauses what plays; if the playback reached the last step and stopped itself
    // between the two presses (a slow machine), the second Space plays it again instead.
    const ended = await page.evaluate(
      (n) => window.dmbnEvents.some((e) => e.n > n && e.type === "step" && e.step === Number(document.querySelector("#scrubber").max)),
      since,
    );
    assert.equal(await page.getAttribute("#play", "aria-pressed"), ended ? "true" : "false");
    if (ended) await page.keyboard.press("Space");
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
    const page = await open(`${server.url}www/`);
    await waitState(page, "ready");
    await pause(page);
    await page.fill("#k", "6");
    await page.click("#random-k");
    // The workers' replies held: the first chunk is handed on, the rest still to come.
    await page.evaluate(() => window.dmbn.hold());
    await page.click("#predict");
    await page.waitForFunction(() => window.dmbn.held() > 0);
    await page.evaluate(() => window.dmbn.release(1));
    // Part of the sequence in and drawn, the rest still to come, and the page responsive meanwhile.
    await page.waitForFunction(() => Number(document.body.dataset.progress) > 0);
    assert.equal(await state(page), "predicting");
    const progress = Number(await page.evaluate(() => document.body.dataset.progress));
    const len = Number(await page.getAttribute("#scrubber", "max")) + 1;
    assert.ok(progress <= 10 && progress < len, `progressive: one chunk in, ${progress} of ${len} steps`);
    await page.keyboard.press("Home");
    assert.equal(await page.inputValue("#scrubber"), "0", "the page answers keys while predicting");
    assert.equal(await state(page), "predicting");
    await shot(page, "predicting");
    await page.evaluate(() => window.dmbn.resume());
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

  test("inference runs in the workers, not on the page's thread", async () => {
    const workers = 2;
    const page = await open(`${server.url}www/?workers=${workers}`);
    await waitState(page, "ready");
    await pause(page);
    // Every worker is up once the page is ready; the counters go into all of them.
    await waitFor(() => page.workers().length === workers, `${workers} workers`);
    await Promise.all(page.workers().map((w) => w.evaluate(countInference)));
    await page.evaluate(countInference);
    await predict(page);
    const len = await page.evaluate(() => window.dmbnTimings.prediction.steps);
    const inWorkers = await Promise.all(page.workers().map((w) => w.evaluate(() => self.inferenceCalls)));
    const decoded = inWorkers.reduce((n, c) => n + c.decodedTargets, 0);
    // (The workers that have loaded the model by then share the prediction.)
    assert.ok(inWorkers.some((c) => c.decode > 0), `decode calls in the workers: ${JSON.stringify(inWorkers)}`);
    assert.ok(inWorkers.every((c) => (c.decode > 0) === (c.encode > 0) && c.predict === 0), `each worker encodes, then decodes: ${JSON.stringify(inWorkers)}`);
    assert.equal(decoded, len, "the workers decode every step of the sequence, once");
    assert.deepEqual(await page.evaluate(() => window.inferenceCalls), { encode: 0, decode: 0, predict: 0, decodedTargets: 0 }, "the main thread runs no model");
    // (How long the main thread is busy meanwhile is bench/page.mjs's to measure.)
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
