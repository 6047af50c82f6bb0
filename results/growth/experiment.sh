#!/usr/bin/env bash
# Issue #41's experiment: does growing while learning help, hurt or not matter for self-touch?
# Four arms on the defaults of the commit it runs on, each trained from scratch for STEPS physics
# steps (the paper's two stages, half the budget each), SEEDS seeds per arm, one run per core:
#   fixed6, fixed12, fixed18: the body at 6, 12 or 18 months throughout (infant.age_months);
#   grow6to18: the body grows from 6 to 18 months over the run (infant.growth=6->18, 24 pieces).
# Every final checkpoint is evaluated at 6, 12 and 18 months (100 random-pose episodes, eval seed
# 0, mean action: its own age is the arm's headline, the others the transfer), and the zero and
# random baselines at each age. A rerun resumes the sweeps and skips written evaluations.
# From the repository root, with nothing else running:
#   bash results/growth/experiment.sh OUT [SEEDS] [STEPS]    # e.g. /work/sweeps/growth 1-5 2048000
#   python results/growth/table.py OUT
# ENVS (16), EPISODES (100) and JOBS (2) for smoke tests; STEPS a multiple of 2 x ENVS x 64 x 5.
set -euo pipefail
OUT=${1:?usage: experiment.sh OUT [SEEDS] [STEPS]}
SEEDS=${2:-1-5}
STEPS=${3:-2048000}
ENVS=${ENVS:-16}
EPISODES=${EPISODES:-100}
JOBS=${JOBS:-2}
AGES=(6 12 18)
DEVLEARN=${DEVLEARN:-.venv/bin/devlearn}
PER_ITERATION=$((ENVS * 64 * 5))
if ((STEPS % (2 * PER_ITERATION))); then
  echo "STEPS=$STEPS must be a multiple of $((2 * PER_ITERATION))" >&2
  exit 2
fi

arm() {  # arm NAME GRID: one sweep
  "$DEVLEARN" sweep self_touch --out "$OUT/$1" --seeds "$SEEDS" --steps "$STEPS" --grid "$2" \
    --envs "$ENVS" --workers 0 --jobs "$JOBS" --episodes "$EPISODES" --eval-seed 0 \
    --set torch_threads=1 --set behavior.curriculum=two_stage \
    --set behavior.fixed_pose_steps=$((STEPS / 2)) --set behavior.random_pose_steps=$((STEPS / 2))
}

evaluate() {  # evaluate DIR ARGS...: one evaluation unless DIR/eval.json exists, JOBS at a time
  local dir=$1
  shift
  [ -f "$dir/eval.json" ] && return
  while (($(jobs -rp | wc -l) >= JOBS)); do wait -n; done
  "$DEVLEARN" eval self_touch "$@" --episodes "$EPISODES" --seed 0 --json --out "$dir" > /dev/null &
}

arm fixed "infant.age_months=$(IFS=,; echo "${AGES[*]}")"
arm grow "infant.growth=6->18"
shopt -s nullglob
for run in "$OUT"/fixed/runs/*/ "$OUT"/grow/runs/*/; do
  run=${run%/}
  for age in "${AGES[@]}"; do
    evaluate "$run/at_${age}_months" --checkpoint "$run/checkpoint_$STEPS.pt" \
      --set infant.age_months="$age"
  done
done
for age in "${AGES[@]}"; do
  for policy in zero random; do
    evaluate "$OUT/baseline_${policy}_${age}_months" --policy "$policy" --set infant.age_months="$age"
  done
done
wait
