// The joint curves as small multiples on one canvas, a panel for each of the D joint values a
// step (the model's: 7 for the simulator's arm, 6 angles and the gripper): the true (shown)
// values, the predicted mean with its ±2σ band as far as the prediction has come, sampled
// futures as a fan of thin lines (futures.js), the observed points and a cursor.

import { plotGrid } from "./hooks.js";
import { cssSize, fit, MUTED, panelFrame } from "./views.js";

/** Joint values a step of the simulator's arm (6 angles, gripper): the shipped models' D. */
export const ARM_JOINTS = 7;
/** The simulator arm's joints, in words and units, as the panels title them. */
export const JOINT_NAMES = ["base", "shoulder", "elbow", "wrist 1", "wrist 2", "wrist 3", "gripper"];
export const JOINT_UNITS = ["rad", "rad", "rad", "rad", "rad", "rad", "m"];
/** A colour per joint value: the arm's 7, then more for robots with more (repeating past 12). */
export const JOINT_COLORS = ["#ff6b6b", "#ffa94d", "#ffd43b", "#69db7c", "#4dabf7", "#b197fc", "#f783ac", "#63e6be", "#e599f7", "#ffc078", "#a9e34b", "#74c0fc"];
const jointColor = (j) => JOINT_COLORS[j % JOINT_COLORS.length];

/**
 * The names of `d` joint values where the data and the model name none: `joint 0`, `joint 1`,
 * …, the last `gripper` (the layout's convention; `Model.jointNames` says the same).
 */
export function defaultJointNames(d) {
  return Array.from({ length: d }, (_, j) => (j + 1 === d && d > 1 ? "gripper" : `joint ${j}`));
}

/**
 * The panels' titles for joint values named `names` (`Model.jointNames`): the simulator arm's
 * joints with their units when the names are the defaults of 7 values (the shipped models,
 * trained on the arm's layout), otherwise the names themselves.
 */
export function jointTitles(names) {
  const arm = names.length === ARM_JOINTS && defaultJointNames(ARM_JOINTS).every((n, j) => n === names[j]);
  return arm ? JOINT_NAMES.map((n, j) => `${n} (${JOINT_UNITS[j]})`) : names.map(String);
}

// 4 columns of panels, as many rows as the D panels and the legend (in the next free cell) need:
// 4 × 2 for the arm's 7; 2 columns on a narrow screen (a phone), where four would squeeze each
// curve into a sliver. The plot's box grows with the rows past the arm's (`--grow`, style.css).
const COLS = 4;
const NARROW_COLS = 2;
const NARROW = 560;
const GAP = { x: 14, y: 12 };
const PAD = { left: 40, right: 6, top: 18, bottom: 16 };
const TRUE = "#e6e9ef";
/** The sampled futures' thin lines: light, so the joint's colour stays the mean's. */
const FUTURE = "rgba(230, 233, 239, 0.45)";
/** The legend's names of the true curve and the predicted mean, unless told others. */
const LABELS = { truth: "true (shown)", mean: "predicted mean" };

/** Per canvas: what its panels were last drawn from. */
const drawnFrom = new WeakMap();

/**
 * Draws into `canvas` (sized from its CSS box at the device pixel ratio) and the step cursor
 * into `cursor`, a transparent canvas over it: the panels are redrawn only when the data
 * change, so that playback redraws the cursors alone.
 * `data`: {len, names (a name per joint value: D of them, `Model.jointNames`), joints (T×D
 * true), observed (sorted steps), step, prediction: null or {done (Uint8Array T), jointMean,
 * jointSigma (T×D), count}, futures: null or {samples, from, steps, joints (samples × steps × D:
 * the steps from `from` on)}, labels: optional legend names {truth, mean} (imitate mode:
 * demonstrated, imagined)}. Returns a function mapping a client x to a step.
 */
