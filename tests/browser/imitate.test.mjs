// Imitate mode: the simulated arm performs the joints a model imagined from the
// frames it saw, beside the demonstration, with the outcome in a badge; the demonstration's
// own joints for comparison; a model whose joints cannot be performed, or a bad file, gives a
// message and the page carries on.
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import { join } from "node:path";
import { describe, test } from "node:test";

import { close, errorText, open, pause, pixels, predict, ROOT, server, shot, virtualFiles, waitState } from "./support.mjs";

/** Opens imitate mode on a grasp with 5 evenly spaced observed steps (the benchmark's frames task). */
async function openImitate(query = "") {
  const first = await open(`${server.url}www/?mode=imitate&action=grasp&seed=11${query}`);
  await waitState(first, "ready");
  const len = Number(await first.getAttribute("#scrubber", "max")) + 1;
  await close(first);
  const obs = [0, 1, 2, 3, 4].map((i) => Math.round((i * (len - 1)) / 4)).join(",");
  const page = await open(`${server.url}www/?mode=imitate&action=grasp&seed=11&obs=${obs}${query}`);
  await waitState(page, "ready");
  await pause(page);
  return { page, len, obs };
}

/**
 * In the page, independently of it: the demonstration (episode by action and seed), its own
 * joints performed (`replay`), and the frame of that performance at `step` against the drawn
 * #frame-pred (largest channel difference).
 */
function replayedInPage(page, step) {
  return page.evaluate(async (step) => {
    const pkg = await import(new URL("../pkg/dmbn.js", document.baseURI).href);
    const q = new URLSearchParams(location.search);
    const canvas = document.getElementById("frame-pred");
    const S = canvas.width;
    const episode = pkg.runEpisode(q.get("action"), Number(q.get("seed")), S);
    const replayed = pkg.replay(episode, q.get("action"));
    const frames = replayed.performance().frames();
    const drawn = canvas.getContext("2d").getImageData(0, 0, S, S).data;
    let worst = 0;
    for (let i = 0; i < S * S; i++) {
      for (let c = 0; c < 3; c++) worst = Math.max(worst, Math.abs(drawn[4 * i + c] - frames[step * S * S * 3 + 3 * i + c]));
    }
    const out = { summary: replayed.outcome.summary, success: replayed.outcome.success, worst };
    replayed.free();
    episode.free();
    return out;
  }, step);
}

/** The observed steps the page's URL names. */
const obsOf = (page) => new URL(page.url()).searchParams.get("obs");
/** k steps evenly spaced over `len`, the first and the last included (the benchmark's). */
const even = (len, k = 5) => Array.from({ length: k }, (_, i) => Math.round((i * (len - 1)) / (k - 1))).join(",");

