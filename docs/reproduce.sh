#!/usr/bin/env bash
# Re-run the experiments of docs/results.md: the time-regression probe (Table 1) and the t/p/f
# evaluations on the held-out sequences, for DMBN, DMBN-PTE, DMBN-PTE trained with
# time-warp augmentation and (t/p/f, simulator) the attentive model.
#
#   bash docs/reproduce.sh 2020 PATH/TO/data2020   # the original DMBN data (ids 0-39)
#   bash docs/reproduce.sh sim  PATH/TO/sim2000    # `dmbn simulate --out PATH --sequences 2000 --seed 1000`
#
# By default it uses the shipped weights (assets/models/{dmbn,pte,pte-aug,attn}-{2020,sim}.dmbn,
# those that exist). With TRAIN=1 it first trains them into $OUT/runs with the commands the
# shipped weights were trained with (hours on 2 cores) and uses what was shipped of each run.
# Results go to $OUT (default out/results-<set>): probe-*/probe.md, eval/<model>/<mode>/
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

# A stage of the simulator's reproduction, which the original data's models start from.
sim_file() {
  local path=$root/out/results-sim/runs/$1/model.dmbn
  if [ ! -f "$path" ]; then
    echo "error: the $set_name models start from $path: run TRAIN=1 bash docs/reproduce.sh sim first" >&2
    return 1
  fi
  echo "$path"
}

# One training stage into $out/runs/NAME; --resume continues an interrupted one, a finished
# one is left as it is.
stage() {
  local name=$1; shift
  if [ -f "$out/runs/$name/checkpoint/state.json" ]; then
    "$bin/train" --resume --data "$data" --out "$out/runs/$name"
    return
  fi
  "$bin/train" --data "$data" --out "$out/runs/$name" --joint-weight 1 --contexts-in-targets \
    --targets-per-sequence 8 --joint-targets 32 --single-modality "${single_modality:-0.3}" --prefix-contexts 0.3 \
    --val-every "$every" --checkpoint-every "$every" --val-fraction "$fraction" --half \
    --schedule cosine "$@"
}

