#!/usr/bin/env bash
# Publish issue #29's experiment (results/hand_regard/experiment.sh's OUT folder) into
# results/hand_regard/i29/: per run its evaluations (eval/ from BabyBench's start, eval_random/
# from random starts), config, training metrics and the sweep's record (the code commit of every attempt); the
# baselines; and, for the runs named, the policy file (`devlearn slim`: weights, config and the
# detector) and a video of one evaluation episode from BabyBench's start.
#
# DEST (default results/hand_regard/i29) publishes elsewhere: issue #40's pilot (the cnn_asym
# arm, published as policy=cnn,critic=proprio,seed=N) went to results/hand_regard/i40_pilot.
# Training logs are thinned to every 5th iteration plus the last.
#
#   bash results/hand_regard/publish.sh OUT [RUN_NAME ...]
#   bash results/hand_regard/publish.sh /work/sweeps/hr29 'reward=paper,seed=2' 'policy=cnn,seed=1' ...
#   DEST=results/hand_regard/i40_pilot bash results/hand_regard/publish.sh /work/sweeps/hr40p
set -euo pipefail
cd "$(dirname "$0")/../.."
# shellcheck source=results/publish_lib.sh
source results/publish_lib.sh
sweep=${1:?usage: publish.sh OUT [RUN_NAME ...]}
shift
dest=${DEST:-results/hand_regard/i29}
mkdir -p "$dest"
published_name() {  # published_name RUN: its name in DEST (the sweep's runs are named seed=N)
  local arm
  arm=$(basename "$(dirname "$(dirname "$1")")")
  case $arm in
    curiosity) echo "curiosity=forward_model,$(basename "$1")" ;;
    cnn) echo "policy=cnn,$(basename "$1")" ;;
    cnn_asym) echo "policy=cnn,critic=proprio,$(basename "$1")" ;;
    *) basename "$1" ;;
  esac
}
for run in "$sweep"/*/runs/*/; do
  [ -d "$run" ] || continue
  run=${run%/}
  name=$(basename "$run")
  [ -f "$run/eval/eval.json" ] || { echo "$run: not evaluated yet, skipped" >&2; continue; }
  out="$dest/$(published_name "$run")"
  mkdir -p "$out/eval"
  cp "$run/config.json" "$out/"
  thin_log "$run/metrics.jsonl" "$out/metrics.jsonl" 5
  cp "$run/eval/eval.json" "$out/eval/"
  if [ -f "$run/eval_random/eval.json" ]; then
    mkdir -p "$out/eval_random" && cp "$run/eval_random/eval.json" "$out/eval_random/"
  fi
  cp "$(dirname "$(dirname "$run")")/records/$name.json" "$out/sweep_record.json"
done
copy_baselines "$sweep" "$dest"
for name in "$@"; do  # as published: reward=paper,seed=2, curiosity=forward_model,seed=1, policy=cnn,seed=1
  run=$(run_named "$sweep" published_name "$name")
  .venv/bin/devlearn slim "$run" --out "$dest/$name/policy.pt"
  .venv/bin/devlearn eval hand_regard --checkpoint "$dest/$name/policy.pt" --episodes 1 \
    --seed 0 --video "$dest/$name/episode.mp4" --out "$(mktemp -d)" > /dev/null
  echo "published $name with its policy and a video"
done
