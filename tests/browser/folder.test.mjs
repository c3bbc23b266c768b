// Browser tests of "Open a dataset": folders in the DMBN layout that the tests write (from the
// web package's simulator, and broken copies), read in the page by the Rust reader compiled to
// wasm; and the original DMBN data ($DMBN2020, else ../shared/datasets/dmbn2020; skipped
// without it).
import assert from "node:assert/strict";
import { existsSync, mkdirSync, readFileSync } from "node:fs";
import { join } from "node:path";
import { before, describe, test } from "node:test";
import { pathToFileURL } from "node:url";

import { writeBrokenFolders, writeFolder } from "./folders.mjs";
import { ARTIFACTS, close, errorText, open, pause, predict, ROOT, server, shot, waitState } from "./support.mjs";

const FOLDERS = join(ARTIFACTS, "folders");
let wasm;

before(async () => {
  wasm = await import(pathToFileURL(join(ROOT, "pkg", "dmbn.js")).href);
  await wasm.default({ module_or_path: readFileSync(join(ROOT, "pkg", "dmbn_bg.wasm")) });
  mkdirSync(FOLDERS, { recursive: true });
});

/** Chooses folder `dir` with the directory picker (its input) and waits until the page has read a sequence or failed. */
async function openFolder(page, dir) {
  const reads = await page.evaluate(() => document.getElementById("object-info").title);
  await page.setInputFiles("#dataset", dir);
  await page.waitForFunction(
    (before) => !document.getElementById("error").hidden || document.getElementById("object-info").title !== before,
    reads,
  );
}

/** The digest of the episode on screen (the wasm Episode.digest the page shows in a title). */
const digest = async (page) => (await page.getAttribute("#object-info", "title")).replace("episode sha256 ", "");

/** Forecasts finished so far (the page's counter). */
const predictions = (page) => page.evaluate(() => Number(document.body.dataset.predictions ?? 0));