export function drawJoints(canvas, cursor, data) {
  const names = data?.names ?? defaultJointNames(ARM_JOINTS);
  const d = names.length;
  const cols = cssSize(canvas).w < NARROW ? NARROW_COLS : COLS;
  const rows = Math.ceil((d + 1) / cols);
  plotGrid(canvas, cols, d);
  // The box grows with the rows beyond the arm's (style.css's --grow; 1 for 7 joint values,
  // so their layout is the one it always was); a change resizes the canvas, which redraws.
  const grow = String(rows / Math.ceil((ARM_JOINTS + 1) / cols));
  const box = canvas.parentElement;
  if (box && box.style.getPropertyValue("--grow") !== grow) box.style.setProperty("--grow", grow);
  const { w, h } = cssSize(canvas);
  const cw = (w - GAP.x * (cols - 1)) / cols;
  const ch = (h - GAP.y * (rows - 1)) / rows;
  const cells = [];
  for (let j = 0; j < cols * rows; j++) {
    cells.push({ x: (j % cols) * (cw + GAP.x), y: Math.floor(j / cols) * (ch + GAP.y), w: cw, h: ch });
  }
  const p = data?.prediction;
  const labels = data?.labels ?? LABELS;
  const key = [window.devicePixelRatio, w, h, data?.len, data?.joints, data?.observed.join(","), p, p?.count, data?.futures, labels.truth, names.join("\n")];
  const last = drawnFrom.get(canvas);
  if (!last || key.some((v, i) => v !== last[i])) {
    const { g } = fit(canvas);
    drawLegend(g, cells[d], labels, Boolean(data?.futures));
    if (data && data.len >= 1) {
      const titles = jointTitles(names);
      for (let j = 0; j < d; j++) drawJoint(g, cells[j], j, d, titles[j], data);
    }
    drawnFrom.set(canvas, key);
  }
  const { g } = fit(cursor);
  if (!data || data.len < 1) return () => 0;
  for (let j = 0; j < d; j++) drawCursor(g, cells[j], data);
  const pw = cw - PAD.left - PAD.right;
  // Client x → step, using the column under the pointer.
  return (clientX) => {
    const rect = canvas.getBoundingClientRect();
    const x = clientX - rect.left;
    const col = Math.min(cols - 1, Math.max(0, Math.floor(x / (cw + GAP.x))));
    const local = x - col * (cw + GAP.x) - PAD.left;
    return Math.round((local / pw) * (data.len - 1));
  };
}

/** Panel `j` of `d` (joint value j of each step's d), titled `title`. */
function drawJoint(g, cell, j, d, title, { len, joints, observed, prediction, futures }) {
  const left = cell.x + PAD.left;
  const right = cell.x + cell.w - PAD.right;
  const top = cell.y + PAD.top;
  const bottom = cell.y + cell.h - PAD.bottom;
  const at = (k) => joints[k * d + j];

  // y range: the true curve, widened to the predicted band but never beyond 3 true ranges
  // (an unsure joint would otherwise flatten every other curve).
  let lo = Infinity;
  let hi = -Infinity;
  for (let k = 0; k < len; k++) {
    lo = Math.min(lo, at(k));
    hi = Math.max(hi, at(k));
  }
  const span = Math.max(hi - lo, j === d - 1 ? 0.01 : 0.1);
  const mid = (lo + hi) / 2;
  let blo = mid - span / 2;
  let bhi = mid + span / 2;
  const p = prediction;
  if (p) {
    for (let k = 0; k < len; k++) {
      if (!p.done[k]) continue;
      const m = p.jointMean[k * d + j];
      const s = 2 * p.jointSigma[k * d + j];
      blo = Math.min(blo, m - s);
      bhi = Math.max(bhi, m + s);
    }
  }
  const future = (s, k) => futures.joints[(s * futures.steps + k - futures.from) * d + j];
  for (let s = 0; futures && s < futures.samples; s++) {
    for (let k = futures.from; k < len; k++) {
      blo = Math.min(blo, future(s, k));
      bhi = Math.max(bhi, future(s, k));
    }
  }
  lo = Math.max(blo, mid - 1.5 * span);
  hi = Math.min(bhi, mid + 1.5 * span);
  const margin = (hi - lo) * 0.08;
  lo -= margin;
  hi += margin;
  const x = (k) => left + (len > 1 ? (k / (len - 1)) * (right - left) : 0);
  const y = (v) => bottom - ((v - lo) / (hi - lo)) * (bottom - top);

  // Frame, title, ticks.
  g.save();
  panelFrame(g, { left, right, top, bottom }, title, cell.y + 12, jointColor(j));
  for (const v of ticks(lo, hi, 3)) {
    const yy = Math.round(y(v)) + 0.5;
    g.beginPath();
    g.moveTo(left, yy);
    g.lineTo(right, yy);
    g.stroke();
    g.fillText(fmt(v), left - 4, yy);
  }
  g.textAlign = "center";
  g.textBaseline = "top";
  for (const k of [0, len - 1]) g.fillText(String(k), x(k), bottom + 3);
  g.beginPath();
  g.rect(left, top, right - left, bottom - top);
  g.clip();

  // Prediction: ±2σ band and mean, in runs of consecutive predicted steps.
  if (p) {
    const runs = [];
    for (let k = 0; k < len; k++) {
      if (!p.done[k]) continue;
      if (runs.length && runs[runs.length - 1][1] === k - 1) runs[runs.length - 1][1] = k;
      else runs.push([k, k]);
    }
    const mean = (k) => p.jointMean[k * d + j];
    const sd = (k) => p.jointSigma[k * d + j];
    g.fillStyle = jointColor(j) + "40";
    for (const [a, b] of runs) {
      g.beginPath();
      for (let k = a; k <= b; k++) g.lineTo(x(k), y(mean(k) + 2 * sd(k)));
      for (let k = b; k >= a; k--) g.lineTo(x(k), y(mean(k) - 2 * sd(k)));
      g.closePath();
      g.fill();
    }
    // The futures: a thin line each, under the mean.
    if (futures) {
      g.strokeStyle = FUTURE;
      g.lineWidth = 0.9;
      for (let s = 0; s < futures.samples; s++) {
        g.beginPath();
        for (let k = futures.from; k < len; k++) g.lineTo(x(k), y(future(s, k)));
        g.stroke();
      }
    }
    g.strokeStyle = jointColor(j);
    g.lineWidth = 1.8;
    g.lineJoin = "round";
    for (const [a, b] of runs) {
      g.beginPath();
      for (let k = a; k <= b; k++) g.lineTo(x(k), y(mean(k)));
      if (a === b) g.lineTo(x(a) + 1, y(mean(a)));
      g.stroke();
    }
  }

  // True curve.
  g.strokeStyle = TRUE;
  g.globalAlpha = 0.75;
  g.lineWidth = 1.2;
  g.setLineDash([4, 3]);
  g.beginPath();
  for (let k = 0; k < len; k++) g.lineTo(x(k), y(at(k)));
  g.stroke();
  g.setLineDash([]);
  g.globalAlpha = 1;

  // Observed points.
  for (const k of observed) {
    g.beginPath();
    g.arc(x(k), y(at(k)), 3.2, 0, 2 * Math.PI);
    g.fillStyle = "#0f1115";
    g.fill();
    g.lineWidth = 1.6;
    g.strokeStyle = TRUE;
    g.stroke();
  }

  g.restore();
}

