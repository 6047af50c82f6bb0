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
# The paper's CNN policy (`behavior.policy=cnn`: the eyes' images through the paper's network,
# the paper's reward) trains the same curriculum for seeds 1-2: whether the CPU variant's result
# carries over to the paper's network (about 100 physics steps/s per core: ~1 h 45 min a run).
# Issue #40's pilot, not in the default ARMS: cnn_asym, the same CNN actor with the asymmetric
# critic (`behavior.critic=proprio`: proprioception and the detector's output, no eye CNNs),
# seeds 1-2: whether the CNN arm's 614k-step result holds with the cheaper update.
# Two runs at a time, one core each. From the repository root:
#   bash results/hand_regard/experiment.sh OUT
#   ARMS=cnn bash results/hand_regard/experiment.sh OUT   # one part: rewards curiosity cnn
#                                                         # cnn_asym baselines
set -euo pipefail
OUT=${1:?usage: experiment.sh OUT}
ARMS=${ARMS:-rewards curiosity cnn baselines}
has() { [[ " $ARMS " == *" $1 "* ]]; }
STEPS=${STEPS:-614400}
STAGE=${STAGE:-61440}
EPISODES=${EPISODES:-10}
DET=results/hand_regard/detector/babybench_mittens_detector.json
common=(--steps "$STEPS" --envs 8 --workers 0 --jobs 2 --episodes "$EPISODES" --eval-seed 0
  --set torch_threads=1 --set behavior.detector_file="$DET"
  --set behavior.left_arm_steps="$STAGE" --set behavior.right_arm_steps="$STAGE" --no-report)
! has rewards || .venv/bin/devlearn sweep hand_regard --out "$OUT/rewards" \
  --grid behavior.reward=paper,bilateral --seeds 1,2,3 "${common[@]}"
! has curiosity || .venv/bin/devlearn sweep hand_regard --out "$OUT/curiosity" --seeds 1,2,3 \
  --set behavior.reward=paper --set curiosity=forward_model "${common[@]}"
! has cnn || .venv/bin/devlearn sweep hand_regard --out "$OUT/cnn" --seeds 1,2 \
  --set behavior.reward=paper --set behavior.policy=cnn "${common[@]}"
! has cnn_asym || .venv/bin/devlearn sweep hand_regard --out "$OUT/cnn_asym" --seeds 1,2 \
  --set behavior.reward=paper --set behavior.policy=cnn --set behavior.critic=proprio \
  "${common[@]}"
for policy in zero random held_random; do
  for start in babybench random; do
    dir="$OUT/baseline_${policy}_$start"
    ! has baselines || [ -f "$dir/eval.json" ] || .venv/bin/devlearn eval hand_regard \
      --policy "$policy" --episodes "$EPISODES" --seed 0 --start "$start" \
      --set behavior.detector_file="$DET" --out "$dir" > /dev/null
  done
done
for run in "$OUT"/*/runs/*/; do
  [ -f "$run/eval_random/eval.json" ] || .venv/bin/devlearn eval hand_regard \
    --checkpoint "$run/checkpoint_latest.pt" --episodes "$EPISODES" --seed 0 --start random \
    --out "$run/eval_random" > /dev/null
done
