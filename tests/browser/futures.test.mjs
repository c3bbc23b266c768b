// "Imagine S futures" in live and imitate modes: after each prediction a worker samples S
// seeded futures of the same observations; the joint panels draw them as a fan of thin lines,
// the strip their final frames, and in imitate mode the outcome of performing each. The same
// seed gives the same futures (as the wasm Model.sample's), from a link too; 0 turns them off.
import assert from "node:assert/strict";
import { describe, test } from "node:test";

import { close, open, pause, pixels, predict, server, shot, waitState } from "./support.mjs";

/** The futures drawn (www/hooks.js: `window.dmbn.futures()`), or null. */
const futuresOf = (page) => page.evaluate(() => window.dmbn.futures());

/** Sets the futures control to `n` (and its change event: the control is read then). */
async function setFutures(page, n, seed = null) {
  if (seed !== null) await page.fill("#futures-seed", String(seed));
  await page.fill("#futures", String(n));
  await page.locator("#futures").dispatchEvent("change");
}

/**
 * Live mode, paused at `step`: waits until the forecast from what it has seen has finished (a
 * forecast of the same steps made while playing may be replaced by a new one) and its futures
 * are drawn.
 */
async function liveFuturesAt(page, step, every = 10) {
  await page.locator("#scrubber").fill(String(step));
  const from = Math.floor(step / every) * every + 1;
  await page.waitForFunction((from) => {
    const { state } = document.body.dataset;
    const last = window.dmbnEvents.findLast((e) => e.type === "finished");
    return (state === "predicted" && last?.from === from && window.dmbn.futures()?.id === last.id) || state === "error";
  }, from);
  assert.notEqual(await page.getAttribute("body", "data-state"), "error", await page.textContent("#error"));
  return futuresOf(page);
}

/** The largest difference between two rows of numbers. */
const largest = (a, b) => a.reduce((m, v, i) => Math.max(m, Math.abs(v - b[i])), 0);

/**
 * The same futures: the same draws, up to float rounding (a worker encodes the observations
 * one by one or together, as it happened to meet them: the last bits differ).
 */
function assertSameFutures(got, want, what) {
  assert.equal(got.length, want.length, what);
  got.forEach((rows, s) => assert.ok(largest(rows, want[s]) < 1e-4, `${what}: future ${s} differs by ${largest(rows, want[s])}`));
}

