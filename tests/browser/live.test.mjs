// Browser tests of the page's live mode: the episode plays, the steps seen so far are the
// observations, and the rest of the action is forecast again as they come in.
import assert from "node:assert/strict";
import { describe, test } from "node:test";

import { close, countInference, open, pause, pixels, server, shot, waitFor } from "./support.mjs";

/** Live-mode forecasts finished so far (the page's counter). */
const forecasts = (page) => page.evaluate(() => Number(document.body.dataset.predictions ?? 0));

/** Goes to `step` (paused) and waits until the forecast from the observations seen there has finished. */
async function forecastAt(page, step) {
  await page.locator("#scrubber").fill(String(step));
  await page.waitForFunction(
    (step) => {
      const every = Number(document.getElementById("live-every").value);
      const from = Math.floor(step / every) * every + 1;
      const last = window.dmbnTimings.live.at(-1);
      return (last && last.from === from && document.body.dataset.state === "predicted") || document.body.dataset.state === "error";
    },
    step,
  );
  return page.evaluate(() => window.dmbnTimings.live.at(-1));
}

describe("live mode", () => {
  test("the forecast updates while the episode plays, and the page stays responsive", async () => {
    const page = await open(`${server.url}www/?mode=live&action=grasp&seed=11&every=10&workers=2`);
    await page.waitForFunction(() => ["predicting", "predicted", "error"].includes(document.body.dataset.state));
    assert.equal(await page.inputValue("#mode"), "live");
    assert.equal(await page.locator("#error-panel").isHidden(), false, "the live error plot is shown");
    assert.equal(await page.locator("#random-k").isDisabled(), true, "the rule chooses the observations");
    await waitFor(() => page.workers().length === 2, "2 workers");
    await page.evaluate(countInference);
    await page.evaluate(() => {
      window.longTasks = [];
      new PerformanceObserver((list) => window.longTasks.push(...list.getEntries().map((e) => e.duration))).observe({ type: "longtask" });
    });
    // From the start: play, and watch the seen steps and the forecasts come in.
    await pause(page);
    await page.keyboard.press("Home");
    const before = await forecasts(page);
    // Recorded in the page: the steps seen and the forecast's progress at every change of
    // the hooks, and a hash of the forecast frame on screen at every animation frame.
    await page.evaluate(() => {
      window.liveLog = [];
      window.frameHashes = new Set();
      new MutationObserver(() => {
        window.liveLog.push([Number(document.body.dataset.seen), Number(document.body.dataset.progress)]);
      }).observe(document.body, { attributes: true, attributeFilter: ["data-seen", "data-progress"] });
      const canvas = document.getElementById("frame-pred");
      const sample = () => {
        const d = canvas.getContext("2d").getImageData(0, 0, canvas.width, canvas.height).data;
        let hash = 2166136261;
        for (let i = 0; i < d.length; i += 7) hash = Math.imul(hash ^ d[i], 16777619) >>> 0;
        window.frameHashes.add(hash);
        if (!window.sampled) requestAnimationFrame(sample);
      };
      requestAnimationFrame(sample);
    });
    await page.click("#play");
    await page.waitForFunction(() => document.getElementById("play").getAttribute("aria-pressed") === "false");
    const log = await page.evaluate(() => window.liveLog);
    const seen = log.map(([from]) => from);
    const drawn = new Set(log.filter(([, progress]) => progress > 0).map(([from]) => from));
    const frames = await page.evaluate(() => ((window.sampled = true), window.frameHashes.size));
    const len = Number(await page.getAttribute("#scrubber", "max")) + 1;
    assert.equal(await page.inputValue("#scrubber"), String(len - 1), "it played to the end");
    assert.ok(new Set(seen).size >= 4, `the seen steps advanced while playing: ${[...new Set(seen)].join(", ")}`);
    assert.ok(seen.every((s, i) => i === 0 || s >= seen[i - 1]), `and only forward: ${seen.join(", ")}`);
    // Each new observation's forecast starts drawing while the episode plays on (a slow
    // machine may not finish one before the next observation cancels it; the last one ends).
    assert.ok(drawn.size >= 3, `forecasts drawn while playing, by steps seen: ${[...drawn].join(", ")}`);
    await page.waitForFunction(() => document.body.dataset.state === "predicted");
    assert.ok((await forecasts(page)) > before, "the last forecast finished");
    assert.ok(frames >= 3, `the forecast frame changed as observations came in (${frames} different)`);
    const calls = await page.evaluate(() => window.inferenceCalls);
    assert.deepEqual(calls, { encode: 0, decode: 0, predict: 0, decodedTargets: 0 }, "the main thread runs no model");
    const longest = Math.max(0, ...(await page.evaluate(() => window.longTasks)));
    assert.ok(longest < 300, `longest main-thread task while playing live: ${longest} ms`);
    assert.ok(Number(await page.getAttribute("#error-plot", "data-points")) >= 1, "the error plot has the finished forecasts");
    await shot(page, "live");
    assert.deepEqual(page.problems, []);
    await close(page);
  });

  test("pausing and scrubbing: the forecast follows the seen steps, and its error falls as more of a grasp is seen", async () => {
    const page = await open(`${server.url}www/?mode=live&action=grasp&seed=11&every=5`);
    await page.waitForFunction(() => ["predicting", "predicted", "error"].includes(document.body.dataset.state));
    await pause(page);
    const len = Number(await page.getAttribute("#scrubber", "max")) + 1;
    const early = await forecastAt(page, 2);
    assert.equal(early.from, 1, "at step 2, only step 0 is observed");
    assert.equal(early.steps, len - 1, "and the forecast covers the rest");
    assert.equal(await page.textContent("#obs-info"), "live: the 1 step seen so far, every 5: 0");
    const earlyFrame = (await pixels(page, "frame-pred")).hash;
    const middle = await forecastAt(page, 27);
    assert.equal(middle.from, 26);
    assert.equal(middle.observed, 6);
    const late = await forecastAt(page, len - 12);
    assert.notEqual((await pixels(page, "frame-pred")).hash, earlyFrame, "the forecast frame follows the step");
    assert.ok(late.joint_rmse < early.joint_rmse, `joint RMSE of the rest falls: ${early.joint_rmse} → ${late.joint_rmse}`);
    assert.ok(late.image_mse < early.image_mse, `image MSE of the rest falls: ${early.image_mse} → ${late.image_mse}`);
    // Scrubbing back observes less again.
    const again = await forecastAt(page, 7);
    assert.equal(again.from, 6);
    assert.equal(await page.getAttribute("#play", "aria-pressed"), "false", "scrubbing keeps it paused");
    // A stale forecast is dropped, not queued: many steps at once leave one forecast running.
    const finished = await forecasts(page);
    for (const step of [12, 17, 22, 33, 38]) await page.locator("#scrubber").fill(String(step));
    await page.waitForFunction(() => document.body.dataset.state === "predicted");
    const last = await page.evaluate(() => window.dmbnTimings.live.at(-1));
    assert.equal(last.from, 36, "the last forecast is made from what step 38 has seen");
    assert.ok((await forecasts(page)) - finished <= 2, `the stale forecasts were cancelled: ${(await forecasts(page)) - finished} of 5 finished`);
    assert.deepEqual(page.problems, []);
    await close(page);
  });

  test("the joint panels keep the last finished forecast until the next one finishes", async () => {
    // Chunks 400 ms apart: a forecast takes over a second, long enough to look at mid-way.
    const page = await open(`${server.url}www/?mode=live&action=grasp&seed=11&every=5&chunkDelay=400`);
    await page.waitForFunction(() => ["predicting", "predicted", "error"].includes(document.body.dataset.state));
    await pause(page);
    assert.equal((await forecastAt(page, 12)).from, 11);
    const held = (await pixels(page, "joints-plot")).hash;
    const finished = await forecasts(page);
    await page.locator("#scrubber").fill("17");
    // The new forecast's first chunk is in (its frames drawn), the forecast not finished.
    await page.waitForFunction(() => Number(document.body.dataset.progress) > 0 && document.body.dataset.state === "predicting");
    assert.equal(await page.getAttribute("body", "data-seen"), "16");
    assert.equal((await pixels(page, "joints-plot")).hash, held, "the panels still show the forecast from step 11");
    assert.equal(await forecasts(page), finished);
    assert.equal((await forecastAt(page, 17)).from, 16);
    assert.notEqual((await pixels(page, "joints-plot")).hash, held, "the finished forecast replaced it");
    assert.deepEqual(page.problems, []);
    await close(page);
  });

  test("the URL keeps the rule; models are compared on one plot", async () => {
    const page = await open(`${server.url}www/?mode=live&action=grasp&seed=11&every=10&ahead=5&ghost=0&observe=joints`);
    await page.waitForFunction(() => ["predicting", "predicted", "error"].includes(document.body.dataset.state));
    await pause(page);
    assert.equal(await page.inputValue("#live-every"), "10");
    assert.equal(await page.inputValue("#ahead"), "5");
    assert.equal(await page.isChecked("#ghost"), false);
    // A value being typed is not the rule yet: a forecast that finishes meanwhile is made and
    // plotted under the old rule, and the new rule's curve starts empty. (The forecast of the
    // steps played before the pause finishes first: counted after it, it is not taken for the
    // one from step 25.)
    await page.waitForFunction(() => ["predicted", "error"].includes(document.body.dataset.state));
    const finished = await forecasts(page);
    await page.locator("#scrubber").fill("25");
    await page.fill("#live-every", "8");
    await page.waitForFunction((n) => Number(document.body.dataset.predictions ?? 0) > n, finished);
    assert.equal(await page.evaluate(() => window.dmbnTimings.live.at(-1).from), 21, "seen under every 10");
    assert.match(await page.textContent("#obs-info"), /every 10:/);
    await page.locator("#live-every").dispatchEvent("change");
    await page.waitForFunction(() => window.dmbnTimings.live.at(-1)?.from === 25 && document.body.dataset.state === "predicted");
    assert.equal(await page.getAttribute("#error-plot", "data-points"), "1", "only the new rule's forecast");
    await page.waitForFunction(() => new URLSearchParams(location.search).get("every") === "8");
    const url = new URL(page.url());
    assert.equal(url.searchParams.get("mode"), "live");
    assert.equal(url.searchParams.get("ahead"), "5");
    assert.equal(url.searchParams.get("ghost"), "0");
    assert.equal(url.searchParams.has("obs"), false, "the rule, not a list of steps");
    // Every model's curve over the episode.
    const compared = await page.evaluate(() => Number(document.body.dataset.compared ?? 0));
    await page.click("#compare");
    await page.waitForFunction(
      (n) => Number(document.body.dataset.compared ?? 0) > n || document.body.dataset.state === "error",
      compared,
      { timeout: 180_000 },
    );
    assert.equal(await page.getAttribute("#error-plot", "data-models"), "attn,dmbn,pte,pte-aug");
    const len = Number(await page.getAttribute("#scrubber", "max")) + 1;
    const points = Number(await page.getAttribute("#error-plot", "data-points"));
    assert.equal(points, 4 * Math.ceil((len - 1) / 8), "one point per model and observation point");
    await shot(page, "live-compared");
    assert.deepEqual(page.problems, []);
    await close(page);
  }, { timeout: 240_000 });
});
