#!/usr/bin/env bash
# Publish finished self-touch runs of curriculum.sh or ablation.sh (their OUT folder) into a
# folder under results/self_touch/ with the same layout, so that table.py reads either:
# per run its evaluations (eval/, rest/, at_STEP/), config, the sweep's record (command, code
# commit, wall time of every attempt) and its training log thinned to every 10th iteration plus
# the last (the training score is the last row's); the baselines; and, for the runs named,
# the policy file (`devlearn slim`: weights and config). Runs already published are refreshed;
# runs not yet evaluated are skipped, so sessions can publish what they finished.
#
#   bash results/self_touch/publish.sh OUT DEST [RUN_NAME ...]
#   bash results/self_touch/publish.sh /work/sweeps/abl30 results/self_touch/i30/ablation \
#       'curriculum=two_stage,seed=1'
set -euo pipefail
cd "$(dirname "$0")/../.."
USAGE="usage: publish.sh OUT DEST [RUN_NAME ...]"
out=${1:?$USAGE}
dest=${2:?$USAGE}
shift 2
shopt -s nullglob
for run in "$out"/runs/*/; do
  run=${run%/}
  name=$(basename "$run")
  [ -f "$run/eval/eval.json" ] || { echo "$run: not evaluated yet, skipped" >&2; continue; }
  mkdir -p "$dest/runs/$name"
  cp "$run/config.json" "$dest/runs/$name/"
  cp "$out/records/$name.json" "$dest/runs/$name/sweep_record.json"
  awk -v last="$(wc -l < "$run/metrics.jsonl")" 'NR % 10 == 0 || NR == last' \
    "$run/metrics.jsonl" > "$dest/runs/$name/metrics.jsonl"
  for evaluation in "$run"/eval "$run"/rest "$run"/at_*; do
    [ -f "$evaluation/eval.json" ] || continue
    mkdir -p "$dest/runs/$name/$(basename "$evaluation")"
    cp "$evaluation/eval.json" "$dest/runs/$name/$(basename "$evaluation")/"
  done
  echo "published $name"
done
for base in "$out"/baseline_*/; do
  mkdir -p "$dest/$(basename "$base")"
  cp "$base/eval.json" "$dest/$(basename "$base")/"
done
for name in "$@"; do
  .venv/bin/devlearn slim "$out/runs/$name" --out "$dest/runs/$name/policy.pt"
  echo "published $name's policy file"
done
