// Browser tests of the page's live mode: the episode plays, the steps seen so far are the
// observations, and the rest of the action is forecast again as they come in.
import assert from "node:assert/strict";
import { describe, test } from "node:test";

import { close, countInference, ENDS, eventsSince, lastEvent, lifecycles, open, pause, pixels, server, shot, waitFor } from "./support.mjs";

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
  test("the forecast follows the steps seen while the episode plays, one at a time", async () => {
    const page = await open(`${server.url}www/?mode=live&action=grasp&seed=11&every=10&workers=2`);
    await page.waitForFunction(() => ["predicting", "predicted", "error"].includes(document.body.dataset.state));
    assert.equal(await page.inputValue("#mode"), "live");
    assert.equal(await page.locator("#error-panel").isHidden(), false, "the live error plot is shown");
    assert.equal(await page.locator("#random-k").isDisabled(), true, "the rule chooses the observations");
    await waitFor(() => page.workers().length === 2, "2 workers");
    await page.evaluate(countInference);
    // From the start: play, and read in the page's event log what happened in what order.
    // (Paused, the forecast running finishes first: none is left to start later.)
    await pause(page);
    await page.waitForFunction(() => ["predicted", "error"].includes(document.body.dataset.state));
    const before = await forecasts(page);
    const mark = await lastEvent(page);
    const seenBefore = Number(await page.getAttribute("body", "data-seen"));
    await page.keyboard.press("Home");
    await page.click("#play");
    await page.waitForFunction(() => document.getElementById("play").getAttribute("aria-pressed") === "false");
    await page.waitForFunction(() => ["predicted", "error"].includes(document.body.dataset.state));
    assert.equal(await page.getAttribute("body", "data-state"), "predicted", await page.textContent("#error"));
    const len = Number(await page.getAttribute("#scrubber", "max")) + 1;
    assert.equal(await page.inputValue("#scrubber"), String(len - 1), "it played to the end");
    const log = await eventsSince(page);
    const lives = lifecycles(log);
    const played = log.filter((e) => e.n > mark);
    const steps = played.filter((e) => e.type === "step").map((e) => e.step);
    assert.equal(steps[0], 0, "from the start");
    assert.equal(steps.at(-1), len - 1, "to the end");
    assert.ok(steps.every((s, i) => i === 0 || s >= steps[i - 1]), `only forward: ${steps.join(", ")}`);
    // A forecast starts each time the steps seen change (every 10th: 0, 10, …), of the steps
    // after the last one seen, and at no other time: whatever the machine's speed.
    const seenFrom = (step) => Math.floor(step / 10) * 10 + 1;
    const expected = [];
    let seen = seenBefore;
    let shown = null;
    for (const e of played) {
      if (e.type === "step") {
        shown = e.step;
        if (seenFrom(shown) === seen) continue;
        seen = seenFrom(shown);
        // (Once the last step is seen, nothing is left to forecast.)
        if (seen < len) expected.push(seen);
      } else if (e.type === "start") {
        assert.equal(e.from, seenFrom(shown), `forecast ${e.id} is of what step ${shown}, the step shown before it started, has seen`);
      }
    }
    const starts = played.filter((e) => e.type === "start");
    assert.ok(expected.length >= 1, `the steps seen changed while playing: ${steps.join(", ")}`);
    assert.deepEqual(starts.map((e) => e.from), expected, "a forecast for each change of the steps seen");
    // Each was cancelled before the next started, or finished and drawn; the last finished.
    for (const { start, end, drawn } of starts.map((e) => lives.get(e.id))) {
      assert.ok(end, `forecast ${start.id} (from ${start.from}) ended`);
      if (end.type === "finished") assert.ok(drawn > 0, `finished forecast ${start.id} (from ${start.from}) was drawn`);
      else assert.equal(end.type, "cancelled", `forecast ${start.id} (from ${start.from})`);
    }
    assert.equal(lives.get(starts.at(-1).id).end.type, "finished", "the last forecast finished");
    assert.ok((await forecasts(page)) > before, "and was counted");
    const calls = await page.evaluate(() => window.inferenceCalls);
    assert.deepEqual(calls, { encode: 0, decode: 0, predict: 0, decodedTargets: 0 }, "the main thread runs no model");
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
    // A stale forecast is dropped, not queued: the workers' replies held, each step's forecast
    // is cancelled by the next before any of its replies comes, and only the last one finishes.
    const finished = await forecasts(page);
    const mark = await lastEvent(page);
    await page.evaluate(() => window.dmbn.hold());
    for (const step of [12, 17, 22, 33, 38]) await page.locator("#scrubber").fill(String(step));
    await page.evaluate(() => window.dmbn.resume());
    await page.waitForFunction(() => document.body.dataset.state === "predicted");
    const last = await page.evaluate(() => window.dmbnTimings.live.at(-1));
    assert.equal(last.from, 36, "the last forecast is made from what step 38 has seen");
    const lives = lifecycles(await eventsSince(page));
    const log = await eventsSince(page, mark);
    const starts = log.filter((e) => e.type === "start");
    assert.deepEqual(starts.map((e) => e.from), [11, 16, 21, 31, 36], "a forecast for each step's seen steps");
    const ends = log.filter((e) => ENDS.includes(e.type)).map((e) => `${e.type} ${e.from}`);
    assert.deepEqual(ends, ["cancelled 11", "cancelled 16", "cancelled 21", "cancelled 31", "finished 36"]);
    for (const { id } of starts.slice(0, -1)) {
      assert.deepEqual([lives.get(id).chunks, lives.get(id).drawn], [0, 0], `cancelled forecast ${id}: no chunk stored, nothing drawn`);
    }
    assert.equal((await forecasts(page)) - finished, 1, "one forecast finished");
    assert.deepEqual(page.problems, []);
    await close(page);
  });

  test("the joint panels keep the last finished forecast until the next one finishes", async () => {
    const page = await open(`${server.url}www/?mode=live&action=grasp&seed=11&every=5`);
    await page.waitForFunction(() => ["predicting", "predicted", "error"].includes(document.body.dataset.state));
    await pause(page);
    assert.equal((await forecastAt(page, 12)).from, 11);
    const held = (await pixels(page, "joints-plot")).hash;
    const finished = await forecasts(page);
    // The next forecast mid-way: the workers' replies held, its first one handed on (a chunk:
    // the step on screen, decoded alone first), the rest still held.
    await page.evaluate(() => window.dmbn.hold());
    const mark = await lastEvent(page);
    await page.locator("#scrubber").fill("17");
    await page.waitForFunction(() => window.dmbn.held() > 0);
    await page.evaluate(() => window.dmbn.release(1));
    // Its frames are drawn (at the next animation frame).
    await page.waitForFunction((n) => window.dmbnEvents.some((e) => e.n > n && e.type === "drawn"), mark);
    const log = await eventsSince(page, mark);
    const start = log.find((e) => e.type === "start");
    assert.equal(start.from, 16);
    const mine = log.filter((e) => e.id === start.id).map((e) => e.type);
    assert.deepEqual(mine.slice(0, 3), ["start", "chunk", "drawn"], "started, its first chunk stored and drawn");
    assert.equal(mine.filter((t) => t === "chunk").length, 1, "one chunk in");
    assert.deepEqual(mine.filter((t) => ENDS.includes(t)), [], "not finished");
    assert.equal(await page.getAttribute("body", "data-state"), "predicting");
    assert.equal(await page.getAttribute("body", "data-seen"), "16");
    assert.ok(Number(await page.getAttribute("body", "data-progress")) > 0);
    assert.equal((await pixels(page, "joints-plot")).hash, held, "the panels still show the forecast from step 11");
    assert.equal(await forecasts(page), finished);
    await page.evaluate(() => window.dmbn.resume());
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
    // plotted under the old rule, and the new rule's curve starts empty. (First step 0's
    // forecast, finished: wherever playback paused, step 25 then sees new steps, and the
    // forecast counted next is the one from there.)
    assert.equal((await forecastAt(page, 0)).from, 1);
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
