// The simulator's second arm in the page: the Arm select (episode panel) simulates the
// Panda-like arm (8 joint values a step) and offers the models trained on it; the choice is in
// the URL; imitate mode performs on that arm; a model of the other arm's joint count is refused,
// saying both counts.
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import { join } from "node:path";
import { before, describe, test } from "node:test";
import { pathToFileURL } from "node:url";

import { close, errorText, open, pause, predict, ROOT, server, shot, waitState } from "./support.mjs";

let wasm;

before(async () => {
  wasm = await import(pathToFileURL(join(ROOT, "pkg", "dmbn.js")).href);
  await wasm.default({ module_or_path: readFileSync(join(ROOT, "pkg", "dmbn_bg.wasm")) });
});

/** The page's episode digest (the title of #object-info). */
const digest = async (page) => (await page.getAttribute("#object-info", "title")).replace("episode sha256 ", "");
/** The model ids the Model select offers. */
const offered = (page) => page.evaluate(() => [...document.getElementById("model").options].map((o) => o.value));
/** The episode `runEpisode(action, seed, 64, arm)` makes in Node: the same package. */
const simulated = (action, seed, arm) => {
  const ep = wasm.runEpisode(action, seed, 64, arm);
  const d = ep.digest();
  ep.free();
  return d;
};

describe("the second arm", () => {
  test("choosing the Panda simulates it, offers its model, predicts, and is in the URL", async () => {
    const page = await open(`${server.url}www/?workers=2&action=move&seed=5`);
    await waitState(page, "ready");
    assert.equal(await page.inputValue("#arm"), "ur5");
    assert.deepEqual(await offered(page), ["attn", "dmbn", "pte", "pte-aug"]);
    assert.equal(await page.getAttribute("#joints-plot", "data-panels"), "7");
    await page.selectOption("#arm", "panda");
    await page.waitForFunction((d) => !document.getElementById("object-info").title.endsWith(d), simulated("move", 5, undefined));
    assert.equal(await digest(page), simulated("move", 5, "panda"), "the page's Panda episode is the package's");
    assert.deepEqual(await offered(page), ["attn-panda"]);
    assert.equal(await page.inputValue("#model"), "attn-panda");
    await waitState(page, "ready");
    assert.equal(await page.getAttribute("#joints-plot", "data-panels"), "8");
    assert.match(await page.textContent("#status"), /Attentive · Panda arm ready: attn-panda\.dmbn/);
    const info = await page.evaluate(() => window.dmbnTimings.models["attn-panda"]);
    assert.equal(info.jointCount, 8);
    await pause(page);
    await predict(page);
    await shot(page, "arm-panda");
    assert.match(page.url(), /[?&]arm=panda/);
    assert.match(page.url(), /[?&]model=attn-panda/);
    // Back to the UR5: its episode and its models again (predicted again, as after any
    // change once a prediction was made), the arm gone from the URL.
    await predict(page, () => page.selectOption("#arm", "ur5"));
    assert.equal(await digest(page), simulated("move", 5, undefined));
    assert.deepEqual(await offered(page), ["attn", "dmbn", "pte", "pte-aug"]);
    assert.equal(await page.inputValue("#model"), "attn");
    assert.equal(await page.getAttribute("#joints-plot", "data-panels"), "7");
    assert.doesNotMatch(page.url(), /arm=/);
    assert.deepEqual(page.problems, []);
    await close(page);
  });

  test("a link with arm=panda opens the Panda's episode with its model", async () => {
    const page = await open(`${server.url}www/?arm=panda&model=attn-panda&action=grasp&seed=11&x=0.05&y=0.6`);
    await waitState(page, "ready");
    assert.equal(await page.inputValue("#arm"), "panda");
    assert.equal(await page.inputValue("#model"), "attn-panda");
    const want = wasm.Simulator.withObject("grasp", 0.05, 0.6, 11, 64, "panda").run();
    assert.equal(await digest(page), want.digest());
    want.free();
    // An arm no one has falls back to the UR5.
    const other = await open(`${server.url}www/?arm=kuka&model=attn-panda&seed=3`);
    await waitState(other, "ready");
    assert.equal(await other.inputValue("#arm"), "ur5");
    assert.equal(await other.inputValue("#model"), "attn");
    await close(other);
    await close(page);
  });

  test("imitate mode: the Panda performs what its model imagined from 5 frames", async () => {
    const url = `${server.url}www/?workers=2&arm=panda&mode=imitate&action=grasp&seed=11`;
    const first = await open(url);
    await waitState(first, "ready");
    const len = Number(await first.getAttribute("#scrubber", "max")) + 1;
    await close(first);
    const obs = [0, 1, 2, 3, 4].map((i) => Math.round((i * (len - 1)) / 4)).join(",");
    const page = await open(`${url}&obs=${obs}`);
    await waitState(page, "ready");
    await pause(page);
    await predict(page);
    await page.waitForFunction(() => document.body.dataset.performed === "imagined");
    assert.equal(await page.evaluate(() => document.body.dataset.outcome), "success", await page.textContent("#outcome"));
    assert.match(await page.textContent("#outcome"), /^lifted \d+ cm/);
    // The demonstration's own joints, performed on the same arm, lift it too.
    await page.click("#replay");
    await page.waitForFunction(() => document.body.dataset.performed === "demonstration");
    assert.equal(await page.evaluate(() => document.body.dataset.outcome), "success");
    await shot(page, "arm-panda-imitate");
    assert.deepEqual(page.problems, []);
    await close(page);
  });

  test("a model of the UR5's 7 values on the Panda's episodes is refused, saying both counts", async () => {
    const page = await open(`${server.url}www/?arm=panda&attn-panda=../assets/models/attn-sim.dmbn`);
    await waitState(page, "error");
    assert.match(await errorText(page), /reads 7 joint values a step, the simulator's episodes have 8: choose a model trained on this robot/);
    await close(page);
  });
});
