#!/usr/bin/env bash
# Issue #38's proof: a behaviour the built-ins did not tune for learns with the core defaults
# alone. BEHAVIOR is trained for STEPS physics steps with each seed of SEEDS (devlearn sweep:
# no --set beyond one thread per run), each final policy evaluated with the default protocol
# (a behaviour that declares none: the curriculum stage where the policy trained) and from the
# rest pose (--start rest), and with actions sampled from the policy (--action sample, the
# default start: how the policy acted in training); zero and random baselines under both
# starts. One run at a time
# (JOBS=1: one core; pin the script with taskset), EPISODES (30) episodes per evaluation,
# eval seed 0. A rerun resumes (the sweep continues unfinished runs, written evaluations are
# skipped). From the repository root:
#   bash results/plugins/proof.sh BEHAVIOR OUT SEEDS STEPS   # e.g. hand_to_mouth OUT 1-3 500000
# Layout: OUT/runs/seed=N/ (run; eval/ the default protocol, rest/ from the rest pose,
# sample/ sampled actions),
# OUT/baseline_{zero,random}[_rest]/, OUT/report/ (the sweep's).
set -euo pipefail
USAGE="usage: proof.sh BEHAVIOR OUT SEEDS STEPS"
BEHAVIOR=${1:?$USAGE}
OUT=${2:?$USAGE}
SEEDS=${3:?$USAGE}
STEPS=${4:?$USAGE}
EPISODES=${EPISODES:-30}
JOBS=${JOBS:-1}
DEVLEARN=${DEVLEARN:-.venv/bin/devlearn}

evaluate() {  # evaluate DIR ARGS...: one evaluation (eval seed 0) unless DIR/eval.json exists
  local dir=$1
  shift
  [ -f "$dir/eval.json" ] || "$DEVLEARN" eval "$BEHAVIOR" "$@" --episodes "$EPISODES" --seed 0 \
    --json --out "$dir" > /dev/null
}

"$DEVLEARN" sweep "$BEHAVIOR" --out "$OUT" --seeds "$SEEDS" --steps "$STEPS" --workers 0 \
  --jobs "$JOBS" --episodes "$EPISODES" --eval-seed 0 --set torch_threads=1

shopt -s nullglob
for run in "$OUT"/runs/seed=*/; do
  run=${run%/}
  evaluate "$run/rest" --checkpoint "$run/checkpoint_latest.pt" --start rest
  evaluate "$run/sample" --checkpoint "$run/checkpoint_latest.pt" --action sample
done
for policy in zero random; do
  evaluate "$OUT/baseline_$policy" --policy "$policy"
  evaluate "$OUT/baseline_${policy}_rest" --policy "$policy" --start rest
done
