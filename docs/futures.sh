#!/usr/bin/env bash
# Re-make the figures of docs/results.md, *Many futures*: sampled futures of the page's default
# model (assets/models/attn-sim.dmbn) finishing grasps and pushes from their first 30%.
#
#   bash docs/futures.sh design [OUT]   # the design sets (seeds 1000000-, 1400000-, 1500000-, 1600000-): the sampling settings compared
#   bash docs/futures.sh final  [OUT]   # the three fresh sets (seeds 3100000-, 3200000-, 3300000-): the reported table
#                                       # (the defaults; the 8 as drawn; drawn with independent joints; the defaults before)
#   bash docs/futures.sh further [OUT]  # the defaults on three more fresh sets (seeds 3400000-, 3500000-, 3600000-)
#   bash docs/futures.sh latent [OUT]   # the latent path against autoregressive sampling, on the design set
#   bash docs/futures.sh script         # what 8 futures drawn from the simulator's script itself would score
#
# Each set is 100 simulated demonstrations per action (`dmbn simulate --sequences 100`). OUT
# (default out/futures) receives the data, every run's JSON and printed tables. On a 2-core
# machine: design about 2.5 h, final about 30 min, further about 10 min, latent about 3 h (its training), script
# seconds.
set -euo pipefail

what=${1:?usage: bash docs/futures.sh design|final|further|latent|script [OUT]}
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

# The defaults: the page's model finishing set SEED's demonstrations, 8 futures each.
finish() {
  local set
  set=$(data "$1")
  "$dmbn" imitate --model "$model" --data "$set" --task finish --samples 8 --json "$out/finish-$1.json" | tee "$out/finish-$1.txt"
}

# The page's model with a joint correlation per action over both drawn steps (fitted on the
# shipped file's 300 unseen episodes per action, seeds 750000-): the defaults before the
# regions per drawn step, with 3 principal directions.
actions() {
  if [ ! -f "$out/attn-sim-actions.dmbn" ]; then
    [ -d "$out/calib-750000" ] || "$dmbn" simulate --out "$out/calib-750000" --sequences 300 --seed 750000 >/dev/null
    "$dmbn" calibrate --model "$model" --data "$out/calib-750000" --ids 0-299 --fit correlation --regions actions \
      --out "$out/attn-sim-actions.dmbn" >/dev/null
  fi
  echo "$out/attn-sim-actions.dmbn"
}

# The page's model with one joint correlation pooled over both actions, fitted as it was
# before the regions (the σ scales' 30 unseen episodes, seeds 700000-): the defaults before
# the regions per action.
pooled() {
  if [ ! -f "$out/attn-sim-pooled.dmbn" ]; then
    [ -d "$out/calib" ] || "$dmbn" simulate --out "$out/calib" --sequences 30 --seed 700000 >/dev/null
    "$dmbn" calibrate --model "$model" --data "$out/calib" --ids 0-29 --fit correlation --regions 1 \
      --out "$out/attn-sim-pooled.dmbn" >/dev/null
  fi
  echo "$out/attn-sim-pooled.dmbn"
}

# Where a run's futures take the object against the demonstrations (the ceiling's replays):
# the median push travel and grasp carry (cm from where the object rested), how far apart
# a demonstration's futures push (the standard deviation of their travel, mean over pushes),
# and where they are centred: the median travel of a push's futures against the push's own
# (Pearson's r) and from push to push (its standard deviation).
spread() {
  [ -f "$1" ] || return 0
  python3 - "$1" "$2" <<'PY'
import json, statistics, sys
from collections import defaultdict
run = json.load(open(sys.argv[1]))[0]
ceiling = [p for p in run["performances"] if p["trajectory"].startswith("ceiling")]
futures = run["future_performances"]
median = lambda rows, action: statistics.median(r["travel_cm"] for r in rows if r["action"] == action)
travel = defaultdict(list)
for f in futures:
    if f["action"] == "move":
        travel[f["id"]].append(f["travel_cm"])
own = {p["id"]: p["travel_cm"] for p in ceiling if p["action"] == "move"}
ids = sorted(travel)
centre = [statistics.median(travel[i]) for i in ids]
r = statistics.correlation(centre, [own[i] for i in ids])
print(f"{sys.argv[2]}: push travel spread {statistics.mean(map(statistics.pstdev, travel.values())):.2f} cm; "
      f"median push travel {median(futures, 'move'):.1f} cm (demonstrations {median(ceiling, 'move'):.1f}), "
      f"grasp carry {median(futures, 'grasp'):.1f} cm (demonstrations {median(ceiling, 'grasp'):.1f}); "
      f"a push's futures centred: r {r:.2f} with its own travel, {statistics.pstdev(centre):.2f} cm from push to push")
PY
}

