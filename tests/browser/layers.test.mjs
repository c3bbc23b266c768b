// The page's modules import one way (www/README.md, "Layers"): each www/*.js imports only
// modules of its own layer or lower ones, and no import cycle exists. What flows up goes through
// www/events.js or a callback. No browser needed: the import lines are read as text.
import assert from "node:assert/strict";
import { readdirSync, readFileSync } from "node:fs";
import { dirname, join } from "node:path";
import { describe, test } from "node:test";
import { fileURLToPath } from "node:url";

// (Not support.mjs: that one starts a browser.)
const WWW = join(dirname(fileURLToPath(import.meta.url)), "..", "..", "www");

/** The layers, lowest first; README's Files table gives each module the same one. */
const LAYERS = [
  ["base", ["config.js", "ui.js", "events.js", "hooks.js"]],
  ["state", ["state.js", "status.js", "observations.js", "url.js"]],
  ["drawing", ["views.js", "plot.js", "error_plot.js", "strip.js", "draw.js"]],
  ["inference", ["wasm.js", "inference.js", "models.js", "worker.js", "encoded_steps.js"]],
  ["controllers", ["playback.js", "imitate.js", "prediction.js", "live.js", "futures.js", "episodes.js", "folder.js", "changes.js"]],
  ["wiring", ["wire.js", "main.js"]],
];
/** The worker's thread: it imports none of the page's modules, and they import none of its. */
const WORKER = new Set(["worker.js", "encoded_steps.js"]);

const layerOf = new Map(LAYERS.flatMap(([, files], i) => files.map((f) => [f, i])));
const name = (i) => `${i} ${LAYERS[i][0]}`;

/** The www/ modules a source imports: `import … from "./x.js"`, `export … from`, `import("./x.js")`. */
function importsOf(source) {
  const found = [
    ...source.matchAll(/^\s*(?:import|export)\b[^;]*?\bfrom\s*["']\.\/([^"']+)["']/gm),
    ...source.matchAll(/^\s*import\s*["']\.\/([^"']+)["']/gm),
    ...source.matchAll(/\bimport\(\s*["']\.\/([^"']+)["']\s*\)/g),
  ];
  return [...new Set(found.map((m) => m[1]))];
}

/** The first import cycle of `graph` (module → imported modules) as a path, or null. */
function findCycle(graph) {
  const state = new Map(); // module → "open" while on the path, "done" after
  const path = [];
  const visit = (m) => {
    if (state.get(m) === "done") return null;
    if (state.get(m) === "open") return [...path.slice(path.indexOf(m)), m];
    state.set(m, "open");
    path.push(m);
    for (const next of graph.get(m) ?? []) {
      const cycle = visit(next);
      if (cycle) return cycle;
    }
    path.pop();
    state.set(m, "done");
    return null;
  };
  for (const m of graph.keys()) {
    const cycle = visit(m);
    if (cycle) return cycle;
  }
  return null;
}

/** Every import that breaks the rules, in words. */
function violations(graph) {
  const out = [];
  for (const [from, imports] of graph) {
    for (const to of imports) {
      if (!graph.has(to)) out.push(`${from} imports ${to}, which is not a module of www/`);
      else if (layerOf.get(to) > layerOf.get(from)) out.push(`${from} (layer ${name(layerOf.get(from))}) imports ${to} (layer ${name(layerOf.get(to))}), a higher layer`);
      if (WORKER.has(from) !== WORKER.has(to)) out.push(`${from} imports ${to} across the worker's thread`);
    }
  }
  return out;
}

const modules = readdirSync(WWW).filter((f) => f.endsWith(".js")).sort();
const graph = new Map(modules.map((f) => [f, importsOf(readFileSync(join(WWW, f), "utf8"))]));

describe("the page's modules import one way", () => {
  test("every module has a layer, and README's table gives the same", () => {
    assert.deepEqual(modules.filter((f) => !layerOf.has(f)), [], "modules without a layer: add them to LAYERS and www/README.md");
    assert.deepEqual([...layerOf.keys()].filter((f) => !modules.includes(f)), [], "layers name modules that are gone");
    const readme = readFileSync(join(WWW, "README.md"), "utf8");
    for (const f of modules) {
      const row = new RegExp(`^\\| \`${f.replace(".", "\\.")}\` \\| (\\d) `, "m").exec(readme);
      assert.ok(row, `www/README.md's Files table has no row for ${f}`);
      assert.equal(Number(row[1]), layerOf.get(f), `www/README.md puts ${f} in layer ${row[1]}, this test in ${name(layerOf.get(f))}`);
    }
  });

  test("each module imports only its own layer or lower ones", () => {
    assert.ok([...graph.values()].flat().length > 50, "the imports were read");
    assert.deepEqual(violations(graph), []);
  });

  test("no import cycle", () => {
    assert.equal(findCycle(graph)?.join(" → ") ?? null, null);
  });

  test("the check finds a cycle and an upward import", () => {
    // What draw.js importing live.js (as it once did) would make.
    const bad = new Map(graph);
    bad.set("draw.js", [...graph.get("draw.js"), "live.js"]);
    assert.match(findCycle(bad).join(" → "), /draw\.js → .*live\.js → .*draw\.js|live\.js → .*draw\.js → live\.js/);
    assert.deepEqual(violations(bad), ["draw.js (layer 2 drawing) imports live.js (layer 4 controllers), a higher layer"]);
    assert.deepEqual(importsOf('import { a,\n  b } from "./x.js";\nexport { c } from "./y.js";\n// import z from "./z.js"\nawait import("./w.js");'), ["x.js", "y.js", "w.js"]);
  });
});
