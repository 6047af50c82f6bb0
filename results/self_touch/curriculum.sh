#!/usr/bin/env bash
# Issue #30: the paper's two-stage curriculum with the defaults of the commit it runs on,
# 4,096,000 fixed-pose + 4,096,000 random-pose physics steps (the paper's 4M + 4M rounded to
# a multiple of the 1,024,000-step evaluation interval), one run per seed; every seed's
# checkpoints at each 1,024,000 steps (the 4,096,000 one is the stage switch) evaluated on
# 100 random-pose episodes (eval seed 0, 10-step settle, deterministic policy), the final
# one also from the rest pose (--start rest); zero and random baselines under the same two
# protocols (random actions held for the behaviour's default action repeat). JOBS runs (and
# evaluations) at a time, one core each. Evaluations already written are skipped, so a rerun resumes: the
# sweep continues unfinished runs from their checkpoints. From the repository root:
#   bash results/self_touch/curriculum.sh OUT SEEDS [ARGS...]     # e.g. sweeps/st30 1-5
# ARGS go to `devlearn sweep` (e.g. --set ppo.entropy_coef=0.01). Budgets (for smoke tests):
#   STAGE_STEPS (4096000) physics steps per stage; EVAL_EVERY (1024000) between evaluated
#   checkpoints, a multiple of one iteration (ENVS x 64 decisions x 5 physics steps) that
#   divides STAGE_STEPS; ENVS (16); EPISODES (100); JOBS (2).
# Layout: OUT/runs/seed=N/ (run folder; eval/ the sweep's evaluation of the final checkpoint),
# OUT/runs/seed=N/at_STEP/eval.json (earlier checkpoints), OUT/runs/seed=N/rest/eval.json,
# OUT/baseline_{zero,random}/ and OUT/baseline_{zero,random}_rest/; OUT/report/ the sweep's.
set -euo pipefail
OUT=${1:?usage: curriculum.sh OUT SEEDS [ARGS...]}
SEEDS=${2:?usage: curriculum.sh OUT SEEDS [ARGS...]}
shift 2
STAGE_STEPS=${STAGE_STEPS:-4096000}
EVAL_EVERY=${EVAL_EVERY:-1024000}
ENVS=${ENVS:-16}
EPISODES=${EPISODES:-100}
JOBS=${JOBS:-2}
PER_ITERATION=$((ENVS * 64 * 5))  # self_touch's ppo.num_steps_per_env x env.action_repeat
if ((EVAL_EVERY % PER_ITERATION || STAGE_STEPS % EVAL_EVERY)); then
  echo "EVAL_EVERY=$EVAL_EVERY must be a multiple of $PER_ITERATION and divide" \
    "STAGE_STEPS=$STAGE_STEPS" >&2
  exit 2
fi
TOTAL=$((2 * STAGE_STEPS))
DEVLEARN=${DEVLEARN:-.venv/bin/devlearn}
# shellcheck source=results/self_touch/common.sh
source "$(dirname "$0")/common.sh"

# checkpoint_<step>.pt every save_interval iterations (each EVAL_EVERY steps) and before the
# random-pose stage (STAGE_STEPS, a multiple of EVAL_EVERY)
"$DEVLEARN" sweep self_touch --out "$OUT" --seeds "$SEEDS" --steps "$TOTAL" \
  --envs "$ENVS" --workers 0 --jobs "$JOBS" --episodes "$EPISODES" --eval-seed 0 \
  --set torch_threads=1 --set behavior.curriculum=two_stage \
  --set behavior.fixed_pose_steps="$STAGE_STEPS" --set behavior.random_pose_steps="$STAGE_STEPS" \
  --set save_interval=$((EVAL_EVERY / PER_ITERATION)) "$@"

# the earlier checkpoints' evaluations, JOBS at a time (the final checkpoint's is the sweep's,
# in $run/eval); a failed evaluation fails the script
shopt -s nullglob
throttle() { while (($(jobs -rp | wc -l) >= JOBS)); do wait -n; done; }
for run in "$OUT"/runs/seed=*/; do
  run=${run%/}
  for ((step = EVAL_EVERY; step < TOTAL; step += EVAL_EVERY)); do
    throttle
    evaluate "$run/at_$step" --checkpoint "$run/checkpoint_$step.pt" &
  done
  throttle
  evaluate "$run/rest" --checkpoint "$run/checkpoint_$TOTAL.pt" --start rest &
done
while (($(jobs -rp | wc -l))); do wait -n; done
baselines "$OUT"