case $what in
  design)
    # grid order τ joints K (oversample) sets: the settings compared on the design set, those
    # of the oversampling on a second one too (seeds 1400000-); every correlated draw along
    # all of R's directions (pooled over both actions), each future from all the observations,
    # every step at τ.
    for cfg in "1 left-to-right 1 independent 1 1" "2 left-to-right 1 independent 1 1" \
      "3 left-to-right 1 independent 1 1" "4 left-to-right 1 independent 1 1" "8 left-to-right 1 independent 1 1" \
      "4 random 1 independent 1 1" "8 random 1 independent 1 1" "2 left-to-right 0.85 independent 1 1" \
      "2 left-to-right 0.7 independent 1 1" "3 left-to-right 0.7 independent 1 1" "2 left-to-right 0.5 independent 1 1" \
      "2 left-to-right 0.7 correlated 1 2" "2 left-to-right 0.85 correlated 1 1" "2 left-to-right 1 correlated 1 1" \
      "3 left-to-right 0.85 correlated 1 1" "3 left-to-right 1 correlated 1 1" \
      "2 left-to-right 0.7 correlated 2 2" "2 left-to-right 0.7 correlated 4 2" "2 left-to-right 0.7 correlated 8 2" \
      "2 left-to-right 0.85 correlated 4 2" "2 left-to-right 1 correlated 4 1"; do
      read -r grid order tau joints k sets <<<"$cfg"
      for seed in 1000000 1400000; do
        [ "$seed" = 1400000 ] && [ "$sets" = 1 ] && continue
        set=$(data $seed)
        name="$out/design-$seed-g$grid-$order-t$tau-$joints-k$k"
        "$dmbn" imitate --model "$(pooled)" --data "$set" --task finish --samples 8 --grid "$grid" \
          --order "$order" --temperature "$tau" --end-temperature "$tau" --joints "$joints" --oversample "$k" \
          --components all --bootstrap false --stage false --json "$name.json" >"$name.txt"
        grep -A5 "sampled futures each" "$name.txt" | grep '^| [gm]' | sed "s/^/$seed g$grid $order τ$tau $joints K$k /"
      done
    done
    # C (principal directions), bootstrap, the joint stage, τ on four design sets (2 steps
    # left to right, correlated, K = 4). The defaults: 3 true true 0.7.
    for cfg in "all false false 0.7" "3 false false 0.85" "3 false false 1" "all true false 0.7" "3 true false 0.85" \
      "3 true false 0.7" "3 true false 1" "3 true true 0.7"; do
      read -r c boot stage tau <<<"$cfg"
      for seed in 1000000 1400000 1500000 1600000; do
        set=$(data $seed)
        name="$out/design-$seed-c$c-boot$boot-stage$stage-t$tau"
        "$dmbn" imitate --model "$(pooled)" --data "$set" --task finish --samples 8 --components "$c" \
          --bootstrap "$boot" --stage "$stage" --temperature "$tau" --end-temperature "$tau" \
          --json "$name.json" >"$name.txt"
        grep -A5 "sampled futures each" "$name.txt" | grep '^| [gm]' | sed "s/^/$seed C$c bootstrap $boot stage $stage τ$tau /"
      done
    done
    # The joint correlation pooled or a region per action, and the future's end drawn at τ
    # 0.7 or 1 (the rest at 0.7), along 3 principal directions.
    for cfg in "pooled 1" "actions 0.7" "actions 1"; do
      read -r regions end <<<"$cfg"
      file=$(actions)
      [ "$regions" = pooled ] && file=$(pooled)
      for seed in 1000000 1400000 1500000 1600000; do
        set=$(data $seed)
        name="$out/design-$seed-$regions-end$end"
        "$dmbn" imitate --model "$file" --data "$set" --task finish --samples 8 --end-temperature "$end" \
          --components 3 --json "$name.json" >"$name.txt"
        grep -A5 "sampled futures each" "$name.txt" | grep '^| [gm]' | sed "s/^/$seed R $regions, end τ$end /"
      done
    done
    # A region per action, or per action and drawn step (the shipped file), along 3 or 2
    # principal directions (the end at τ 1). The defaults: steps 2.
    for cfg in "actions 2" "steps 3" "steps 2"; do
      read -r regions c <<<"$cfg"
      file=$model
      [ "$regions" = actions ] && file=$(actions)
      for seed in 1000000 1400000 1500000 1600000; do
        set=$(data $seed)
        name="$out/design-$seed-$regions-c$c"
        "$dmbn" imitate --model "$file" --data "$set" --task finish --samples 8 --components "$c" \
          --json "$name.json" >"$name.txt"
        grep -A5 "sampled futures each" "$name.txt" | grep '^| [gm]' | sed "s/^/$seed R $regions, C $c /"
      done
    done
    ;;
  final)
    for seed in 3100000 3200000 3300000; do
      set=$(data $seed)
      finish "$seed"
      # The defaults before (a joint correlation per action over both drawn steps, along 3
      # principal directions).
      "$dmbn" imitate --model "$(actions)" --data "$set" --task finish --samples 8 --components 3 \
        --json "$out/finish-before-$seed.json" | tee "$out/finish-before-$seed.txt"
      # The 8 as drawn (no representatives), and drawn with independent joints.
      "$dmbn" imitate --model "$model" --data "$set" --task finish --samples 8 --oversample 1 \
        --json "$out/finish-drawn-$seed.json" | tee "$out/finish-drawn-$seed.txt"
      "$dmbn" imitate --model "$model" --data "$set" --task finish --samples 8 --oversample 1 --joints independent \
        --json "$out/finish-independent-$seed.json" | tee "$out/finish-independent-$seed.txt"
      "$dmbn" imitate --model "$model" --data "$set" --task frames --json "$out/frames-$seed.json" | tee "$out/frames-$seed.txt"
      "$dmbn" score --model "$model" --data "$set" --scenario extrap --samples 8 --json "$out/score-$seed.json" | tee "$out/score-$seed.txt"
    done
    for seed in 3100000 3200000 3300000; do
      spread "$out/finish-$seed.json" "set $seed, the defaults"
      spread "$out/finish-before-$seed.json" "set $seed, the defaults before"
      spread "$out/finish-drawn-$seed.json" "set $seed, as drawn"
      spread "$out/finish-independent-$seed.json" "set $seed, as drawn, independent joints"
    done
    ;;
  further)
    # The defaults on three more fresh sets, first run after the choice and after `final`: how
    # far the mean over three sets moves with the demonstrations drawn.
    for seed in 3400000 3500000 3600000; do
      finish "$seed"
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
    # A path trained with the network from the start: 20,000 steps, about 1.5 h on two cores.
    if [ ! -f "$out/scratch/model.dmbn" ]; then
      if [ -f "$out/scratch/checkpoint/state.json" ]; then
        "$CARGO_TARGET_DIR/release/train" --resume --data "$sim" --out "$out/scratch"
      else
        "$CARGO_TARGET_DIR/release/train" --data "$sim" --out "$out/scratch" --model attn --joint-weight 1 \
          --contexts-in-targets --targets-per-sequence 8 --joint-targets 32 --single-modality 0.6 \
          --prefix-contexts 0.5 --val-every 500 --checkpoint-every 250 --val-fraction 0.1 --half \
          --schedule cosine --lr 1e-3 --beta-nll 1 --encoder-filters 16,32,64,64,128 \
          --decoder-filters 128,64,32,32,16,16,8 --coarse-tail --frame-joints --steps 20000 --seed 31 \
          --latent 16 --latent-kl 0.003 --latent-free-nats 8
      fi
    fi
    for run in kl003-latent-1 free3-latent-1 free3-latent-2.5 free3-ar-0.7 free8-latent-1 free8-latent-2.5 long8-latent-1 long8-latent-2.5 scratch-latent-1 scratch-latent-2; do
      IFS=- read -r name method tau <<<"$run"
      "$dmbn" imitate --model "$out/$name/model.dmbn" --data "$set" --task finish --samples 8 \
        --method "$method" --temperature "$tau" --bootstrap false --json "$out/latent-$run.json" >"$out/latent-$run.txt"
      grep -A5 "sampled futures each" "$out/latent-$run.txt" | grep '^| [gm]' | sed "s/^/$run /"
      spread "$out/latent-$run.json" "$run"
    done
    spread "$out/design-1000000-c3-boottrue-stagetrue-t0.7.json" "attn-sim, the defaults (bash docs/futures.sh design)"
    for run in independent-k1 correlated-k1 correlated-k4; do
      spread "$out/design-1000000-g2-left-to-right-t0.7-$run.json" "attn-sim-ar-0.7-$run (bash docs/futures.sh design)"
    done
    ;;
  script)
    # The script (crate/sim/script.rs) draws a grasp's carry spot uniformly within ±6 cm of
    # the object on each axis and a push's length uniformly in 12-22 cm, after the first 30%.
    # Futures drawn from the script itself, judged as `imitate` judges (a grasp within 5 cm of
    # the demonstration's spot, a push within 3 cm along its direction):
    python3 - <<'PY'
import math, random
r, n, s = random.Random(0), 100_000, 8
spot = lambda: (r.uniform(-6, 6), r.uniform(-6, 6))
valid = covered = pushes = centre = 0
for _ in range(n):
    demo = spot()
    centre += math.dist(demo, (0, 0)) < 5
    hits = [math.dist(demo, spot()) < 5 for _ in range(s)]
    valid, covered = valid + sum(hits), covered + any(hits)
    length = r.uniform(12, 22)
    pushes += any(abs(length - r.uniform(12, 22)) < 3 for _ in range(s))
print(f"the script's own futures, {s} a demonstration: grasps valid (carried within 5 cm) "
      f"{valid / (s * n):.0%}, covered {covered / n:.0%}; pushes covered {pushes / n:.0%}; "
      f"a push's length spreads {10 / math.sqrt(12):.1f} cm (standard deviation); grasp futures all carried "
      f"to the square's centre, the most any sampler's can be valid: {centre / n:.0%}")
PY
    ;;
  *)
    echo "error: the first argument is design, final, further, latent or script, not '$what'" >&2
    exit 2
    ;;
esac