/** The step cursor over a joint's panel. */
function drawCursor(g, cell, { len, step }) {
  const left = cell.x + PAD.left;
  const right = cell.x + cell.w - PAD.right;
  const cx = Math.round(left + (len > 1 ? (step / (len - 1)) * (right - left) : 0)) + 0.5;
  g.strokeStyle = "rgba(230, 233, 239, 0.55)";
  g.lineWidth = 1;
  g.beginPath();
  g.moveTo(cx, cell.y + PAD.top);
  g.lineTo(cx, cell.y + cell.h - PAD.bottom);
  g.stroke();
}

function drawLegend(g, cell, labels, futures) {
  if (!cell) return;
  const items = [
    [labels.truth, (x, y) => dashed(g, x, y)],
    [labels.mean, (x, y) => line(g, x, y, "#4dabf7", 2)],
    ["mean ± 2σ", (x, y) => band(g, x, y)],
    ...(futures ? [["sampled futures", (x, y) => line(g, x, y, FUTURE, 0.9)]] : []),
    ["observed", (x, y) => dot(g, x + 9, y)],
  ];
  g.save();
  g.font = "12px system-ui, sans-serif";
  g.textBaseline = "middle";
  g.textAlign = "left";
  // Aligned with the plots' axes, unless the cell is narrow (a phone) and the labels need room.
  const x0 = cell.x + (cell.w < 220 ? 4 : PAD.left);
  const y0 = cell.y + PAD.top + 6;
  const dy = Math.min(22, (cell.h - PAD.top) / items.length);
  items.forEach(([label, mark], i) => {
    const yy = y0 + i * dy;
    mark(x0, yy);
    g.fillStyle = MUTED;
    g.fillText(label, x0 + 26, yy);
  });
  g.fillStyle = "#5c6475";
  g.font = "10px system-ui, sans-serif";
  g.fillText("x axis: step of the shown sequence", x0, y0 + items.length * dy);
  g.restore();
}

function line(g, x, y, color, width) {
  g.strokeStyle = color;
  g.lineWidth = width;
  g.beginPath();
  g.moveTo(x, y);
  g.lineTo(x + 18, y);
  g.stroke();
}

function dashed(g, x, y) {
  g.setLineDash([4, 3]);
  line(g, x, y, TRUE, 1.2);
  g.setLineDash([]);
}

function band(g, x, y) {
  g.fillStyle = "#4dabf740";
  g.fillRect(x, y - 5, 18, 10);
}

function dot(g, x, y) {
  g.beginPath();
  g.arc(x, y, 3.2, 0, 2 * Math.PI);
  g.fillStyle = "#0f1115";
  g.fill();
  g.lineWidth = 1.6;
  g.strokeStyle = TRUE;
  g.stroke();
}

/** About `n` round tick values within [lo, hi]. */
function ticks(lo, hi, n) {
  const raw = (hi - lo) / n;
  if (!(raw > 0)) return [lo];
  const p = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 5, 10].map((m) => m * p).find((s) => raw <= s);
  const out = [];
  for (let i = Math.ceil(lo / step); i * step <= hi; i++) out.push(i * step);
  return out;
}

function fmt(v) {
  const r = Math.round(v * 1000) / 1000;
  return Object.is(r, -0) ? "0" : String(r);
}