describe("open a dataset", () => {
  test("a folder of simulated sequences reads as the simulator made them, and everything works on it", async () => {
    const dir = join(FOLDERS, "sim");
    const digests = writeFolder(wasm, dir, [
      { action: "grasp", seed: 4 },
      { action: "move", seed: 4 },
      { action: "grasp", seed: 9 },
    ]);
    const page = await open(`${server.url}www/?workers=2`);
    await waitState(page, "ready");
    assert.match(await page.textContent("#dataset-info"), /nothing is uploaded/);
    await openFolder(page, dir);
    assert.equal(await page.locator("#error").isHidden(), true, await errorText(page));
    const options = await page.evaluate(() => [...document.querySelectorAll("#sequence option")].map((o) => o.value));
    assert.deepEqual(options, ["sim", "4/grasp", "4/move", "9/grasp"]);
    assert.equal(await page.inputValue("#sequence"), "4/grasp");
    // PNG frames and text rows read back to the very episode: the same digest.
    assert.equal(await digest(page), digests["4/grasp"]);
    assert.equal(await page.locator("#sim-controls").isHidden(), true);
    assert.match(await page.textContent("#dataset-info"), /^sim: 3 sequences, 2 ids/);
    // Simulator data: the simulator's models stay offered.
    await waitState(page, "ready");
    const models = await page.evaluate(() => [...document.getElementById("model").options].map((o) => o.value));
    assert.deepEqual(models, ["attn", "dmbn", "pte", "pte-aug"]);
    await pause(page);
    await predict(page);
    await shot(page, "folder-sim");
    // Another sequence, the modes and the modalities.
    await page.selectOption("#sequence", "9/grasp");
    await page.waitForFunction((d) => document.getElementById("object-info").title.endsWith(d), digests["9/grasp"]);
    for (const [id, value] of [["#mode", "p"], ["#mode", "f"], ["#observe", "joints"], ["#mode", "t"]]) {
      await predict(page, () => page.selectOption(id, value));
    }
    // Live mode forecasts on it.
    const before = await predictions(page);
    await page.selectOption("#mode", "live");
    await page.waitForFunction((n) => Number(document.body.dataset.predictions) > n || document.body.dataset.state === "error", before);
    assert.notEqual(await page.evaluate(() => document.body.dataset.state), "error", await errorText(page));
    // Back to the simulator.
    await page.selectOption("#mode", "t");
    await page.selectOption("#sequence", "sim");
    await page.waitForFunction(() => !document.getElementById("sim-controls").hidden);
    await predict(page);
    assert.deepEqual(page.problems, []);
    await close(page);
  });

  test("a folder of 128-px frames is read at the models' 64 px", async () => {
    const dir = join(FOLDERS, "sim128");
    writeFolder(wasm, dir, [{ action: "move", seed: 2 }], 128);
    const page = await open(`${server.url}www/?workers=1`);
    await waitState(page, "ready");
    await openFolder(page, dir);
    assert.equal(await page.locator("#error").isHidden(), true, await errorText(page));
    assert.match(await page.textContent("#object-info"), /^sim128\/2\/move: \d+ steps read in \d+ ms \(frames at 64×64\)/);
    await pause(page);
    await predict(page);
    await close(page);
  });

  test("a broken folder shows the reader's error, and the page keeps working with the simulator", async () => {
    const cases = writeBrokenFolders(wasm, join(FOLDERS, "broken"));
    const page = await open(`${server.url}www/?workers=1`);
    await waitState(page, "ready");
    await pause(page);
    const simulated = await digest(page);
    for (const { name, dir, message } of cases) {
      await openFolder(page, dir);
      assert.equal(await page.locator("#error").isHidden(), false, name);
      assert.match(await errorText(page), message, name);
      assert.equal(await page.inputValue("#sequence"), "sim", name);
      assert.equal(await digest(page), simulated, `${name}: the simulated episode stays`);
      await predict(page);
      assert.equal(await page.locator("#error").isHidden(), true, `${name}: predicting clears the error`);
    }
    // The console saw exactly the errors shown.
    assert.equal(page.problems.length, cases.length, page.problems.join("\n"));
    await close(page);
  });

  // As the native tests: $DMBN2020, else ../shared/datasets/dmbn2020 beside the clone.
  const original = process.env.DMBN2020 || join(ROOT, "..", "shared", "datasets", "dmbn2020");
  test("the original data: the -2020 models are offered and chosen", { skip: existsSync(original) ? false : `no original data at ${original} (set DMBN2020)` }, async () => {
    const page = await open(`${server.url}www/?workers=2`);
    await waitState(page, "ready");
    await openFolder(page, original);
    assert.equal(await page.locator("#error").isHidden(), true, await errorText(page));
    assert.equal(await page.locator("#sequence option").count(), 81);
    // The page compares the joints with both models' normalisations, then offers the -2020
    // ones, the attentive first: before it says it is ready (a click then predicts with them).
    await waitState(page, "ready");
    const models = await page.evaluate(() => [...document.getElementById("model").options].map((o) => o.value));
    assert.deepEqual(models, ["attn-2020", "pte-2020", "dmbn-2020", "pte-aug-2020"]);
    assert.equal(await page.inputValue("#model"), "attn-2020");
    await page.selectOption("#sequence", "12/move");
    await page.waitForFunction(() => /\/12\/move:/.test(document.getElementById("object-info").textContent));
    await pause(page);
    await predict(page);
    await shot(page, "folder-2020");
    assert.deepEqual(page.problems, []);
    // The simulated arm cannot perform a real arm's joints: imitate mode says so.
    await page.selectOption("#mode", "imitate");
    assert.equal(await page.inputValue("#observe"), "images");
    await waitState(page, "error");
    assert.match(await errorText(page), /original DMBN data, recorded on a real arm/);
    assert.equal(await page.textContent("#outcome"), "no performance yet");
    assert.equal(page.problems.length, 1, "the message, logged once");
    await close(page);
  });
});
