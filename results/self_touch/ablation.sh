#!/usr/bin/env bash
# Issue #30's ablation (the paper's Table II) with independent arms: fixed-only, random-only
# and two-stage (half the budget each stage), each trained from scratch for the same STEPS
# physics steps, one run per arm and seed, with the defaults of the commit it runs on; the
# final checkpoint evaluated as in curriculum.sh: 100 random-pose episodes (eval seed 0,
# 10-step settle, deterministic policy) and from the rest pose (--start rest); zero and random
# baselines under both protocols. Two runs at a time, one core each; a rerun resumes (the
# sweep continues unfinished runs, written evaluations are skipped). From the repository root:
#   bash results/self_touch/ablation.sh OUT SEEDS STEPS [ARGS...]  # e.g. sweeps/abl30 1-5 8192000
# ARGS go to `devlearn sweep`. ARMS (fixed_only,random_only,two_stage) picks arms, so that the
# runs can be spread over sessions; ENVS (16), EPISODES (100) and JOBS (2) can be set for smoke
# tests; STEPS must be a multiple of 2 x ENVS x 64 x 5 (whole iterations in each stage).
# Layout: OUT/runs/curriculum=ARM,seed=N/ (run; eval/ the final random-pose evaluation,
# rest/ the rest-pose one), OUT/baseline_{zero,random}[_rest]/; OUT/report/ the sweep's.
set -euo pipefail
USAGE="usage: ablation.sh OUT SEEDS STEPS [ARGS...]"
OUT=${1:?$USAGE}
SEEDS=${2:?$USAGE}
STEPS=${3:?$USAGE}
shift 3
ENVS=${ENVS:-16}
EPISODES=${EPISODES:-100}
JOBS=${JOBS:-2}
ARMS=${ARMS:-fixed_only,random_only,two_stage}
PER_ITERATION=$((ENVS * 64 * 5))  # self_touch's ppo.num_steps_per_env x env.action_repeat
if ((STEPS % (2 * PER_ITERATION))); then
  echo "STEPS=$STEPS must be a multiple of $((2 * PER_ITERATION))" >&2
  exit 2
fi
DEVLEARN=${DEVLEARN:-.venv/bin/devlearn}
# shellcheck source=results/self_touch/common.sh
source "$(dirname "$0")/common.sh"

"$DEVLEARN" sweep self_touch --out "$OUT" --seeds "$SEEDS" --steps "$STEPS" \
  --grid behavior.curriculum="$ARMS" \
  --envs "$ENVS" --workers 0 --jobs "$JOBS" --episodes "$EPISODES" --eval-seed 0 \
  --set torch_threads=1 --set behavior.fixed_pose_steps=$((STEPS / 2)) \
  --set behavior.random_pose_steps=$((STEPS / 2)) "$@"

shopt -s nullglob
for run in "$OUT"/runs/curriculum=*/; do
  run=${run%/}
  evaluate "$run/rest" --checkpoint "$run/checkpoint_$STEPS.pt" --start rest
done
baselines "$OUT"
