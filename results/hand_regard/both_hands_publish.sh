#!/usr/bin/env bash
# Publish issue #39 item 4's runs (both_hands.sh's OUT) into DEST, named as table.py reads them
# (arm paper: reward=paper,seed=N; bilateral: reward=bilateral,seed=N; reach, the pilots'
# temperature-4 arm: reward=reach_t4,seed=N; cnn: policy=cnn,seed=N): per run its config, the
# sweep's record (command, commit, host, wall time of every attempt), its training log thinned to
# every 10th iteration plus the last, and its evaluations (eval/ from BabyBench's start,
# eval_random/ from random starts); the baselines; and for each RUN named (e.g. each arm's median
# seed) its policy file (`devlearn slim`: weights, config and the detector) and a video of one
# evaluation episode from BabyBench's start. A run not yet evaluated is skipped, so seeds can be
# published as sessions finish them.
#   bash results/hand_regard/both_hands_publish.sh OUT DEST [RUN ...]
#   bash results/hand_regard/both_hands_publish.sh /work/sweeps/hr39 results/hand_regard/i39 'reward=paper,seed=3'
#   (RUN: a published name, as above)
set -euo pipefail
USAGE="usage: both_hands_publish.sh OUT DEST [RUN ...]"
out=${1:?$USAGE}
dest=${2:?$USAGE}
shift 2
DEVLEARN=${DEVLEARN:-.venv/bin/devlearn}
# shellcheck source=results/publish_lib.sh
source "$(dirname "$0")/../publish_lib.sh"
shopt -s nullglob
published_name() {  # published_name RUN: the name table.py reads for a both_hands.sh run
  local arm
  arm=$(basename "$(dirname "$(dirname "$1")")")
  case $arm in
    reach) echo "reward=reach_t4,$(basename "$1")" ;;
    cnn) echo "policy=cnn,$(basename "$1")" ;;
    *) echo "reward=$arm,$(basename "$1")" ;;
  esac
}
for run in "$out"/*/runs/*/; do
  run=${run%/}
  arm=$(basename "$(dirname "$(dirname "$run")")")
  name=$(published_name "$run")
  [ -f "$run/eval/eval.json" ] || { echo "$run: not evaluated yet, skipped" >&2; continue; }
  to=$dest/$name
  mkdir -p "$to/eval"
  cp "$run/config.json" "$to/"
  cp "$run/eval/eval.json" "$to/eval/"
  if [ -f "$run/eval_random/eval.json" ]; then
    mkdir -p "$to/eval_random" && cp "$run/eval_random/eval.json" "$to/eval_random/"
  fi
  record=$out/$arm/records/$(basename "$run").json
  [ ! -f "$record" ] || cp "$record" "$to/sweep_record.json"
  thin_log "$run/metrics.jsonl" "$to/metrics.jsonl" 10
  echo "published $name"
done
copy_baselines "$out" "$dest"
for name in "$@"; do  # e.g. reward=paper,seed=N
  run=$(run_named "$out" published_name "$name")
  "$DEVLEARN" slim "$run" --out "$dest/$name/policy.pt"
  "$DEVLEARN" eval hand_regard --checkpoint "$dest/$name/policy.pt" --episodes 1 --seed 0 \
    --video "$dest/$name/episode.mp4" --out "$(mktemp -d)" > /dev/null
  echo "published $name with its policy and a video"
done
