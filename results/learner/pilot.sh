#!/usr/bin/env bash
# Issue #28's pilots: single-factor arms around the new learner, 300k physics steps each
# (150k fixed pose + 150k random poses), seeds 1 and 2, 30 random-pose evaluation episodes.
# Each arm is its own sweep folder under $OUT (default sweeps/learner_pilot); two runs at a
# time, one core each. Run from the repository root: bash results/learner/pilot.sh [ARM...]
set -euo pipefail
OUT=${OUT:-sweeps/learner_pilot}
STEPS=${STEPS:-300000}
# Arms are relative to the code's defaults at the commit they ran on: "new" and "fixed_lr" ran
# on 657df7c (adaptive learning rate by default), the others on the commit that made the
# fixed schedule self-touch's default (where "new" would be "--set ppo.schedule=adaptive").
declare -A ARMS=(
  [new]=""
  [fixed_lr]="--set ppo.schedule=fixed"
  [separate]="--set network.layout=separate"
  [paper_head]="--set network.head=paper"
  [no_norm]="--set ppo.normalize_rewards=false"
  [k1]="--set env.action_repeat=1 --set ppo.num_steps_per_env=128 --set ppo.gamma=0.995"
  [onset]="--set behavior.touch_count=onset"
  [old]="--set network.head=paper --set ppo.normalize_rewards=false --set env.action_repeat=1 --set ppo.num_steps_per_env=128 --set ppo.gamma=0.995"
)
ORDER=(${@:-separate onset paper_head no_norm k1})
for arm in "${ORDER[@]}"; do
  # shellcheck disable=SC2086
  .venv/bin/devlearn sweep self_touch --out "$OUT/$arm" --seeds 1,2 --steps "$STEPS" \
    --envs 16 --workers 0 --jobs 2 --episodes 30 \
    --set torch_threads=1 --set behavior.fixed_pose_steps=$((STEPS / 2)) ${ARMS[$arm]}
done
