// Canvas helpers: frames, the σ heat map's legend, the table map for placing the object, the timeline.

/** RGB bytes (S×S×3, from `offset`) as ImageData. */
export function rgbImage(rgb, size, offset = 0) {
  const img = new ImageData(size, size);
  const px = size * size;
  for (let i = 0; i < px; i++) {
    img.data[4 * i] = rgb[offset + 3 * i];
    img.data[4 * i + 1] = rgb[offset + 3 * i + 1];
    img.data[4 * i + 2] = rgb[offset + 3 * i + 2];
    img.data[4 * i + 3] = 255;
  }
  return img;
}

/**
 * CSS gradient of the σ heat maps' ramp, for its legend: `heatMap` (the wasm export that colours
 * them, crate/predict/heat_map.rs) at 0, ¼, ½, ¾ and 1, the ramp's stops.
 */
export function heatGradient(heatMap) {
  const rgb = heatMap(Float32Array.of(0, 0.25, 0.5, 0.75, 1), 1);
  const stops = Array.from({ length: rgb.length / 3 }, (_, i) => `rgb(${rgb.subarray(3 * i, 3 * i + 3).join(",")})`);
  return `linear-gradient(90deg, ${stops.join(", ")})`;
}

/** Draws a placeholder (no prediction for this step yet) on a frame canvas. */
export function clearFrame(canvas) {
  const g = canvas.getContext("2d");
  g.fillStyle = "#0b0d11";
  g.fillRect(0, 0, canvas.width, canvas.height);
}

/** CSS box sizes of the canvases `watchSize` observes, kept as they change. */
const sizes = new WeakMap();

/**
 * Keeps the CSS sizes of `canvases` (so that drawing them never reads layout: a read after
 * the page changed forces a layout in the middle of every animation frame) and calls
 * `onResize` when one changes.
 */
export function watchSize(canvases, onResize) {
  const observer = new ResizeObserver((entries) => {
    for (const e of entries) sizes.set(e.target, { w: e.contentRect.width, h: e.contentRect.height });
    onResize();
  });
  for (const canvas of canvases) observer.observe(canvas);
}

/** A canvas's CSS box: as `watchSize` keeps it, or read from the layout. */
export function cssSize(canvas) {
  return sizes.get(canvas) ?? { w: canvas.clientWidth, h: canvas.clientHeight };
}

/** Sizes a canvas's backing store to its CSS box at the device pixel ratio; returns the context. */
export function fit(canvas) {
  const dpr = window.devicePixelRatio || 1;
  const { w, h } = cssSize(canvas);
  if (canvas.width !== Math.round(w * dpr) || canvas.height !== Math.round(h * dpr)) {
    canvas.width = Math.round(w * dpr);
    canvas.height = Math.round(h * dpr);
  }
  const g = canvas.getContext("2d");
  g.setTransform(dpr, 0, 0, dpr, 0, 0);
  g.clearRect(0, 0, w, h);
  return { g, w, h };
}

/**
 * Top-down schematic of the table around the placement region (x right, y away from the
 * camera and the arm base). `region` {x: [x0, x1], y: [y0, y1]} in metres; `object` [x, y] at
 * the start, `end` [x, y] at the end of the episode. Returns a function mapping client
 * coordinates to a point in the region (clamped) or null when the click is off the table.
 */
export function drawTable(canvas, region, object, end) {
  const { g, w, h } = fit(canvas);
  const [x0, x1] = region.x;
  const [y0, y1] = region.y;
  // Room around the region for the object (radius 4 cm) and the labels; one scale for x and y.
  const margin = 0.065;
  const vw = x1 - x0 + 2 * margin;
  const vh = y1 - y0 + 2 * margin;
  const scale = Math.min(w / vw, h / vh);
  const cx = (x0 + x1) / 2;
  const cy = (y0 + y1) / 2;
  const px = (x) => w / 2 + (x - cx) * scale;
  const py = (y) => h / 2 - (y - cy) * scale;
  const view = { x: [cx - w / 2 / scale, cx + w / 2 / scale], y: [cy - h / 2 / scale, cy + h / 2 / scale] };

  g.fillStyle = "#1d2129";
  g.fillRect(0, 0, w, h);
  // Region.
  g.fillStyle = "#242a35";
  g.fillRect(px(x0), py(y1), (x1 - x0) * scale, (y1 - y0) * scale);
  g.strokeStyle = "#4dabf7";
  g.setLineDash([5, 4]);
  g.lineWidth = 1;
  g.strokeRect(px(x0) + 0.5, py(y1) + 0.5, (x1 - x0) * scale - 1, (y1 - y0) * scale - 1);
  g.setLineDash([]);
  // Grid every 5 cm.
  g.strokeStyle = "#2c3340";
  for (let x = Math.ceil(view.x[0] / 0.05) * 0.05; x < view.x[1]; x += 0.05) {
    g.beginPath();
    g.moveTo(Math.round(px(x)) + 0.5, 0);
    g.lineTo(Math.round(px(x)) + 0.5, h);
    g.stroke();
  }
  for (let y = Math.ceil(view.y[0] / 0.05) * 0.05; y < view.y[1]; y += 0.05) {
    g.beginPath();
    g.moveTo(0, Math.round(py(y)) + 0.5);
    g.lineTo(w, Math.round(py(y)) + 0.5);
    g.stroke();
  }
  g.font = "10px system-ui, sans-serif";
  g.fillStyle = "#8b93a3";
  g.textAlign = "center";
  g.textBaseline = "bottom";
  g.fillText(`▼ arm base and camera (y = 0)`, w / 2, h - 3);
  g.textBaseline = "top";
  g.fillText("click to place the object", w / 2, 3);

  const radius = Math.max(4, 0.04 * scale);
  if (end && object && Math.hypot(end[0] - object[0], end[1] - object[1]) > 0.005) {
    g.strokeStyle = "#fcc419";
    g.setLineDash([3, 3]);
    g.beginPath();
    g.moveTo(px(object[0]), py(object[1]));
    g.lineTo(px(end[0]), py(end[1]));
    g.stroke();
    g.setLineDash([]);
    g.beginPath();
    g.arc(px(end[0]), py(end[1]), radius, 0, 2 * Math.PI);
    g.stroke();
  }
  if (object) {
    g.fillStyle = "#fcc419";
    g.beginPath();
    g.arc(px(object[0]), py(object[1]), radius, 0, 2 * Math.PI);
    g.fill();
  }

  return (clientX, clientY) => {
    const rect = canvas.getBoundingClientRect();
    const x = cx + (clientX - rect.left - w / 2) / scale;
    const y = cy - (clientY - rect.top - h / 2) / scale;
    const clamp = (v, [a, b]) => Math.min(b, Math.max(a, v));
    // Inside the region, or near it (snapped to its edge); far off it is ignored.
    if (x < view.x[0] || x > view.x[1] || y < view.y[0] || y > view.y[1]) return null;
    return [clamp(x, region.x), clamp(y, region.y)];
  };
}

