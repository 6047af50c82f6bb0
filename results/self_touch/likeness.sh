#!/usr/bin/env bash
# Issue #43's likeness measures of the published policies of issue #30's curriculum (5 seeds,
# 8,192,000 steps) and of the zero and random baselines, under the evaluation protocol (random
# initial poses, eval seed 0, 10-step settle, mean action), EPISODES (50) episodes each. From
# the repository root: bash results/self_touch/likeness.sh OUT; then
#   python results/self_touch/likeness_table.py OUT
set -euo pipefail
# Seeds 1, 2, 3 and 5's policy files are in git history since issue #54: restore them first
# (results/self_touch/README.md, "Where and on what it ran").
OUT=${1:?usage: likeness.sh OUT}
EPISODES=${EPISODES:-50}
DEVLEARN=${DEVLEARN:-.venv/bin/devlearn}
run() {  # run DIR ARGS...: one evaluation unless DIR/eval.json exists
  local dir=$1
  shift
  [ -f "$dir/eval.json" ] || "$DEVLEARN" eval self_touch "$@" --episodes "$EPISODES" --seed 0 \
    --json --out "$dir" > /dev/null
}
for seed in 1 2 3 4 5; do
  run "$OUT/seed=$seed" --checkpoint "results/self_touch/i30/curriculum/runs/seed=$seed/policy.pt"
done
for policy in zero random; do
  run "$OUT/baseline_$policy" --policy "$policy"
done
