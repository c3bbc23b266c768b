// Loading WebAssembly: the browser's support for it, the glue, and the module compiled once.

/** A tiny module with one v128 instruction: validates only where 128-bit SIMD is supported. */
const SIMD_PROBE = new Uint8Array([0, 97, 115, 109, 1, 0, 0, 0, 1, 5, 1, 96, 0, 1, 123, 3, 2, 1, 0, 10, 10, 1, 8, 0, 65, 0, 253, 15, 253, 98, 11]);

/** Throws, saying what is missing, when the browser cannot run the demo. */
export function checkSupport() {
  if (typeof WebAssembly !== "object" || typeof WebAssembly.validate !== "function") {
    throw new Error("This browser does not support WebAssembly, which the demo needs: use a current Chrome, Edge, Firefox or Safari.");
  }
  if (!WebAssembly.validate(SIMD_PROBE)) {
    throw new Error(
      "This browser's WebAssembly has no 128-bit SIMD (simd128), which the demo's module is built with: " +
        "use Chrome/Edge ≥ 91, Firefox ≥ 89 or Safari ≥ 16.4.",
    );
  }
  if (typeof Worker !== "function") {
    throw new Error("This browser has no Web Workers, which the demo runs its models in.");
  }
}

/** Imports the glue and compiles the module once; the workers get the compiled module. */
export async function loadWasm() {
  const pkg = new URL("../pkg/", import.meta.url);
  const hint = "Build it with `wasm-pack build --release --target web --out-dir pkg` and serve the repository root over HTTP (`bash .ci/demo`).";
  let glue;
  try {
    glue = await import(new URL("dmbn.js", pkg).href);
  } catch (err) {
    throw new Error(`Could not load the WebAssembly package (${new URL("dmbn.js", pkg).href}): ${err.message ?? err}. ${hint}`);
  }
  const url = new URL("dmbn_bg.wasm", pkg).href;
  let module;
  try {
    const response = await fetch(url);
    if (!response.ok) throw new Error(`HTTP ${response.status} ${response.statusText}`);
    try {
      module = await WebAssembly.compileStreaming(response.clone());
    } catch (err) {
      // A server without the application/wasm type: compile from the bytes instead.
      if (!(err instanceof TypeError)) throw err;
      module = await WebAssembly.compile(await response.arrayBuffer());
    }
  } catch (err) {
    throw new Error(`Could not load the WebAssembly module (${url}): ${err.message ?? err}. ${hint}`);
  }
  await glue.default({ module_or_path: module });
  return { glue, module };
}
