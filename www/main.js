// DMBN web demo: generate an episode in WebAssembly, then play it back with its joint curves.
// Plain ES module, no bundler: the wasm-pack `--target web` build is expected in ../pkg/.

const JOINTS = 7;
const JOINT_NAMES = ["base", "shoulder", "elbow", "wrist 1", "wrist 2", "wrist 3", "gripper (right axis)"];
const JOINT_COLORS = ["#ff6b6b", "#ffa94d", "#ffd43b", "#69db7c", "#4dabf7", "#9775fa", "#f783ac"];
/** Playback rate: one recorded step is 3 physics substeps of 1/60 s, so 20 steps/s is real time. */
const STEPS_PER_SECOND = 20;

const $ = (id) => document.getElementById(id);
const ui = {
  form: $("controls"),
  action: $("action"),
  seed: $("seed"),
  random: $("random"),
  size: $("size"),
  generate: $("generate"),
  info: $("info"),
  error: $("error"),
  frame: $("frame"),
  joints: $("joints"),
  legend: $("legend"),
  play: $("play"),
  scrub: $("scrub"),
  counter: $("counter"),
  region: $("region"),
};

let wasm = null;
/** The episode on screen: step count, per-step ImageData and joint values (T × 7). */
let episode = null;
let step = 0;
let playing = false;
let lastTick = 0;

function setState(state) {
  document.body.dataset.state = state;
}

function showError(err) {
  const message = err instanceof Error ? err.message : String(err);
  ui.error.textContent = message;
  ui.error.hidden = false;
  setState("error");
  console.error(err);
}

function clearError() {
  ui.error.hidden = true;
  ui.error.textContent = "";
}

/** Settings from the URL (?action=move&seed=3&size=128), so a view can be linked. */
function readUrl() {
  const q = new URLSearchParams(location.search);
  if (q.has("action")) ui.action.value = q.get("action");
  if (q.has("seed")) ui.seed.value = q.get("seed");
  if (q.has("size")) ui.size.value = q.get("size");
}

function writeUrl() {
  const q = new URLSearchParams({ action: ui.action.value, seed: ui.seed.value, size: ui.size.value });
  history.replaceState(null, "", `${location.pathname}?${q}`);
}

/** Let the browser paint (the "Generating…" text) before the synchronous wasm call blocks. */
const nextPaint = () => new Promise((r) => requestAnimationFrame(() => setTimeout(r, 0)));

async function generate() {
  if (!wasm) return;
  clearError();
  pause();
  setState("loading");
  ui.generate.disabled = true;
  ui.info.textContent = "Generating…";
  await nextPaint();
  try {
    const t0 = performance.now();
    const ep = wasm.runEpisode(ui.action.value, Number(ui.seed.value === "" ? NaN : ui.seed.value), Number(ui.size.value));
    const ms = performance.now() - t0;
    try {
      episode = unpack(ep);
    } finally {
      ep.free();
    }
    const [ox, oy] = episode.object;
    const rate = ms > 0 ? ` (${Math.round((episode.len * 1000) / ms)} frames/s)` : "";
    ui.info.textContent =
      `${episode.len} steps generated in ${ms < 10 ? ms.toFixed(1) : ms.toFixed(0)} ms${rate}` +
      ` · object at (${ox.toFixed(3)}, ${oy.toFixed(3)}) m · sha256 ${episode.digest.slice(0, 12)}…`;
    ui.info.title = `sha256 ${episode.digest}`;
    ui.scrub.max = String(episode.len - 1);
    ui.scrub.disabled = false;
    ui.play.disabled = false;
    writeUrl();
    show(0);
    setState("ready");
    play();
  } catch (err) {
    ui.info.textContent = "";
    showError(err);
  } finally {
    ui.generate.disabled = false;
  }
}

/** Copy what playback needs out of the wasm Episode, frames as ready-to-draw ImageData. */
function unpack(ep) {
  const len = ep.len;
  const size = ep.imageSize;
  const rgb = ep.frames();
  const px = size * size;
  const images = [];
  for (let k = 0; k < len; k++) {
    const img = new ImageData(size, size);
    const src = k * px * 3;
    for (let i = 0; i < px; i++) {
      img.data[i * 4] = rgb[src + i * 3];
      img.data[i * 4 + 1] = rgb[src + i * 3 + 1];
      img.data[i * 4 + 2] = rgb[src + i * 3 + 2];
      img.data[i * 4 + 3] = 255;
    }
    images.push(img);
  }
  return { len, size, images, joints: ep.joints(), object: ep.object(), digest: ep.digest() };
}

