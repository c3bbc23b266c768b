// The strip of sampled futures (futures.js): a cell per future with its final frame, where the
// arm ends in that future, and in imitate mode the outcome of performing it (a button that
// performs it again).

import { futuresShown } from "./hooks.js";
import { rgbImage } from "./views.js";

/** What the strip was last built from (the cells are rebuilt only for other futures), and its labels. */
let built;
let labelled = "";

/**
 * Draws `futures` (null: none) into `strip`, a cell per future: its final frame and, with
 * `outcomes` (imitate mode), each one's outcome label or "…" until performed; `chosen`: the
 * future whose performance is drawn (or -1).
 */
export function drawStrip(strip, futures, chosen = -1) {
  if (futures !== built) {
    built = futures;
    labelled = "";
    futuresShown(futures);
    strip.replaceChildren();
    if (!futures) return;
    const { samples, size, frames, outcomes } = futures;
    const px = size * size * 3;
    for (let s = 0; s < samples; s++) {
      const cell = document.createElement(outcomes ? "button" : "div");
      cell.className = "future";
      cell.dataset.future = String(s);
      if (outcomes) cell.type = "button";
      const canvas = document.createElement("canvas");
      canvas.width = canvas.height = size;
      canvas.getContext("2d").putImageData(rgbImage(frames, size, s * px), 0, 0);
      const label = document.createElement("span");
      cell.append(canvas, label);
      strip.append(cell);
    }
  }
  if (!futures) return;
  // The outcomes come one by one: only the labels change, and only then (playback redraws
  // every step, and a change of the page's text lays it out again).
  const labels = `${chosen}|${futures.outcomes?.map((o) => o?.label).join(",")}`;
  if (labels === labelled) return;
  labelled = labels;
  [...strip.children].forEach((cell, s) => {
    const outcome = futures.outcomes?.[s];
    const label = futures.outcomes ? (outcome?.label ?? "…") : `future ${s + 1}`;
    cell.dataset.outcome = outcome?.label ?? "";
    cell.classList.toggle("chosen", s === chosen);
    cell.lastChild.textContent = label;
    cell.title = outcome ? `future ${s + 1}: ${outcome.summary}; click to perform it` : `future ${s + 1}: its final frame`;
  });
}