# The shipped weights' recipe (docs/results.md, "How the shipped weights were trained"): the
# first 3,000 steps at lr 1e-3, then, on the simulator, every network trained longer from the
# previous stage's model.dmbn at lr 5e-4.
if [ "${TRAIN:-0}" = 1 ]; then
  first=(--steps "$steps" --seed 1 --lr 1e-3)
  longer=(--lr 5e-4 --beta-nll 1)
  for m in "${models[@]}"; do
    case $set_name/$m in
      sim/attn) stage attn "${first[@]}" --model attn --beta-nll 1 --encoder-filters 16,32,64,64,128 \
          --decoder-filters 128,64,32,32,16,16,8 --coarse-tail
        stage attn-2 "${longer[@]}" --init "$out/runs/attn/model.dmbn" --steps 2000 --seed 2
        # Frames alone in 30% of the sequences (the imitation benchmark, `dmbn imitate`).
        single_modality=0.6 stage attn-3 --lr 5e-4 --beta-nll 1 --init "$out/runs/attn-2/best.dmbn" --steps 2000 --seed 3
        # Joints read from frames, frames alone in 90% of the sequences.
        single_modality=0.9 stage attn-4 --lr 5e-4 --beta-nll 1 --init "$out/runs/attn-3/model.dmbn" --frame-joints --steps 2000 --seed 5
        single_modality=0.9 stage attn-5 --lr 3e-4 --beta-nll 1 --init "$out/runs/attn-4/best.dmbn" --steps 4000 --seed 6
        single_modality=0.9 stage attn-6 --lr 2e-4 --beta-nll 1 --init "$out/runs/attn-5/model.dmbn" --steps 4000 --seed 8
        file[$m]=$out/runs/attn-6/model.dmbn ;;
      sim/pte) stage pte "${first[@]}" --model pte --beta-nll 1
        stage pte-2 "${longer[@]}" --init "$out/runs/pte/model.dmbn" --steps 3000 --seed 2
        file[$m]=$out/runs/pte-2/model.dmbn ;;
      sim/dmbn) stage dmbn "${first[@]}" --model dmbn --beta-nll 1
        stage dmbn-2 "${longer[@]}" --init "$out/runs/dmbn/model.dmbn" --steps 2000 --seed 2
        stage dmbn-3 "${longer[@]}" --init "$out/runs/dmbn-2/model.dmbn" --steps 3000 --seed 3
        stage dmbn-4 "${longer[@]}" --init "$out/runs/dmbn-3/model.dmbn" --steps 3000 --seed 4
        file[$m]=$out/runs/dmbn-4/model.dmbn ;;
      # DMBN-PTE's trained file, then the time warps (run after sim/pte: models are in that order).
      sim/pte-aug) stage pte-aug "${longer[@]}" --init "$out/runs/pte-2/model.dmbn" --augment --steps 2000 --seed 5
        file[$m]=$out/runs/pte-aug/model.dmbn ;;
      # The simulator's trained DMBN and DMBN-PTE fine-tuned here (DMBN-PTE then longer at half
      # the rate), then at half the rate with one normalising scale for the arm's joints
      # (--joint-scale shared: the wrist sweeps radians, the others tenths); the time warps
      # start from DMBN-PTE's last stage.
      2020/dmbn) init=$(sim_file dmbn-4)
        stage dmbn --init "$init" --steps 3000 --lr 5e-4 --seed 11 --beta-nll 1
        stage dmbn-2 --init "$out/runs/dmbn/model.dmbn" --joint-scale shared --steps 1000 --lr 2.5e-4 --seed 11 --beta-nll 1
        stage dmbn-3 --init "$out/runs/dmbn-2/model.dmbn" --joint-scale shared --steps 2000 --lr 2.5e-4 --seed 22 --beta-nll 1
        file[$m]=$out/runs/dmbn-3/model.dmbn ;;
      2020/pte) init=$(sim_file pte-2)
        stage pte --init "$init" --steps 3000 --lr 5e-4 --seed 12 --beta-nll 1
        stage pte-2 --init "$out/runs/pte/model.dmbn" --steps 2500 --lr 2.5e-4 --seed 13 --beta-nll 1
        stage pte-3 --init "$out/runs/pte-2/model.dmbn" --joint-scale shared --steps 1000 --lr 2.5e-4 --seed 11 --beta-nll 1
        stage pte-4 --init "$out/runs/pte-3/model.dmbn" --joint-scale shared --steps 2000 --lr 2.5e-4 --seed 21 --beta-nll 1
        file[$m]=$out/runs/pte-4/model.dmbn ;;
      2020/pte-aug) stage pte-aug --init "$out/runs/pte-4/model.dmbn" --joint-scale shared --augment --steps 3000 --lr 1.25e-4 --seed 29 --beta-nll 1
        file[$m]=$out/runs/pte-aug/model.dmbn ;;
      # The simulator's attentive model (stage attn-3 of the sim reproduction) fine-tuned here.
      2020/attn) init=$(sim_file attn-3)
        single_modality=0.5 stage attn --init "$init" --steps 1500 --lr 5e-4 --seed 1 --beta-nll 1
        single_modality=0.5 stage attn-2 --init "$out/runs/attn/best.dmbn" --steps 3000 --lr 3e-4 --seed 2 --beta-nll 1
        single_modality=0.5 stage attn-3 --init "$out/runs/attn-2/best.dmbn" --steps 3000 --lr 2e-4 --seed 3 --beta-nll 1
        file[$m]=$out/runs/attn-3/model.dmbn ;;
    esac
  done
  # The joint σ scales (docs/results.md, "Calibration"): fitted on ids the weights did not
  # train on. The simulator's on 30 more episodes per action (seeds 700000-700029); the
  # original data's on its validation ids 32-39, the only ids left (its 40 are few).
  if [ "$set_name" = sim ]; then
    calib=$out/calib
    [ -d "$calib" ] || "$bin/dmbn" simulate --out "$calib" --sequences 30 --seed 700000 >/dev/null
    calib_ids=0-29
  else
    calib=$data
    calib_ids=32-39
  fi
  for m in "${models[@]}"; do
    "$bin/dmbn" calibrate --model "${file[$m]}" --data "$calib" --ids "$calib_ids" \
      --out "$out/runs/$m-calibrated.dmbn"
    file[$m]=$out/runs/$m-calibrated.dmbn
  done
  # The attentive model's joint stage (docs/results.md, "The joint stage"): fitted to the
  # calibrated network on the network's own frames-only reads of the training ids.
  if [ "$set_name" = sim ] && [ -n "${file[attn]:-}" ]; then
    "$bin/train" --init "${file[attn]}" --steps 0 --joint-stage --data "$data" --out "$out/runs/attn-joint-stage"
    file[attn]=$out/runs/attn-joint-stage/model.dmbn
  fi
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
# Table 1 with the paper's own recipe (the original data): DMBN trained as the original was
# (Glorot-uniform weights, one sequence and one target per step, joint weight 0.01, Adam 1e-4;
# 15,000 steps). Its shape is the paper's, where the quality recipe's DMBN keeps time.
paper=$root/assets/models/dmbn-paper-$set_name.dmbn
if [ "${TRAIN:-0}" = 1 ] && [ "$set_name" = 2020 ]; then
  if [ -f "$out/runs/dmbn-paper/checkpoint/state.json" ]; then
    "$bin/train" --resume --data "$data" --out "$out/runs/dmbn-paper"
  else
    "$bin/train" --data "$data" --out "$out/runs/dmbn-paper" --model dmbn --initialization glorot \
      --batch 1 --targets-per-sequence 1 --max-contexts 5 --lr 1e-4 --schedule constant \
      --joint-weight 0.01 --val-fraction "$fraction" --steps 15000 --val-every 5000 \
      --checkpoint-every 5000 --half --seed 1
  fi
  paper=$out/runs/dmbn-paper/model.dmbn
fi
if [ -f "$paper" ] && [ -n "${file[pte-aug]:-}" ]; then
  "$bin/dmbn" probe --data "$probe_data" --dmbn "$paper" --pte "${file[pte-aug]}" --seeds 5 \
    "${probe_split[@]}" --out "$out/probe-paper-recipe"
fi

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
