// The live error plot: the error of each forecast of the rest of the action against the fraction
// of the action seen when it was made, one line per model (joint RMSE and image MSE side by side);
// and the curves it shows, those of the episode on screen (live.js adds their points).

import { MODEL_NAMES } from "./config.js";
import { errorPlotHolds } from "./hooks.js";
import { heldForecast, state } from "./state.js";
import { ui } from "./ui.js";
import { cssSize, fit, MUTED, panelFrame } from "./views.js";

/** The error curves of the episode on screen under the current rule and modalities (model → points). */
export function curves() {
  const key = [state.episode?.digest, state.every, ui.observe.value, state.shown?.len].join("|");
  if (state.curves.key !== key) state.curves = { key, byModel: new Map(), version: 0 };
  return state.curves.byModel;
}

/** What the error plot was last drawn from: it is redrawn only when that changes. */
let errorsDrawnFrom = "";

/** Draws the error plot, the fraction of the action seen by the forecast on screen marked. */
export function redrawErrors() {
  const { shown } = state;
  if (!shown) return;
  const forecast = heldForecast();
  const now = forecast ? forecast.from / shown.len : null;
  const byModel = curves();
  const { w, h } = cssSize(ui.errorPlot);
  const key = [window.devicePixelRatio, w, h, state.curves.key, state.curves.version, now].join("|");
  if (key === errorsDrawnFrom) return;
  errorsDrawnFrom = key;
  drawErrors(ui.errorPlot, byModel, MODEL_NAMES, now);
}

/** A colour per model id (the page's MODELS). */
export const MODEL_COLORS = { attn: "#4dabf7", dmbn: "#ff6b6b", pte: "#69db7c", "pte-aug": "#ffd43b", "attn-2020": "#4dabf7", "pte-2020": "#69db7c", "dmbn-2020": "#ff6b6b", "pte-aug-2020": "#ffd43b", "attn-panda": "#4dabf7" };
const PANELS = [
  { key: "jointRmse", title: "joint RMSE of the forecast (rad)" },
  { key: "imageMse", title: "image MSE of the forecast" },
];
const PAD = { left: 44, right: 16, top: 20, bottom: 30 };
const GAP = 18;

/**
 * Draws `byModel` (model id → [{seen (0-1), jointRmse, imageMse}] sorted by seen) into `canvas`;
 * `names` labels the models; `now` (0-1, or null) marks the fraction seen now.
 */
export function drawErrors(canvas, byModel, names, now) {
  const { g, w, h } = fit(canvas);
  const cw = (w - GAP) / 2;
  errorPlotHolds(canvas, byModel);
  PANELS.forEach((panel, i) => drawPanel(g, { x: i * (cw + GAP), y: 0, w: cw, h }, panel, byModel, now));
  // Legend: the models with a curve, left to right under the panels.
  g.font = "11px system-ui, sans-serif";
  g.textBaseline = "middle";
  g.textAlign = "left";
  let x = PAD.left;
  for (const model of byModel.keys()) {
    g.fillStyle = MODEL_COLORS[model] ?? MUTED;
    g.fillRect(x, h - 7, 14, 2.5);
    g.fillStyle = MUTED;
    const label = names[model] ?? model;
    g.fillText(label, x + 18, h - 6);
    x += 30 + g.measureText(label).width;
  }
  if (!byModel.size) {
    g.fillStyle = MUTED;
    g.fillText("play the episode: each forecast's error appears here", PAD.left, h - 6);
  }
}

function drawPanel(g, cell, { key, title }, byModel, now) {
  const left = cell.x + PAD.left;
  const right = cell.x + cell.w - PAD.right;
  const top = cell.y + PAD.top;
  const bottom = cell.y + cell.h - PAD.bottom;
  let hi = 0;
  for (const points of byModel.values()) for (const p of points) hi = Math.max(hi, p[key]);
  hi = hi > 0 ? hi * 1.1 : 1;
  const x = (s) => left + s * (right - left);
  const y = (v) => bottom - (v / hi) * (bottom - top);
  g.save();
  panelFrame(g, { left, right, top, bottom }, title, cell.y + 12, "#c5cad3");
  for (const v of [0, hi / 2, hi / 1.1]) g.fillText(format(v), left - 4, y(v));
  g.textAlign = "center";
  g.textBaseline = "top";
  for (const s of [0, 1]) g.fillText(`${s * 100}%`, x(s), bottom + 3);
  g.fillText("of the action seen", (left + right) / 2, bottom + 3);
  if (now !== null && Number.isFinite(now)) {
    g.strokeStyle = "rgba(230, 233, 239, 0.4)";
    g.beginPath();
    g.moveTo(Math.round(x(now)) + 0.5, top);
    g.lineTo(Math.round(x(now)) + 0.5, bottom);
    g.stroke();
  }
  for (const [model, points] of byModel) {
    g.strokeStyle = g.fillStyle = MODEL_COLORS[model] ?? MUTED;
    g.lineWidth = 1.8;
    g.beginPath();
    for (const p of points) g.lineTo(x(p.seen), y(p[key]));
    g.stroke();
    for (const p of points) {
      g.beginPath();
      g.arc(x(p.seen), y(p[key]), 2.4, 0, 2 * Math.PI);
      g.fill();
    }
  }
  g.restore();
}

function format(v) {
  if (v === 0) return "0";
  return v >= 0.1 ? v.toFixed(2) : v.toPrecision(2);
}
