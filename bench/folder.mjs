#!/usr/bin/env node
// The README's screenshot of the page on the original data: opens $DMBN2020 (the original
// DMBN dataset, never part of the repository) with the page's "Open a dataset", predicts
// sequence 12 (move) with the model the page chooses for it (attn-2020) from 5 observed steps,
// half-way through, and saves docs/folder.png.
//
// Usage: DMBN2020=path/to/data2020 node bench/folder.mjs
//   Needs the web package: wasm-pack build --release --target web --out-dir pkg --no-typescript
import { existsSync } from "node:fs";
import { dirname, join } from "node:path";
import { fileURLToPath } from "node:url";

import { launch } from "../tests/browser/browser.mjs";
import { serve } from "../tests/browser/server.mjs";

const ROOT = join(dirname(fileURLToPath(import.meta.url)), "..");
const data = process.env.DMBN2020;
if (!data || !existsSync(data)) {
  console.error("set DMBN2020 to a copy of the original data (data/data2020 of myunusseker/Deep-Modality-Blending-Networks)");
  process.exit(2);
}
const TIMEOUT = 120_000;
const server = await serve(ROOT);
const browser = await launch();
try {
  const context = await browser.newContext({ viewport: { width: 1280, height: 940 } });
  const page = await context.newPage();
  page.setDefaultTimeout(TIMEOUT);
  await page.goto(`${server.url}www/?chunkDelay=150`);
  await page.waitForFunction(() => document.body.dataset.state === "ready");
  await page.setInputFiles("#dataset", data);
  await page.waitForFunction(() => document.getElementById("model").value === "attn-2020" && document.body.dataset.state === "ready");
  await page.selectOption("#sequence", "12/move");
  await page.waitForFunction(() => /\/12\/move:/.test(document.getElementById("object-info").textContent));
  if ((await page.getAttribute("#play", "aria-pressed")) === "true") await page.click("#play");
  await page.click("#predict");
  await page.waitForFunction(() => document.body.dataset.state === "predicted");
  const len = Number(await page.getAttribute("#scrubber", "max")) + 1;
  await page.locator("#scrubber").fill(String(Math.round(len / 2)));
  const error = await page.locator("#error").isHidden();
  if (!error) throw new Error(await page.textContent("#error"));
  await page.screenshot({ path: join(ROOT, "docs", "folder.png"), fullPage: true });
  console.log(`docs/folder.png: ${await page.textContent("#object-info")} · ${await page.textContent("#status")}`);
} finally {
  await browser.close();
  await server.close();
}
