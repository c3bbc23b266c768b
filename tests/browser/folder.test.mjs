// Browser tests of "Open a dataset": folders in the DMBN layout that the tests write (from the
// web package's simulator, and broken copies), read in the page by the Rust reader compiled to
// wasm; and the original DMBN data ($DMBN2020, else ../shared/datasets/dmbn2020; skipped
// without it).
import assert from "node:assert/strict";
import { spawnSync } from "node:child_process";
import { existsSync, mkdirSync, readFileSync, rmSync } from "node:fs";
import { join } from "node:path";
import { before, describe, test } from "node:test";
import { pathToFileURL } from "node:url";

import { writeBrokenFolders, writeFolder, writeRobotFolder } from "./folders.mjs";
import { widenModel } from "./models.mjs";
import { ARTIFACTS, close, errorText, open, pause, predict, ROOT, server, shot, virtualFiles, waitState } from "./support.mjs";

const FOLDERS = join(ARTIFACTS, "folders");
let wasm;

/** A Python that runs the converters (as tests/convert.rs finds one), or null. */
function convertPython() {
  const home = process.env.HOME ?? "";
  for (const py of [process.env.DMBN_PYTHON_CONVERT, join(home, ".cache/dmbn/venv-convert/bin/python"), "python3"]) {
    if (py && spawnSync(py, ["-c", "import pyarrow, av, h5py"]).status === 0) return py;
  }
  return null;
}

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

  test("a folder without object and endpoint files: everything that needs no object works", async () => {
    const dir = join(FOLDERS, "no-object");
    writeFolder(wasm, dir, [{ action: "grasp", seed: 5 }, { action: "grasp", seed: 6 }], 64, { object: false });
    const page = await open(`${server.url}www/?workers=2`);
    await waitState(page, "ready");
    await openFolder(page, dir);
    assert.equal(await page.locator("#error").isHidden(), true, await errorText(page));
    await waitState(page, "ready");
    const models = await page.evaluate(() => [...document.getElementById("model").options].map((o) => o.value));
    assert.deepEqual(models, ["attn", "dmbn", "pte", "pte-aug"]);
    assert.equal(await page.getAttribute("#joints-plot", "data-panels"), "7");
    await pause(page);
    await predict(page);
    await page.selectOption("#sequence", "6/grasp");
    await page.waitForFunction(() => /\/6\/grasp:/.test(document.getElementById("object-info").textContent));
    await predict(page, () => page.selectOption("#mode", "p"));
    // Live mode forecasts, and its error (forecastError) joins the plot.
    const before = await predictions(page);
    await page.selectOption("#mode", "live");
    await page.waitForFunction((n) => Number(document.body.dataset.predictions) > n || document.body.dataset.state === "error", before);
    assert.notEqual(await page.evaluate(() => document.body.dataset.state), "error", await errorText(page));
    await page.waitForFunction(() => Number(document.getElementById("error-plot").dataset.points) > 0);
    assert.deepEqual(page.problems, []);
    await close(page);
  });

  test("another robot's data (9 joint values a step, which no shipped model reads): a 7-value model is refused, saying both counts", async () => {
    const dir = join(FOLDERS, "robot9");
    writeRobotFolder(dir, { ids: [0, 1], action: "move", steps: 12, joints: 9, width: 40, height: 30 });
    const page = await open(`${server.url}www/?workers=1`);
    await waitState(page, "ready");
    await pause(page);
    await predict(page);
    const starts = () => page.evaluate(() => window.dmbnEvents.filter((e) => e.type === "start").length);
    const started = await starts();
    const done = await predictions(page);
    await openFolder(page, dir);
    const options = await page.evaluate(() => [...document.querySelectorAll("#sequence option")].map((o) => o.value));
    assert.deepEqual(options, ["sim", "0/move", "1/move"]);
    assert.equal(await page.inputValue("#sequence"), "0/move");
    assert.match(await page.textContent("#object-info"), /^robot9\/0\/move: 12 steps read in \d+ ms \(frames at 64×64\)/);
    // No data's models read 9 values: the page says so, naming both counts, and predicts
    // nothing (a prediction had been made, so the new sequence would otherwise be predicted).
    await waitState(page, "error");
    const refusal = /reads 7 joint values a step, the folder's sequences have 9: choose a model trained on this robot/;
    assert.match(await errorText(page), refusal);
    assert.match(await page.textContent("#status"), /sequences have 9 joint values a step/);
    // The panels are the sequence's: 9 of them, the legend in the tenth cell (3 rows of 4).
    assert.equal(await page.getAttribute("#joints-plot", "data-panels"), "9");
    assert.equal(await page.getAttribute("#joints-plot", "data-columns"), "4");
    await shot(page, "folder-robot9");
    // Predict, another model, the modes: each refused the same way, never asked of the workers.
    const refused = async (action) => {
      await action();
      await page.evaluate(() => new Promise((ok) => requestAnimationFrame(() => setTimeout(ok, 50))));
      await waitState(page, "error");
      assert.match(await errorText(page), refusal);
    };
    await refused(() => page.click("#predict"));
    await refused(() => page.selectOption("#model", "dmbn"));
    assert.match(await errorText(page), /^The DMBN model reads 7/);
    await refused(async () => {
      await page.selectOption("#sequence", "1/move");
      await page.waitForFunction(() => /\/1\/move:/.test(document.getElementById("object-info").textContent));
    });
    await refused(() => page.selectOption("#mode", "p"));
    await refused(() => page.selectOption("#mode", "live"));
    // Live mode plays on; however far it gets, nothing is forecast.
    await page.waitForFunction(() => window.dmbnEvents.filter((e) => e.type === "step").slice(-1)[0]?.step >= 5);
    await refused(() => page.click("#predict"));
    assert.equal(await starts(), started, "no prediction was asked of the workers");
    assert.equal(await predictions(page), done, "no prediction finished");
    // Each refusal is logged once, however often it was asked again.
    assert.ok(page.problems.length >= 1 && page.problems.every((p) => /reads 7 joint values a step/.test(p)), page.problems.join("\n"));
    // The simulator is one choice away, and predicts again.
    await page.selectOption("#mode", "t");
    await page.selectOption("#sequence", "sim");
    await page.waitForFunction(() => !document.getElementById("sim-controls").hidden);
    await predict(page);
    assert.equal(await page.locator("#error").isHidden(), true, await errorText(page));
    assert.equal(await page.getAttribute("#joints-plot", "data-panels"), "7");
    await close(page);
  });

  test("another robot's data with a model of its 9 joint values: chosen, predicted, forecast", async () => {
    const dir = join(FOLDERS, "robot9-model");
    writeRobotFolder(dir, { ids: [0, 1], action: "move", steps: 12, joints: 9, width: 40, height: 30 });
    // No shipped model reads 9 values: DMBN-PTE widened (models.mjs) stands in for one, as
    // the simulator's default model (a weight override); the page starts with DMBN (7).
    const names = ["rail", "base", "shoulder", "elbow", "wrist 1", "wrist 2", "wrist 3", "finger 1", "finger 2"];
    virtualFiles["/test/robot9.dmbn"] = widenModel(readFileSync(join(ROOT, "assets", "models", "pte-sim.dmbn")), 9, names);
    const page = await open(`${server.url}www/?workers=2&model=dmbn&attn=/test/robot9.dmbn`);
    await waitState(page, "ready");
    await pause(page);
    await openFolder(page, dir);
    // The 9-value model fits the folder: it is chosen.
    await page.waitForFunction(() => document.getElementById("model").value === "attn");
    await waitState(page, "ready");
    assert.equal(await page.locator("#error").isHidden(), true, await errorText(page));
    const info = await page.evaluate(() => window.dmbnTimings.models.attn);
    assert.equal(info.jointCount, 9);
    assert.deepEqual(info.jointNames, names);
    assert.equal(await page.getAttribute("#joints-plot", "data-panels"), "9");
    await pause(page);
    await predict(page);
    assert.equal(await page.evaluate(() => document.body.dataset.state), "predicted", await errorText(page));
    await shot(page, "folder-robot9-model");
    // Live mode forecasts, its error computed over 9 values a step.
    const before = await predictions(page);
    await page.selectOption("#mode", "live");
    await page.waitForFunction((n) => Number(document.body.dataset.predictions) > n || document.body.dataset.state === "error", before);
    assert.notEqual(await page.evaluate(() => document.body.dataset.state), "error", await errorText(page));
    await page.waitForFunction(() => Number(document.getElementById("error-plot").dataset.points) > 0);
    assert.deepEqual(page.problems, []);
    // A 7-value model is refused.
    await page.selectOption("#mode", "t");
    await page.selectOption("#model", "dmbn");
    await waitState(page, "error");
    assert.match(await errorText(page), /^The DMBN model reads 7 joint values a step, the folder's sequences have 9/);
    await close(page);
  });

  test("the Panda's data (8 joint values a step, no object files): its model is offered, chosen and predicts", async () => {
    const dir = join(FOLDERS, "panda");
    writeFolder(wasm, dir, [{ action: "move", seed: 4 }, { action: "grasp", seed: 6 }], 64, { object: false, arm: "panda" });
    const page = await open(`${server.url}www/?workers=2`);
    await waitState(page, "ready");
    await openFolder(page, dir);
    assert.equal(await page.inputValue("#sequence"), "4/move");
    await page.waitForFunction(() => document.getElementById("model").value === "attn-panda");
    await waitState(page, "ready");
    const models = await page.evaluate(() => [...document.getElementById("model").options].map((o) => o.value));
    assert.deepEqual(models, ["attn-panda"]);
    assert.equal(await page.getAttribute("#joints-plot", "data-panels"), "8");
    await pause(page);
    await predict(page);
    await shot(page, "folder-panda");
    assert.deepEqual(page.problems, []);
    await close(page);
  });

  // The converters' output (python/tests/converted.py: a LeRobot v2.1 dataset and a robomimic
  // file written by the formats' own libraries, converted) opens in the page like any folder.
  const python = convertPython();
  test("converted LeRobot and robomimic data open, and predict with a model of their joint count", { skip: python ? false : "no Python with pyarrow, av and h5py (see tests/convert.rs)" }, async () => {
    const out = join(FOLDERS, "converted");
    rmSync(out, { recursive: true, force: true });
    const made = spawnSync(python, ["python/tests/converted.py", out], { cwd: ROOT, encoding: "utf8", env: { ...process.env, PYTHONDONTWRITEBYTECODE: "1" } });
    assert.equal(made.status, 0, made.stderr);
    const model9 = widenModel(readFileSync(join(ROOT, "assets", "models", "pte-sim.dmbn")), 9);
    virtualFiles["/test/converted9.dmbn"] = model9;
    // LeRobot: 8 state values (the Panda's model reads 8); robomimic: 7 joints + 2 fingers (the
    // widened test model, as the simulator's default).
    for (const [name, d, action, model] of [["from-lerobot", 8, "pick", "attn-panda"], ["from-robomimic", 9, "lift", "attn"]]) {
      // (DMBN, of 7 values, on screen first: the simulator's episode at load is the UR5's.)
      const page = await open(`${server.url}www/?workers=2&model=dmbn&attn=/test/converted9.dmbn`);
      await waitState(page, "ready");
      await openFolder(page, join(out, name));
      assert.equal(await page.locator("#error").isHidden(), true, await errorText(page));
      assert.equal(await page.inputValue("#sequence"), `0/${action}`);
      await page.waitForFunction((m) => document.getElementById("model").value === m, model);
      await waitState(page, "ready");
      assert.equal(await page.getAttribute("#joints-plot", "data-panels"), String(d), name);
      assert.match(await page.textContent("#object-info"), new RegExp(`^${name}/0/${action}: \\d+ steps read`));
      await pause(page);
      await predict(page);
      await shot(page, `folder-${name}`);
      assert.deepEqual(page.problems, [], name);
      await close(page);
    }
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
