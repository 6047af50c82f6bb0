#!/usr/bin/env bash
# Issue #45's comparison: devlearn's PPO (the defaults of `devlearn run self_touch`), SB3 PPO at
# the same 2,048,000 physics steps, and SB3 SAC for as long as devlearn's run of the same seed
# learned (wall-clock seconds of learning: collect + update summed over metrics.jsonl's rows,
# SB3's learn_s), 3 seeds each, one run per core (--workers 0, one torch thread), then every
# final policy evaluated under one protocol (100 random-pose episodes, eval seed 0, mean action)
# beside the zero and random baselines. A rerun skips what is done: a devlearn run resumes, an
# unfinished SB3 run starts again. From the repository root, with nothing else running:
#   bash results/learners/experiment.sh OUT [SEEDS] [STEPS]     # e.g. /work/sweeps/learners 1-3
# then: python results/learners/table.py OUT
set -euo pipefail
OUT=${1:?usage: experiment.sh OUT [SEEDS] [STEPS]}
SEEDS=${2:-1-3}
STEPS=${3:-2048000}
EPISODES=${EPISODES:-100}
DEVLEARN=${DEVLEARN:-.venv/bin/devlearn}
PYTHON=${PYTHON:-.venv/bin/python}
seeds=$(seq "${SEEDS%-*}" "${SEEDS#*-}")
mkdir -p "$OUT"

ours() {  # ours SEED: devlearn's PPO, resumed if interrupted
  local dir=$OUT/devlearn_ppo/seed=$1
  [ -f "$dir/checkpoint_$STEPS.pt" ] && return
  if [ -f "$dir/checkpoint_latest.pt" ]; then
    "$DEVLEARN" run self_touch --resume "$dir"
  else
    "$DEVLEARN" run self_touch --steps "$STEPS" --seed "$1" --workers 0 --set torch_threads=1 \
      --out "$dir" --force
  fi
}

learn_seconds() {  # learn_seconds RUN: devlearn's learning time (collect + update)
  "$PYTHON" -c 'import json,sys; print(round(sum(r["collect_s"]+r["update_s"] for r in map(json.loads, open(sys.argv[1])))))' "$1/metrics.jsonl"
}

sb3() {  # sb3 ALGO SEED [ARGS...]: one SB3 run, from scratch unless it finished
  local algo=$1 seed=$2 dir=$OUT/sb3_$1/seed=$2
  shift 2
  [ -f "$dir/train.json" ] && return
  rm -rf "$dir"
  "$PYTHON" examples/sb3/train.py --algo "$algo" --steps "$STEPS" --seed "$seed" --workers 0 \
    --threads 1 --out "$dir" "$@"
}

sac() {  # sac SEED: SB3 SAC for as long as devlearn's run of this seed learned
  sb3 sac "$1" --seconds "$(learn_seconds "$OUT/devlearn_ppo/seed=$1")"
}

evaluate() {  # evaluate DIR ARGS...: one evaluation unless DIR/eval.json exists
  local dir=$1
  shift
  [ -f "$dir/eval.json" ] || "$DEVLEARN" eval self_touch "$@" --episodes "$EPISODES" --seed 0 \
    --json --out "$dir" > /dev/null
}

# Two at a time: devlearn's runs first (SAC's budgets come from them), then SB3 PPO, then SAC.
jobs=()
for s in $seeds; do jobs+=("ours $s"); done
for s in $seeds; do jobs+=("sb3 ppo $s"); done
for s in $seeds; do jobs+=("sac $s"); done
running=0
for job in "${jobs[@]}"; do
  if [[ $job == sac* ]]; then wait; running=0; fi  # every devlearn run has finished
  echo "$(date +%T) start: $job"
  $job > "$OUT/log_${job// /_}.txt" 2>&1 &
  running=$((running + 1))
  if ((running == 2)); then wait -n; running=1; fi
done
wait

for s in $seeds; do
  evaluate "$OUT/devlearn_ppo/seed=$s/eval" --checkpoint "$OUT/devlearn_ppo/seed=$s/checkpoint_$STEPS.pt"
  for algo in ppo sac; do
    evaluate "$OUT/sb3_$algo/seed=$s/eval" --checkpoint "$OUT/sb3_$algo/seed=$s/policy.pt"
  done
done
evaluate "$OUT/baseline_zero" --policy zero
evaluate "$OUT/baseline_random" --policy random
