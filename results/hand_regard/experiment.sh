#!/usr/bin/env bash
# Issue #29's experiment: hand regard in BabyBench's scene (sitting_babybench), trained and
# evaluated from BabyBench's start, with the defaults of the commit it runs on (a decision every
# 5 physics steps, bounded spread, reward normalisation, the proprioception + detector policy).
#
# Curriculum: the paper's three stages compressed to 614,400 physics steps (61,440 left arm +
# 61,440 right arm + 491,520 both arms: 10% / 10% / 80%, the paper's 175k + 175k + 1.5M is
# 9.5% / 9.5% / 81%), 8 envs, seeds 1-3 per arm. Every run uses one shared detector,
# results/hand_regard/detector/babybench_mittens_detector.json (10,000 steps of babbling, seed 0,
# one arm per episode: exactly what each run would calibrate for itself), copied into its folder.
#
# Arms: the paper's reward (the control), ours (paper + bilateral_balance), the paper's reward +
# the forward_model curiosity term. Each run is evaluated by the sweep on 10 episodes of 1,000
# steps from BabyBench's start (eval seed 0), then from random starts (the generalisation row),
# and the zero, random and held-random baselines under the identical protocols.
# Two runs at a time, one core each. From the repository root:
#   bash results/hand_regard/experiment.sh OUT
set -euo pipefail
OUT=${1:?usage: experiment.sh OUT}
STEPS=${STEPS:-614400}
STAGE=${STAGE:-61440}
EPISODES=${EPISODES:-10}
DET=results/hand_regard/detector/babybench_mittens_detector.json
common=(--steps "$STEPS" --envs 8 --workers 0 --jobs 2 --episodes "$EPISODES" --eval-seed 0
  --set torch_threads=1 --set behavior.detector_file="$DET"
  --set behavior.left_arm_steps="$STAGE" --set behavior.right_arm_steps="$STAGE" --no-report)
.venv/bin/devlearn sweep hand_regard --out "$OUT/rewards" --grid behavior.reward=paper,bilateral \
  --seeds 1,2,3 "${common[@]}"
.venv/bin/devlearn sweep hand_regard --out "$OUT/curiosity" --seeds 1,2,3 \
  --set behavior.reward=paper --set curiosity=forward_model "${common[@]}"
for policy in zero random held_random; do
  for start in babybench random; do
    dir="$OUT/baseline_${policy}_$start"
    [ -f "$dir/eval.json" ] || .venv/bin/devlearn eval hand_regard --policy "$policy" \
      --episodes "$EPISODES" --seed 0 --start "$start" --set behavior.detector_file="$DET" \
      --out "$dir" > /dev/null
  done
done
for run in "$OUT"/rewards/runs/*/ "$OUT"/curiosity/runs/*/; do
  [ -f "$run/eval_random/eval.json" ] || .venv/bin/devlearn eval hand_regard \
    --checkpoint "$run/checkpoint_latest.pt" --episodes "$EPISODES" --seed 0 --start random \
    --out "$run/eval_random" > /dev/null
done