function show(k) {
  if (!episode) return;
  step = Math.max(0, Math.min(episode.len - 1, k));
  if (ui.frame.width !== episode.size) {
    ui.frame.width = ui.frame.height = episode.size;
  }
  ui.frame.getContext("2d").putImageData(episode.images[step], 0, 0);
  ui.scrub.value = String(step);
  ui.counter.textContent = `step ${step} / ${episode.len - 1}`;
  drawChart();
}

// ---- playback ----

function play() {
  if (!episode) return;
  if (step >= episode.len - 1) show(0);
  playing = true;
  ui.play.textContent = "❚❚ Pause";
  lastTick = performance.now();
  requestAnimationFrame(tick);
}

function pause() {
  playing = false;
  ui.play.textContent = "▶ Play";
}

function toggle() {
  playing ? pause() : play();
}

function tick(now) {
  if (!playing || !episode) return;
  const advance = Math.floor(((now - lastTick) * STEPS_PER_SECOND) / 1000);
  if (advance > 0) {
    lastTick += (advance * 1000) / STEPS_PER_SECOND;
    show(step + advance);
    if (step >= episode.len - 1) {
      pause();
      return;
    }
  }
  requestAnimationFrame(tick);
}

// ---- joint chart ----

/** Plot area inside the chart canvas, in CSS pixels. */
const PAD = { left: 48, right: 48, top: 10, bottom: 40 };

function drawChart() {
  const canvas = ui.joints;
  const dpr = window.devicePixelRatio || 1;
  const w = canvas.clientWidth;
  const h = canvas.clientHeight;
  if (canvas.width !== Math.round(w * dpr) || canvas.height !== Math.round(h * dpr)) {
    canvas.width = Math.round(w * dpr);
    canvas.height = Math.round(h * dpr);
  }
  const g = canvas.getContext("2d");
  g.setTransform(dpr, 0, 0, dpr, 0, 0);
  g.clearRect(0, 0, w, h);
  if (!episode) return;

  const { len, joints } = episode;
  // The 6 angles share the left axis (rad); the gripper, a few centimetres of travel, gets
  // its own right axis so its opening and closing stays visible.
  const ARM = JOINTS - 1;
  const [lo, hi] = range(joints, (k) => k % JOINTS < ARM, 0.1);
  const [glo, ghi] = range(joints, (k) => k % JOINTS === ARM, 0.005);
  const pw = w - PAD.left - PAD.right;
  const ph = h - PAD.top - PAD.bottom;
  const x = (k) => PAD.left + (len > 1 ? (k / (len - 1)) * pw : 0);
  const yOf = (a, b) => (v) => PAD.top + (1 - (v - a) / (b - a)) * ph;
  const y = yOf(lo, hi);
  const gy = yOf(glo, ghi);
  const yj = (j) => (j === ARM ? gy : y);

  // Grid and axis labels.
  g.font = "11px system-ui, sans-serif";
  g.fillStyle = "#8b93a3";
  g.strokeStyle = "#262b36";
  g.lineWidth = 1;
  g.textBaseline = "middle";
  for (const v of ticks(lo, hi, 5)) {
    const yy = Math.round(y(v)) + 0.5;
    g.beginPath();
    g.moveTo(PAD.left, yy);
    g.lineTo(w - PAD.right, yy);
    g.stroke();
    g.textAlign = "right";
    g.fillText(fmt(v), PAD.left - 6, yy);
  }
  g.fillStyle = JOINT_COLORS[ARM];
  g.textAlign = "left";
  for (const v of ticks(glo, ghi, 5)) {
    g.fillText(fmt(v), w - PAD.right + 6, gy(v));
  }
  g.fillStyle = "#8b93a3";
  g.textAlign = "center";
  g.textBaseline = "top";
  for (const k of ticks(0, len - 1, 8).filter(Number.isInteger)) {
    const xx = Math.round(x(k)) + 0.5;
    g.beginPath();
    g.moveTo(xx, PAD.top);
    g.lineTo(xx, h - PAD.bottom);
    g.stroke();
    g.fillText(String(k), xx, h - PAD.bottom + 6);
  }
  g.fillText("step", PAD.left + pw / 2, h - 12);
  g.save();
  g.translate(11, PAD.top + ph / 2);
  g.rotate(-Math.PI / 2);
  g.textBaseline = "middle";
  g.fillText("angle (rad)", 0, 0);
  g.restore();

  // Curves (the gripper dashed, on its own axis).
  g.lineWidth = 1.6;
  g.lineJoin = "round";
  for (let j = 0; j < JOINTS; j++) {
    const yv = yj(j);
    g.strokeStyle = JOINT_COLORS[j];
    g.setLineDash(j === ARM ? [5, 3] : []);
    g.beginPath();
    for (let k = 0; k < len; k++) {
      const v = joints[k * JOINTS + j];
      k === 0 ? g.moveTo(x(k), yv(v)) : g.lineTo(x(k), yv(v));
    }
    g.stroke();
  }
  g.setLineDash([]);

  // Cursor at the current step, with a dot on each curve.
  const cx = Math.round(x(step)) + 0.5;
  g.strokeStyle = "#e6e9ef";
  g.lineWidth = 1;
  g.beginPath();
  g.moveTo(cx, PAD.top);
  g.lineTo(cx, h - PAD.bottom);
  g.stroke();
  for (let j = 0; j < JOINTS; j++) {
    g.fillStyle = JOINT_COLORS[j];
    g.beginPath();
    g.arc(cx, yj(j)(joints[step * JOINTS + j]), 3, 0, 2 * Math.PI);
    g.fill();
  }
  updateLegend();
}