describe("sampled futures", () => {
  test("live mode: a fan of S distinct futures, the same as Model.sample's, from a link too; 0 removes it", async () => {
    const url = `${server.url}www/?mode=live&action=grasp&seed=11&every=10&futures=8&fseed=3`;
    const page = await open(url);
    await page.waitForFunction(() => ["predicting", "predicted", "error"].includes(document.body.dataset.state));
    await pause(page);
    assert.equal(await page.inputValue("#futures"), "8");
    assert.equal(await page.locator("#futures-controls").isVisible(), true);
    const f = await liveFuturesAt(page, 12);
    const len = Number(await page.getAttribute("#scrubber", "max")) + 1;
    assert.equal(f.samples, 8);
    assert.equal(f.seed, 3);
    assert.equal(f.steps, len - 11);
    assert.equal(f.joints.length, 8);
    for (const rows of f.joints) assert.equal(rows.length, f.steps * f.jointCount);
    // Each future its own trajectory, none the mean.
    for (let a = 0; a < 8; a++) {
      assert.ok(largest(f.joints[a], f.mean) > 1e-3, `future ${a} is not the mean`);
      for (let b = 0; b < a; b++) assert.ok(largest(f.joints[a], f.joints[b]) > 1e-3, `futures ${a} and ${b} differ`);
    }
    assert.equal(await page.getAttribute("body", "data-futures"), "8");
    assert.equal(await page.locator("#futures-strip .future canvas").count(), 8, "a final frame per future");
    assert.equal(f.outcomes, null, "live mode performs nothing");
    // What the wasm API samples for the same observations (steps 0 and 10 seen), seed and blend.
    const direct = await page.evaluate(async ({ from }) => {
      const pkg = await import(new URL("../pkg/dmbn.js", document.baseURI).href);
      const ep = pkg.runEpisode("grasp", 11, 64);
      const model = pkg.Model.fromBytes(new Uint8Array(await (await fetch("../assets/models/attn-sim.dmbn")).arrayBuffer()));
      const steps = [0, 10];
      const frames = new Uint8Array(steps.length * 64 * 64 * 3);
      steps.forEach((s, i) => frames.set(ep.frame(s), i * 64 * 64 * 3));
      const joints = Float32Array.from(steps.flatMap((s) => Array.from(ep.joints().subarray(s * 7, s * 7 + 7))));
      const times = ep.times();
      const contexts = model.encodeContexts(frames, joints, Float32Array.from(steps, (s) => times[s]));
      const targets = times.slice(from);
      const sampled = model.sample(contexts, targets, 0.5, 8, 3);
      const both = model.sampleWithFrames(contexts, targets, 0.5, 8, 3);
      return { sampled: Array.from(sampled), same: both.joints.every((v, i) => v === sampled[i]), frames: both.frames.length };
    }, { from: 11 });
    assert.equal(direct.same, true, "sampleWithFrames's joints are sample's");
    assert.equal(direct.frames, 8 * 64 * 64 * 3);
    assert.ok(largest(f.joints.flat(), direct.sampled) < 1e-4, "the page's futures are Model.sample's");
    await page.waitForFunction(() => /futures=8&fseed=3/.test(location.search));
    const fan = (await pixels(page, "joints-plot")).hash;
    await shot(page, "futures-live");

    // Off: the fan and the strip go, the panels are the forecast's alone; the link forgets them.
    await setFutures(page, 0);
    await page.waitForFunction(() => document.body.dataset.futures === "0");
    assert.equal(await futuresOf(page), null);
    assert.equal(await page.locator("#futures-panel").isHidden(), true);
    assert.notEqual((await pixels(page, "joints-plot")).hash, fan, "the fan is gone");
    await page.waitForFunction(() => !/futures=/.test(location.search));
    // Another seed, other futures; back to seed 3, the same ones.
    await setFutures(page, 8, 4);
    await page.waitForFunction(() => window.dmbn.futures()?.seed === 4);
    const other = await futuresOf(page);
    assert.ok(largest(other.joints[0], f.joints[0]) > 1e-3, "seed 4 draws other futures");
    await setFutures(page, 8, 3);
    await page.waitForFunction(() => window.dmbn.futures()?.seed === 3);
    assertSameFutures((await futuresOf(page)).joints, f.joints, "seed 3 again");
    assert.deepEqual(page.problems, []);
    await close(page);

    // The link: the same futures after a reload.
    const again = await open(url);
    await again.waitForFunction(() => ["predicting", "predicted", "error"].includes(document.body.dataset.state));
    await pause(again);
    assertSameFutures((await liveFuturesAt(again, 12)).joints, f.joints, "the same seed from the link");
    assert.deepEqual(again.problems, []);
    await close(again);
  }, { timeout: 240_000 });

  test("imitate mode: each future performed, its outcome in the strip, a click performs it", async () => {
    const first = await open(`${server.url}www/?mode=imitate&action=grasp&seed=11`);
    await waitState(first, "ready");
    const obs = new URL(first.url()).searchParams.get("obs");
    await close(first);
    const page = await open(`${server.url}www/?mode=imitate&action=grasp&seed=11&obs=${obs}&observe=both&futures=4&fseed=1`);
    await waitState(page, "ready");
    await pause(page);
    const imagined = async () => Number((await page.getAttribute("body", "data-imagined")) ?? 0);
    const before = await imagined();
    await predict(page);
    await page.waitForFunction((n) => Number(document.body.dataset.imagined ?? 0) > n, before);
    const f = await futuresOf(page);
    assert.equal(f.samples, 4);
    assert.equal(f.from, 0, "whole trajectories");
    assert.equal(f.outcomes.length, 4);
    for (const label of f.outcomes) assert.ok(["carried", "lifted", "landed", "pushed", "missed"].includes(label), label);
    assert.ok(largest(f.joints[0], f.joints[1]) > 1e-3, "the futures differ");
    const cells = page.locator("#futures-strip button.future");
    assert.equal(await cells.count(), 4);
    assert.deepEqual(await cells.evaluateAll((els) => els.map((e) => e.dataset.outcome)), f.outcomes);
    assert.equal(await page.getAttribute("body", "data-performed"), "imagined");
    // A click performs future 2 on the right frame; another click goes back to the imagined mean.
    await cells.nth(2).click();
    await page.waitForFunction(() => document.body.dataset.performed === "future");
    assert.equal(await page.getAttribute("body", "data-future"), "2");
    assert.match(await page.textContent("#imitate-info"), /^Future 3 of the 4 it imagined \(seed 1\), performed: joint RMSE/);
    assert.equal(await page.textContent("#pred-label"), "future 3");
    const summary = await page.textContent("#outcome");
    assert.ok((await cells.nth(2).getAttribute("title")).includes(summary), `the strip's future 3 is the one performed: ${summary}`);
    await shot(page, "futures-imitate");
    await cells.nth(2).click();
    await page.waitForFunction(() => document.body.dataset.performed === "imagined");
    // Frames only (imitate mode's default): the joints drawn step by step weigh nothing (blend
    // 1), so the autoregressive futures coincide, and the page says so (when they do).
    const done = await imagined();
    await page.selectOption("#observe", "images");
    await page.waitForFunction((n) => Number(document.body.dataset.imagined ?? 0) > n, done);
    const still = await futuresOf(page);
    const same = still.joints.every((rows) => largest(rows, still.joints[0]) === 0);
    const note = await page.textContent("#futures-info");
    if (same) assert.match(note, /they coincide — frames only \(blend 1\)/);
    else assert.doesNotMatch(note, /coincide/);
    assert.deepEqual(page.problems, []);
    await close(page);
  }, { timeout: 240_000 });
});
