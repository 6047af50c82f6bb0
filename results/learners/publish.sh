#!/usr/bin/env bash
# Publish issue #45's comparison (experiment.sh's OUT) into DEST with the layout table.py reads:
# per run its evaluation (eval/eval.json) and its steps and seconds of learning (train.json:
# SB3's own; for devlearn's runs written here from the full metrics.jsonl, which is kept
# thinned to every 10th iteration plus the last, with the run's config); the baselines. No
# policy files (2.3-2.7 MB each; experiment.sh remakes them).
#   bash results/learners/publish.sh OUT DEST    # e.g. /work/sweeps/learners results/learners/i45
set -euo pipefail
USAGE="usage: publish.sh OUT DEST"
out=${1:?$USAGE}
dest=${2:?$USAGE}
PYTHON=${PYTHON:-.venv/bin/python}
# shellcheck source=results/publish_lib.sh
source "$(dirname "$0")/../publish_lib.sh"
shopt -s nullglob
for run in "$out"/devlearn_ppo/seed=*/ "$out"/sb3_ppo/seed=*/ "$out"/sb3_sac/seed=*/; do
  run=${run%/}
  name=${run#"$out"/}
  [ -f "$run/eval/eval.json" ] || { echo "$run: not evaluated yet, skipped" >&2; continue; }
  mkdir -p "$dest/$name/eval"
  cp "$run/eval/eval.json" "$dest/$name/eval/"
  if [ -f "$run/train.json" ]; then
    cp "$run/train.json" "$dest/$name/"
  else
    cp "$run/config.json" "$dest/$name/"
    "$PYTHON" - "$run/metrics.jsonl" "$dest/$name/train.json" <<'PY'
import json, sys
rows = [json.loads(line) for line in open(sys.argv[1])]
learn = sum(r["collect_s"] + r["update_s"] for r in rows)
summary = {"learner": "devlearn_ppo", "env_steps": rows[-1]["step"], "learn_s": learn,
           "iterations": len(rows), "source": "metrics.jsonl: collect_s + update_s of every row"}
open(sys.argv[2], "w").write(json.dumps(summary, indent=2) + "\n")
PY
    thin_log "$run/metrics.jsonl" "$dest/$name/metrics.jsonl" 10
  fi
  echo "published $name"
done
copy_baselines "$out" "$dest"