describe("imitate mode", () => {
  test("observes 5 evenly spaced frames by default, as the benchmark does", async () => {
    const page = await open(`${server.url}www/?mode=imitate&action=grasp&seed=11`);
    await waitState(page, "ready");
    const len = Number(await page.getAttribute("#scrubber", "max")) + 1;
    assert.equal(obsOf(page), even(len));
    // Entering imitate mode from another mode chooses them too.
    const other = await open(`${server.url}www/?action=move&seed=3&obs=1,2,3`);
    await waitState(other, "ready");
    const otherLen = Number(await other.getAttribute("#scrubber", "max")) + 1;
    await other.selectOption("#mode", "imitate");
    await other.waitForFunction(() => /obs=0/.test(location.search));
    assert.equal(obsOf(other), even(otherLen));
    assert.equal(await other.inputValue("#observe"), "images");
    await close(other);
    await close(page);
  });

  test("the robot performs the joints it imagined from frames alone, and the outcome is shown", async () => {
    const { page, len } = await openImitate();
    // Frames only by default, the σ overlay replaced by imitate mode's panel.
    assert.equal(await page.inputValue("#observe"), "images");
    assert.equal(await page.locator("#imitate-panel").isVisible(), true);
    assert.equal(await page.locator("#sigma-panel").isHidden(), true);
    assert.equal(await page.textContent("#outcome"), "no performance yet");
    await predict(page);
    assert.equal(await page.evaluate(() => document.body.dataset.performed), "imagined");
    const outcome = await page.evaluate(() => document.body.dataset.outcome);
    assert.ok(["success", "missed"].includes(outcome), outcome);
    const badge = await page.textContent("#outcome");
    assert.match(badge, /^(lifted \d+ cm|missed: the object rose -?[\d.]+ cm)$/);
    assert.equal(await page.getAttribute("#outcome", "class"), `outcome ${outcome}`);
    const t = await page.evaluate(() => window.dmbnTimings.imitation);
    assert.equal(t.source, "imagined");
    assert.equal(t.summary, badge);
    assert.ok(t.joint_rmse > 0 && t.joint_rmse < 0.5, `joint RMSE ${t.joint_rmse}`);
    assert.match(await page.textContent("#imitate-info"), /5 observed steps \(frames only\).*joint RMSE 0\.\d{3} rad/);
    // The performance is drawn in step with the demonstration: a real frame, another at
    // another step, and not the demonstration's own.
    await page.locator("#scrubber").fill(String(len - 1));
    const end = await pixels(page, "frame-pred");
    const demo = await pixels(page, "frame-true");
    await page.locator("#scrubber").fill("0");
    const start = await pixels(page, "frame-pred");
    assert.ok(end.std > 5, `the performance's frame is not blank (std ${end.std.toFixed(1)})`);
    assert.notEqual(end.hash, start.hash, "the performance moves");
    assert.notEqual(end.hash, demo.hash, "the right frame is the performance, not the demonstration");
    assert.match(page.url(), /mode=imitate/);
    assert.match(page.url(), /observe=images/);
    await shot(page, "imitate");
    assert.deepEqual(page.problems, []);
    await close(page);
  });

  test("the demonstration's own joints, performed for comparison, succeed; and back", async () => {
    const { page, len } = await openImitate();
    await predict(page);
    const k = Math.floor(len / 2);
    await page.locator("#scrubber").fill(String(k));
    const imagined = await page.textContent("#outcome");
    assert.equal(await page.textContent("#replay"), "perform the demonstration's joints");
    await page.click("#replay");
    await page.waitForFunction(() => document.body.dataset.performed === "demonstration");
    // The badge and the drawn frame are the wasm `replay` of the same demonstration, exactly.
    const want = await replayedInPage(page, k);
    assert.equal(want.success, true, "the ceiling lifts the object");
    assert.equal(await page.textContent("#outcome"), want.summary);
    assert.equal(want.worst, 0, "the drawn frame is the replay's");
    assert.equal(await page.evaluate(() => document.body.dataset.outcome), "success");
    await shot(page, "imitate-replay");
    assert.equal(await page.textContent("#replay"), "perform the imagined joints");
    await page.click("#replay");
    await page.waitForFunction(() => document.body.dataset.performed === "imagined");
    assert.equal(await page.textContent("#outcome"), imagined);
    // Another observation predicts again and performs again.
    const before = await page.evaluate(() => Number(document.body.dataset.performances));
    await predict(page, () => page.click("#timeline", { position: { x: 40, y: 10 } }));
    assert.ok((await page.evaluate(() => Number(document.body.dataset.performances))) > before);
    assert.equal(await page.evaluate(() => document.body.dataset.performed), "imagined");
    assert.deepEqual(page.problems, []);
    await close(page);
  });

  test("a model whose joints cannot be performed gives a message, and the page carries on", async () => {
    // The shipped attentive model with its joint σ a million times too wide: the joints it
    // imagines lie far beyond the arm's limits.
    const bytes = readFileSync(join(ROOT, "assets", "models", "attn-sim.dmbn"));
    const length = bytes.readUInt32LE(12);
    const header = JSON.parse(bytes.subarray(16, 16 + length).toString("utf8"));
    header.normalization.std = header.normalization.std.map((s) => s * 1e6);
    const json = Buffer.from(JSON.stringify(header));
    const size = Buffer.alloc(4);
    size.writeUInt32LE(json.length);
    virtualFiles["/test/wild-joints.dmbn"] = Buffer.concat([bytes.subarray(0, 12), size, json, bytes.subarray(16 + length)]);
    const { page } = await openImitate("&attn=/test/wild-joints.dmbn");
    await page.click("#predict");
    await waitState(page, "error");
    assert.match(await errorText(page), /^The joints the model imagined could not be performed: .*(joint limits|beyond)/);
    assert.equal(await page.textContent("#outcome"), "no performance yet");
    await shot(page, "imitate-wild-joints");
    // The demonstration's joints still perform, and another model imitates.
    await page.click("#replay");
    await page.waitForFunction(() => document.body.dataset.performed === "demonstration");
    await waitState(page, "predicted");
    assert.equal(await page.locator("#error").isHidden(), true);
    await page.selectOption("#model", "dmbn");
    await predict(page);
    assert.equal(await page.evaluate(() => document.body.dataset.performed), "imagined");
    assert.equal(await page.locator("#error").isHidden(), true);
    await close(page);
  });

  test("a bad weight file in imitate mode gives a message, and the page carries on", async () => {
    const page = await open(`${server.url}www/?mode=imitate&attn=/test/corrupt.dmbn`);
    await waitState(page, "error");
    assert.match(await errorText(page), /corrupt\.dmbn are corrupt or not a model file/);
    await page.selectOption("#model", "pte");
    await waitState(page, "ready");
    await predict(page);
    assert.equal(await page.evaluate(() => document.body.dataset.performed), "imagined");
    await close(page);
  });
});
