#!/usr/bin/env bash
# Issue #39 item 4: hand regard at the paper's budget, the paper's reward (the control) beside
# both-hands arms, with the detector that tells the hands apart by posture
# (detector/babybench_mittens_sides_detector.json, the visibility model of issue #39).
#
# The defaults of the commit it runs on (the proprioception + detector policy, BabyBench's scene
# and start), the paper's curriculum: 175,000 steps left arm + 175,000 right arm + the rest both
# arms, 1,850,000 physics steps in all (723 iterations of 8 envs x 64 decisions x 5 steps:
# 1,850,880). Arms (ARMS, any of):
#   paper      the paper's reward (hand count, motion, living penalty);
#   bilateral  + our bilateral_balance term;
#   reach      + bilateral_balance + reach_into_view at weight 2, temperature 4 (the
#              posture-predicted visibility of the hand less likely in view, its log-odds
#              flattened 4x, up to 0.5 a step): the pilots' best both-hands arm (i39_pilot/);
#   cnn        the paper's reward with the paper's policy network (each eye's image through the
#              paper's CNN, `behavior.policy=cnn`) and the critic of the commit's default
#              (issue #40's proof: the CNN arm at the paper's budget; not in the default ARMS).
# One sweep per arm, the arms side by side, one run per core (JOBS runs at a time per arm:
# JOBS=2 for a single arm on two cores); each sweep
# trains its seeds in turn and evaluates each on 10 episodes from BabyBench's start (eval/), then
# from random starts (eval_random/); the zero, random and held-random baselines under the same
# detector and protocols. Restartable: a rerun resumes every sweep (an interrupted run continues
# from its latest checkpoint) and skips finished evaluations.
#   bash results/hand_regard/both_hands.sh OUT [SEEDS] [STEPS]      # e.g. /work/sweeps/hr39 1-5
#   bash results/hand_regard/both_hands_publish.sh OUT DEST [RUN ...] # then the table
set -euo pipefail
OUT=${1:?usage: both_hands.sh OUT [SEEDS] [STEPS]}
SEEDS=${2:-1-5}
STEPS=${3:-1850000}
STAGE=${STAGE:-175000}
ARMS=${ARMS:-paper reach}
EPISODES=${EPISODES:-10}
ENVS=${ENVS:-8}
JOBS=${JOBS:-1}
DEVLEARN=${DEVLEARN:-.venv/bin/devlearn}
DET=results/hand_regard/detector/babybench_mittens_sides_detector.json

settings() {  # settings ARM: the arm's --set options
  case $1 in
    paper) echo "--set behavior.reward=paper" ;;
    bilateral) echo "--set behavior.reward=bilateral" ;;
    reach) echo "--set behavior.reward=bilateral --set behavior.rewards.reach_into_view.weight=2 --set behavior.rewards.reach_into_view.params.temperature=4" ;;
    cnn) echo "--set behavior.reward=paper --set behavior.policy=cnn" ;;
    *) echo "unknown arm '$1'; valid: paper bilateral reach cnn" >&2; return 2 ;;
  esac
}

arm() {  # arm NAME: one sweep, its runs in turn, then their random-start evaluations
  local extra
  extra=$(settings "$1")
  # shellcheck disable=SC2086  # extra is a list of options
  "$DEVLEARN" sweep hand_regard --out "$OUT/$1" --seeds "$SEEDS" --steps "$STEPS" \
    --envs "$ENVS" --workers 0 --jobs "$JOBS" --episodes "$EPISODES" --eval-seed 0 --no-report \
    --set torch_threads=1 --set behavior.detector_file="$DET" \
    --set behavior.left_arm_steps="$STAGE" --set behavior.right_arm_steps="$STAGE" $extra
  for run in "$OUT/$1"/runs/*/; do
    [ -f "$run/eval_random/eval.json" ] || "$DEVLEARN" eval hand_regard \
      --checkpoint "$run/checkpoint_latest.pt" --episodes "$EPISODES" --seed 0 --start random \
      --out "$run/eval_random" > /dev/null
  done
}

for name in $ARMS; do settings "$name" > /dev/null; done  # every arm known before any starts
mkdir -p "$OUT"
pids=()
for name in $ARMS; do
  arm "$name" > "$OUT/$name.log" 2>&1 &
  pids+=($!)
done
status=0
for pid in "${pids[@]}"; do wait "$pid" || status=1; done
for policy in zero random held_random; do
  for start in babybench random; do
    dir="$OUT/baseline_${policy}_$start"
    [ -f "$dir/eval.json" ] || "$DEVLEARN" eval hand_regard --policy "$policy" \
      --episodes "$EPISODES" --seed 0 --start "$start" --set behavior.detector_file="$DET" \
      --out "$dir" > /dev/null
  done
done
exit "$status"
