#!/usr/bin/env bash
# Publish issue #43's finished pilots (pilots43.sh's OUT) into a folder with the same layout, so
# that `table.py pilots` reads either: per run its config, evaluation and training log thinned to
# every 50th iteration plus the last (no policy files: the tree's size budget); the baselines.
# Runs not yet evaluated are skipped, so sessions can publish what they finished.
#   bash results/self_touch/publish_pilots.sh OUT DEST   # e.g. /work/sweeps/pil43 results/self_touch/i43/pilots_2M
set -euo pipefail
USAGE="usage: publish_pilots.sh OUT DEST"
out=${1:?$USAGE}
dest=${2:?$USAGE}
# shellcheck source=results/publish_lib.sh
source "$(dirname "$0")/../publish_lib.sh"
shopt -s nullglob
for run in "$out"/*/seed=*/; do
  run=${run%/}
  name=${run#"$out"/}
  [ -f "$run/eval/eval.json" ] || { echo "$run: not evaluated yet, skipped" >&2; continue; }
  mkdir -p "$dest/$name/eval"
  cp "$run/config.json" "$dest/$name/"
  cp "$run/eval/eval.json" "$dest/$name/eval/"
  thin_log "$run/metrics.jsonl" "$dest/$name/metrics.jsonl" 50
  echo "published $name"
done
copy_baselines "$out" "$dest"
