#!/usr/bin/env bash
# Re-make the figures of docs/results.md, *Many futures*: sampled futures of the page's default
# model (assets/models/attn-sim.dmbn) finishing grasps and pushes from their first 30%.
#
#   bash docs/futures.sh design [OUT]   # the design set (seeds 1000000-): the sampling settings compared
#   bash docs/futures.sh final  [OUT]   # the three fresh sets (seeds 1100000-, 1200000-, 1300000-): the reported table
#   bash docs/futures.sh latent [OUT]   # the latent path against autoregressive sampling, on the design set
#
# Each set is 100 simulated demonstrations per action (`dmbn simulate --sequences 100`). OUT
# (default out/futures) receives the data, every run's JSON and printed tables. About 10 min
# per set on a 2-core machine.
set -euo pipefail

what=${1:?usage: bash docs/futures.sh design|final [OUT]}
root=$(cd "$(dirname "$0")/.." && pwd)
out=${2:-$root/out/futures}
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$HOME/.cache/dmbn/target}
cargo build --release --quiet --bin dmbn
dmbn=$CARGO_TARGET_DIR/release/dmbn
model=$root/assets/models/attn-sim.dmbn
mkdir -p "$out"

# The demonstrations of seeds SEED.. (100 per action), once.
data() {
  [ -d "$out/ur5-$1" ] || "$dmbn" simulate --out "$out/ur5-$1" --sequences 100 --seed "$1" >/dev/null
  echo "$out/ur5-$1"
}

# How far apart a run's futures push: the standard deviation of the object's travel over a
# demonstration's 8 futures, mean over the pushes (cm).
spread() {
  [ -f "$1" ] || return 0
  python3 - "$1" "$2" <<'PY'
import json, statistics, sys
from collections import defaultdict
travel = defaultdict(list)
for f in json.load(open(sys.argv[1]))[0]["future_performances"]:
    if f["action"] == "move":
        travel[f["id"]].append(f["travel_cm"])
print(f"{sys.argv[2]}: push travel spread {statistics.mean(map(statistics.pstdev, travel.values())):.2f} cm")
PY
}

case $what in
  design)
    set=$(data 1000000)
    # grid order τ: the settings compared (the defaults: 2 left-to-right 0.7).
    for cfg in "1 left-to-right 1" "2 left-to-right 1" "3 left-to-right 1" "4 left-to-right 1" \
      "8 left-to-right 1" "4 random 1" "8 random 1" "2 left-to-right 0.85" "2 left-to-right 0.7" \
      "3 left-to-right 0.7" "2 left-to-right 0.5"; do
      read -r grid order tau <<<"$cfg"
      name="$out/design-g$grid-$order-t$tau"
      "$dmbn" imitate --model "$model" --data "$set" --task finish --samples 8 --grid "$grid" \
        --order "$order" --temperature "$tau" --json "$name.json" >"$name.txt"
      grep -A5 "sampled futures each" "$name.txt" | grep '^| [gm]' | sed "s/^/g$grid $order τ$tau /"
    done
    ;;
  final)
    for seed in 1100000 1200000 1300000; do
      set=$(data $seed)
      "$dmbn" imitate --model "$model" --data "$set" --task finish --samples 8 --json "$out/finish-$seed.json" | tee "$out/finish-$seed.txt"
      "$dmbn" imitate --model "$model" --data "$set" --task frames --json "$out/frames-$seed.json" | tee "$out/frames-$seed.txt"
      "$dmbn" score --model "$model" --data "$set" --scenario extrap --samples 8 --json "$out/score-$seed.json" | tee "$out/score-$seed.txt"
    done
    ;;
  latent)
    # attn-sim trained on with a latent path of 16 values (3,000-6,000 steps each, 15-30 min on
    # two cores; resumable: run again), then its futures on the design set.
    set=$(data 1000000)
    sim=$out/sim2000
    [ -d "$sim" ] || "$dmbn" simulate --out "$sim" --sequences 2000 --seed 1000 >/dev/null
    cargo build --release --quiet --bin train
    train() {
      local name=$1 init=$2; shift 2
      [ -f "$out/$name/model.dmbn" ] && return
      if [ -f "$out/$name/checkpoint/state.json" ]; then
        "$CARGO_TARGET_DIR/release/train" --resume --data "$sim" --out "$out/$name"
        return
      fi
      "$CARGO_TARGET_DIR/release/train" --data "$sim" --out "$out/$name" --joint-weight 1 \
        --contexts-in-targets --targets-per-sequence 8 --joint-targets 32 --single-modality 0.9 \
        --val-every 250 --checkpoint-every 250 --val-fraction 0.1 --half --schedule cosine \
        --beta-nll 1 --init "$init" --seed 21 --latent 16 --latent-kl 0.003 "$@"
    }
    short=(--steps 3000 --lr 2e-4 --prefix-contexts 0.3)
    train kl003 "$model" "${short[@]}"
    train free3 "$model" "${short[@]}" --latent-free-nats 3
    train free8 "$out/free3/model.dmbn" "${short[@]}" --latent-free-nats 8
    # Longer, at a higher rate, with twice the prefixes (the ambiguous case).
    train long8 "$out/free8/model.dmbn" --steps 6000 --lr 5e-4 --prefix-contexts 0.6 --latent-free-nats 8
    for run in kl003-latent-1 free3-latent-1 free3-latent-2.5 free3-ar-0.7 free8-latent-1 free8-latent-2.5 long8-latent-1 long8-latent-2.5; do
      IFS=- read -r name method tau <<<"$run"
      "$dmbn" imitate --model "$out/$name/model.dmbn" --data "$set" --task finish --samples 8 \
        --method "$method" --temperature "$tau" --json "$out/latent-$run.json" >"$out/latent-$run.txt"
      grep -A5 "sampled futures each" "$out/latent-$run.txt" | grep '^| [gm]' | sed "s/^/$run /"
      spread "$out/latent-$run.json" "$run"
    done
    spread "$out/design-g2-left-to-right-t0.7.json" "attn-sim-ar-0.7 (bash docs/futures.sh design)"
    ;;
  *)
    echo "error: the first argument is design, final or latent, not '$what'" >&2
    exit 2
    ;;
esac
