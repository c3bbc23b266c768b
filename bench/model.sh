#!/usr/bin/env bash
# Model benchmarks side by side, on this machine, in one run:
#   - burn native (flex):   cargo bench --bench model
#   - PyTorch CPU:          bench/torch_dmbn.py (same DMBN, same shapes, same thread count)
#   - burn wasm (node):     bench/model.mjs (simd128, shipped weights; the 100 steps on one
#                           thread and split over THREADS workers, as the page runs them)
# then prints the medians and the ratios the README quotes, and checks that the PyTorch twin
# (python/dmbn_torch/) loaded from every exported shipped model predicts what `dmbn predict`
# does (tests/exchange.rs, within 1e-4). Sets up a venv with torch in
# $HOME/.cache/dmbn/venv on first use (pip; about 1-3 GB).
#
# Usage: bash bench/model.sh [THREADS]   (default: all cores)
set -euo pipefail
cd "$(dirname "$0")/.."
source .ci/setup
threads="${1:-$(nproc)}"
export RAYON_NUM_THREADS="$threads"

venv="$HOME/.cache/dmbn/venv"
if ! "$venv/bin/python" -c "import torch, safetensors" 2>/dev/null; then
  say "setting up $venv with torch (once)"
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet torch numpy safetensors
fi

say "burn native (flex), $threads threads"
# Each part's output is shown as it is, and its `json:` line kept for the summary (no tee to
# /dev/stderr: reopening it would truncate a log that stdout and stderr share).
out=$(cargo bench --bench model 2>/dev/null); echo "$out"
native=$(sed -n 's/^json: //p' <<<"$out")
say "pytorch, $threads threads"
torch=$("$venv/bin/python" bench/torch_dmbn.py --threads "$threads"); echo "$torch"
say "burn wasm (node, simd128)"
wasm-pack build --release --target nodejs --out-dir pkg-node --no-typescript >/dev/null 2>&1
out=$(node bench/model.mjs --workers "$threads"); echo "$out"
wasm=$(sed -n 's/^json: //p' <<<"$out")

say "pytorch twin against dmbn predict (every shipped model)"
DMBN_PYTHON="$venv/bin/python" cargo test --test exchange the_pytorch_twin -- --nocapture 2>&1 |
  grep -E '"max_abs_diff"|test result'

python3 - "$native" "$torch" "$wasm" <<'PY'
import json, sys
native = {r["model"]: r for r in json.loads(sys.argv[1])}
torch = json.loads(sys.argv[2])
wasm = {r["model"]: r for r in json.loads(sys.argv[3])}
d = native["dmbn"]
print("\nDMBN, 64x64 (medians, ms)        burn native   pytorch   ratio (torch/burn)")
for key, label in [("train_step_ms", "train step 8x5x4"), ("infer_one_ms", "infer 1 target"), ("infer_sequence100_ms", "infer 100 steps")]:
    print(f"{label:<32} {d[key]:>11.2f} {torch[key]:>9.2f} {torch[key] / d[key]:>8.2f}x")
t = torch["infer_sequence100_ms"]
for key, label in [("infer_sequence100_workers_ms", f"{wasm['dmbn']['workers']} workers"), ("infer_sequence100_ms", "1 thread")]:
    w = wasm["dmbn"][key]
    print(f"wasm 100 steps, {label}: {w:.1f} ms = {w / t:.2f}x native pytorch, {w / d['infer_sequence100_ms']:.2f}x native burn")
for kind in native:
    w = wasm[kind]
    print(f"{kind}: native {native[kind]['infer_sequence100_ms']:.1f} ms, wasm {w['infer_sequence100_workers_ms']:.1f} ms ({w['workers']} workers) / {w['infer_sequence100_ms']:.1f} ms (1 thread) per 100 steps")
PY
