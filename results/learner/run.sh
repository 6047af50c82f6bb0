#!/usr/bin/env bash
# Issue #28's evidence: self-touch, the two-stage curriculum at 2,048,000 steps (1,024,000
# fixed pose + 1,024,000 random poses), seeds 1-3, with the defaults of the commit it runs on
# (plus ARGS, e.g. --set network.layout=separate), evaluated on 100 random-pose episodes (eval
# seed 0, 10-step settle), and the zero and random baselines under the same protocol at the
# default decision rate. Two runs at a time, one core each. From the repository root:
#   bash results/learner/run.sh OUT [ARGS...]
set -euo pipefail
OUT=${1:?usage: run.sh OUT [ARGS...]}
shift
.venv/bin/devlearn sweep self_touch --out "$OUT" --seeds 1,2,3 --steps 2048000 \
  --envs 16 --workers 0 --jobs 2 --episodes 100 --eval-seed 0 \
  --set torch_threads=1 --set behavior.fixed_pose_steps=1024000 "$@"
for policy in zero random; do
  [ -f "$OUT/baseline_$policy/eval.json" ] || .venv/bin/devlearn eval self_touch \
    --policy "$policy" --episodes 100 --seed 0 --json --out "$OUT/baseline_$policy" > /dev/null
done
