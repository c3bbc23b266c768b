#!/usr/bin/env node
// How the page should decode a dataset folder's frames, measured in headless Chromium on the
// same sequence: the page's way, the Rust reader in wasm (`Folder.put` + `Folder.read`:
// parsing, validation, decoding with the `image` crate and the native 128 → 64 area average),
// against the browser's decoder (createImageBitmap + getImageData, then the same 2x2 area
// average in JavaScript, which is what matching the native reader would take; no parsing).
// Medians of 5 runs after one warm-up.
//
// Usage: node bench/decode.mjs DIR [DIR ...]   (sequence folders, e.g. data/test/0/grasp or
//        path/to/data2020/12/move)
//   Needs the web package: wasm-pack build --release --target web --out-dir pkg --no-typescript
import { readdirSync, readFileSync } from "node:fs";
import { basename, dirname, join } from "node:path";
import { fileURLToPath } from "node:url";

import { launch } from "../tests/browser/browser.mjs";
import { serve } from "../tests/browser/server.mjs";

const ROOT = join(dirname(fileURLToPath(import.meta.url)), "..");

const dirs = process.argv.slice(2);
if (!dirs.length) {
  console.error("usage: node bench/decode.mjs SEQUENCE_DIR [...]");
  process.exit(2);
}
const server = await serve(ROOT);
const browser = await launch();
try {
  const page = await (await browser.newContext()).newPage();
  await page.goto(`${server.url}www/README.md`);
  for (const dir of dirs) {
    const names = readdirSync(dir).filter((n) => /^\d+\.(png|jpe?g)$/.test(n));
    const frames = names.map((n) => [...readFileSync(join(dir, n))]);
    const [id, action] = [basename(dirname(dir)), basename(dir)];
    const files = readdirSync(dir).map((n) => [`seq/${id}/${action}/${n}`, [...readFileSync(join(dir, n))]]);
    const wasm = await page.evaluate(async ({ files, id, action }) => {
      const m = await import("/pkg/dmbn.js");
      await m.default();
      const folder = new m.Folder(files.map(([p]) => p));
      const bytes = files.map(([p, b]) => [p, new Uint8Array(b)]);
      const runs = [];
      let steps = 0;
      for (let i = 0; i < 6; i++) {
        const t0 = performance.now();
        for (const [p, b] of bytes) folder.put(p, b);
        const ep = folder.read(Number(id), action, 64);
        runs.push(performance.now() - t0);
        steps = ep.len;
        ep.free();
      }
      runs.shift();
      runs.sort((a, b) => a - b);
      return { ms: runs[2], steps };
    }, { files, id, action });
    const result = await page.evaluate(async (frames) => {
      const decode = async () => {
        for (const bytes of frames) {
          const bitmap = await createImageBitmap(new Blob([new Uint8Array(bytes)]));
          const { width: w, height: h } = bitmap;
          const canvas = new OffscreenCanvas(w, h);
          const ctx = canvas.getContext("2d");
          ctx.drawImage(bitmap, 0, 0);
          const rgba = ctx.getImageData(0, 0, w, h).data;
          const f = w / 64;
          const out = new Uint8Array(64 * 64 * 3);
          for (let y = 0; y < 64; y++)
            for (let x = 0; x < 64; x++)
              for (let c = 0; c < 3; c++) {
                let sum = 0;
                for (let dy = 0; dy < f; dy++) for (let dx = 0; dx < f; dx++) sum += rgba[((y * f + dy) * w + x * f + dx) * 4 + c];
                out[(y * 64 + x) * 3 + c] = Math.round(sum / (f * f));
              }
          bitmap.close();
        }
      };
      const runs = [];
      for (let i = 0; i < 6; i++) {
        const t0 = performance.now();
        await decode();
        runs.push(performance.now() - t0);
      }
      runs.shift();
      runs.sort((a, b) => a - b);
      return { ms: runs[2] };
    }, frames);
    const kb = frames.reduce((s, f) => s + f.length, 0) / 1024;
    console.log(
      `${dir}: ${names.length} frames (${kb.toFixed(0)} KiB); wasm reader (${wasm.steps} steps read) ` +
        `${wasm.ms.toFixed(1)} ms, ${(wasm.ms / wasm.steps).toFixed(2)} ms per step; browser decode + resize ` +
        `${result.ms.toFixed(1)} ms, ${(result.ms / names.length).toFixed(2)} ms per frame`,
    );
  }
} finally {
  await browser.close();
  await server.close();
}
