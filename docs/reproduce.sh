#!/usr/bin/env bash
# Re-run the experiments of docs/results.md: the time-regression probe (Table 1) and the t/p/f
# evaluations on the held-out sequences, for DMBN, DMBN-PTE, DMBN-PTE trained with
# time-warp augmentation and (t/p/f, simulator) the attentive model.
#
#   bash docs/reproduce.sh 2020 PATH/TO/data2020   # the original DMBN data (ids 0-39)
#   bash docs/reproduce.sh sim  PATH/TO/sim2000    # `dmbn simulate --out PATH --sequences 2000 --seed 1000`
#
# By default it uses the shipped weights (assets/models/{dmbn,pte,pte-aug,attn}-{2020,sim}.dmbn,
# those that exist). With TRAIN=1 it first trains them into $OUT/runs with the README's recipe
# (hours on 2 cores) and uses each run's best.dmbn (the best validation quality). Results go to $OUT (default out/results-<set>): probe-*/probe.md, eval/<model>/<mode>/
# <id>-<action>/{figure.png,eval.json} and tpf.md, the mean scores per model and mode.
set -euo pipefail

set_name=${1:?usage: bash docs/reproduce.sh 2020|sim DATA_DIR}
data=${2:?usage: bash docs/reproduce.sh 2020|sim DATA_DIR}
root=$(cd "$(dirname "$0")/.." && pwd)
out=${OUT:-$root/out/results-$set_name}
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$HOME/.cache/dmbn/target}

case $set_name in
  # The paper holds out 10 of 50 ids; ids 40-49 are not public, so 32-39 (20%) are held out.
  2020) fraction=0.2; steps=3000; every=250; held=$(seq 32 39) ;;
  # The simulator's 2,000 ids (seeds 1000-2999): the last 10% (1800-1999) are held out, as
  # in training; the t/p/f evaluations use the last 10 of them.
  sim) fraction=0.1; steps=3000; every=250; held=$(seq 1990 1999) ;;
  *) echo "error: the first argument is 2020 or sim, not '$set_name'" >&2; exit 2 ;;
esac
if [ ! -d "$data" ]; then
  echo "error: $data: no such folder (see README: The original DMBN dataset)" >&2
  exit 2
fi

cargo build --release --quiet --bin train --bin dmbn
bin=$CARGO_TARGET_DIR/release
mkdir -p "$out"

models=()
declare -A file
for m in dmbn pte pte-aug attn; do
  if [ "${TRAIN:-0}" = 1 ] || [ -f "$root/assets/models/$m-$set_name.dmbn" ]; then
    models+=("$m")
    file[$m]=$root/assets/models/$m-$set_name.dmbn
  fi
done

if [ "${TRAIN:-0}" = 1 ]; then
  for m in "${models[@]}"; do
    kind=${m%-aug}
    extra=(--single-modality 0.3 --prefix-contexts 0.3)
    [ "$m" = pte-aug ] && extra+=(--augment)
    # --resume continues an interrupted run; a finished one is left as it is.
    resume=()
    [ -f "$out/runs/$m/checkpoint/state.json" ] && resume=(--resume)
    "$bin/train" --data "$data" --model "$kind" "${extra[@]}" --out "$out/runs/$m" \
      --steps "$steps" --seed 1 --lr 1e-3 --schedule cosine --joint-weight 1 \
      --contexts-in-targets --targets-per-sequence 8 --joint-targets 32 --beta-nll 1 --val-every "$every" \
      --checkpoint-every "$every" --val-fraction "$fraction" --half "${resume[@]}"
    file[$m]=$out/runs/$m/best.dmbn
  done
fi

# Table 1: DMBN against DMBN-PTE with and without augmentation. On the original data the
# heads are fitted on ids 0-31 and tested on 32-39. The simulator's 4,000 sequences would take
# an hour per probe: its heads are fitted on the 400 training episodes of seeds 1000-1199 (ids
# 0-199 of sim2000) and tested on the 40 held-out ones of seeds 2980-2999 (ids 1980-1999),
# made here.
probe_split=(--test-fraction "$fraction")
probe_data=$data
if [ "$set_name" = sim ]; then
  [ -d "$out/probe-train" ] ||
    "$bin/dmbn" simulate --out "$out/probe-train" --sequences 200 --seed 1000 >/dev/null
  [ -d "$out/probe-test" ] ||
    "$bin/dmbn" simulate --out "$out/probe-test" --sequences 20 --seed 2980 >/dev/null
  probe_data=$out/probe-train
  probe_split=(--test-data "$out/probe-test")
fi
for pte in pte pte-aug; do
  "$bin/dmbn" probe --data "$probe_data" --dmbn "${file[dmbn]}" --pte "${file[$pte]}" --seeds 5 \
    "${probe_split[@]}" --out "$out/probe-$pte"
done

# t/p/f on every held-out sequence: 20 observations spread over the sequence, both modalities.
for m in "${models[@]}"; do
  for mode in t p f; do
    for id in $held; do
      for action in grasp move; do
        [ -d "$data/$id/$action" ] || continue
        "$bin/dmbn" eval --model "${file[$m]}" --data "$data" --sequence "$id/$action" \
          --mode $mode --observations 20 --blend 0.5 \
          --out "$out/eval/$m/$mode/$id-$action" >/dev/null
      done
    done
  done
done

# Mean scores per model and mode over the held-out sequences.
python3 - "$out" "${models[@]}" >"$out/tpf.md" <<'EOF'
import json, pathlib, statistics, sys
out, models = pathlib.Path(sys.argv[1]), sys.argv[2:]
keys = ["image_mse", "image_nll", "joint_mse", "joint_nll"]
print("| model | mode | sequences | image MSE | image NLL | joint MSE | joint NLL |")
print("|---|---|---:|---:|---:|---:|---:|")
for m in models:
    for mode in "tpf":
        runs = [json.loads(p.read_text())["scores"] for p in sorted((out / "eval" / m / mode).glob("*/eval.json"))]
        if not runs:
            continue
        means = [statistics.fmean(r[k] for r in runs) for k in keys]
        print(f"| {m} | {mode} | {len(runs)} | {means[0]:.4f} | {means[1]:.3f} | {means[2]:.3f} | {means[3]:.3f} |")
EOF
cat "$out"/probe-*/probe.md "$out/tpf.md"
echo "wrote $out"
