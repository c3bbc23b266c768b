#!/usr/bin/env bash
# Re-make the figures of docs/results.md, *Many futures*: sampled futures of the page's default
# model (assets/models/attn-sim.dmbn) finishing grasps and pushes from their first 30%.
#
#   bash docs/futures.sh design [OUT]   # the design set (seeds 1000000-): the sampling settings compared
#   bash docs/futures.sh final  [OUT]   # the three fresh sets (seeds 1100000-, 1200000-, 1300000-): the reported table
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
  *)
    echo "error: the first argument is design or final, not '$what'" >&2
    exit 2
    ;;
esac