/**
 * The timeline: one cell per step of the shown sequence, each a centre crop of its frame
 * (`sprite`: a canvas holding all frames side by side), observed steps marked, predicted steps
 * underlined, the current step outlined. Returns a function mapping client x to a step.
 */
export function drawTimeline(canvas, { len, size, sprite, observed, done, step }) {
  const { g, w, h } = fit(canvas);
  if (!len) return () => -1;
  const cell = w / len;
  const thumb = h - 10;
  const cropW = Math.max(1, Math.min(size, (cell * size) / thumb));
  g.imageSmoothingEnabled = true;
  for (let k = 0; k < len; k++) {
    const x = k * cell;
    g.drawImage(sprite, k * size + (size - cropW) / 2, 0, cropW, size, x, 4, Math.ceil(cell), thumb);
  }
  // Separators between cells when they are wide enough to tell apart.
  if (cell >= 6) {
    g.fillStyle = "rgba(15, 17, 21, 0.6)";
    for (let k = 1; k < len; k++) g.fillRect(Math.round(k * cell), 4, 1, thumb);
  }
  // Dim the unobserved steps so the observed ones stand out.
  g.fillStyle = "rgba(15, 17, 21, 0.45)";
  for (let k = 0; k < len; k++) if (!observed.has(k)) g.fillRect(k * cell, 4, cell, thumb);
  for (const k of observed) {
    g.strokeStyle = "#4dabf7";
    g.lineWidth = 2;
    g.strokeRect(k * cell + 1, 5, Math.max(2, cell - 2), thumb - 2);
    g.fillStyle = "#4dabf7";
    g.fillRect(k * cell, 0, Math.max(2, cell), 3);
  }
  if (done) {
    g.fillStyle = "#69db7c";
    for (let k = 0; k < len; k++) if (done[k]) g.fillRect(k * cell, h - 4, Math.ceil(cell), 3);
  }
  g.strokeStyle = "#ffffff";
  g.lineWidth = 1.5;
  g.strokeRect(step * cell + 0.75, 3.75, Math.max(2, cell - 1.5), thumb + 0.5);
  return (clientX) => {
    const rect = canvas.getBoundingClientRect();
    const k = Math.floor(((clientX - rect.left) / rect.width) * len);
    return k >= 0 && k < len ? k : -1;
  };
}

/** The colours of the small plots (joint panels, live error plot): tick labels, grid and frame. */
export const MUTED = "#8b93a3";
export const GRID = "#262b36";

/**
 * A small plot's frame: `title` in `color` above the box `{left, right, top, bottom}` (its
 * baseline at `titleY`), the box, and the tick labels' style (muted, right-aligned) left set.
 */
export function panelFrame(g, { left, right, top, bottom }, title, titleY, color) {
  g.font = "11px system-ui, sans-serif";
  g.fillStyle = color;
  g.textBaseline = "alphabetic";
  g.textAlign = "left";
  g.fillText(title, left, titleY);
  g.strokeStyle = GRID;
  g.lineWidth = 1;
  g.strokeRect(Math.round(left) + 0.5, Math.round(top) + 0.5, Math.round(right - left), Math.round(bottom - top));
  g.fillStyle = MUTED;
  g.font = "10px system-ui, sans-serif";
  g.textAlign = "right";
  g.textBaseline = "middle";
}