/** Min and max of the values at indices that pass `keep`, widened by a margin (at least `pad`). */
function range(values, keep, pad) {
  let lo = Infinity;
  let hi = -Infinity;
  values.forEach((v, k) => {
    if (keep(k)) {
      lo = Math.min(lo, v);
      hi = Math.max(hi, v);
    }
  });
  const margin = Math.max(pad, (hi - lo) * 0.06);
  return [lo - margin, hi + margin];
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

/** `toFixed` without a "-0.00". */
function fmtFixed(v, digits) {
  const s = v.toFixed(digits);
  return Number(s) === 0 ? (0).toFixed(digits) : s;
}

function buildLegend() {
  ui.legend.replaceChildren(
    ...JOINT_NAMES.map((name, j) => {
      const li = document.createElement("li");
      li.style.setProperty("--c", JOINT_COLORS[j]);
      li.innerHTML = `<i></i>${name} <output></output>`;
      return li;
    }),
  );
}

function updateLegend() {
  const outs = ui.legend.querySelectorAll("output");
  outs.forEach((o, j) => {
    o.textContent = episode ? fmtFixed(episode.joints[step * JOINTS + j], j === JOINTS - 1 ? 3 : 2) : "";
  });
}

/** Click or drag on the chart to jump to a step. */
function chartPointer(e) {
  if (!episode || !(e.buttons & 1)) return;
  const rect = ui.joints.getBoundingClientRect();
  const pw = rect.width - PAD.left - PAD.right;
  const k = Math.round(((e.clientX - rect.left - PAD.left) / pw) * (episode.len - 1));
  pause();
  show(k);
}

// ---- wiring ----

function isTyping(el) {
  return (el instanceof HTMLInputElement && el.type !== "range") || el instanceof HTMLSelectElement || el instanceof HTMLTextAreaElement;
}

function onKey(e) {
  if (!episode || isTyping(e.target) || e.ctrlKey || e.metaKey || e.altKey) return;
  const keys = {
    " ": toggle,
    ArrowLeft: () => (pause(), show(step - 1)),
    ArrowRight: () => (pause(), show(step + 1)),
    Home: () => (pause(), show(0)),
    End: () => (pause(), show(episode.len - 1)),
  };
  const action = keys[e.key];
  if (!action) return;
  // Handled here, so a focused button or the scrubber does not act on the key as well.
  e.preventDefault();
  if (e.type === "keydown") action();
}

function wire() {
  ui.form.addEventListener("submit", (e) => {
    e.preventDefault();
    generate();
  });
  ui.random.addEventListener("click", () => {
    ui.seed.value = String(Math.floor(Math.random() * 2 ** 32));
    generate();
  });
  ui.play.addEventListener("click", toggle);
  ui.scrub.addEventListener("input", () => {
    pause();
    show(Number(ui.scrub.value));
  });
  ui.joints.addEventListener("pointerdown", (e) => {
    ui.joints.setPointerCapture(e.pointerId);
    chartPointer(e);
  });
  ui.joints.addEventListener("pointermove", chartPointer);
  addEventListener("keydown", onKey);
  addEventListener("keyup", onKey);
  new ResizeObserver(() => drawChart()).observe(ui.joints);
}

async function main() {
  setState("loading");
  buildLegend();
  wire();
  readUrl();
  try {
    wasm = await import("../pkg/dmbn.js");
    await wasm.default();
  } catch (err) {
    wasm = null;
    ui.info.textContent = "";
    showError(
      new Error(
        `Could not load the WebAssembly module (../pkg/dmbn.js): ${err.message ?? err}. ` +
          "Build it with `wasm-pack build --release --target web` and serve the repository root over HTTP.",
      ),
    );
    return;
  }
  const region = wasm.placementRegion();
  ui.region.textContent = `object placed in x ∈ [${region.x.join(", ")}] m, y ∈ [${region.y.join(", ")}] m`;
  ui.generate.disabled = false;
  ui.info.textContent = "";
  await generate();
}

main();
