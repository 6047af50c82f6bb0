#!/usr/bin/env bash
# Copy what issue #38's proof (results/plugins/proof.sh) produced in OUT into DEST, for git:
# every seed's config, metrics and evaluations (default protocol, rest pose, sampled actions), the
# baselines'
# evaluations and the sweep's report; the policy file (devlearn slim: weights, config) of the
# seed named MEDIAN. From the repository root:
#   bash results/plugins/publish.sh OUT DEST [MEDIAN]
set -euo pipefail
OUT=${1:?usage: publish.sh OUT DEST [MEDIAN]}
DEST=${2:?usage: publish.sh OUT DEST [MEDIAN]}
MEDIAN=${3:-}
DEVLEARN=${DEVLEARN:-.venv/bin/devlearn}
mkdir -p "$DEST"
for run in "$OUT"/runs/seed=*/; do
  run=${run%/}
  to="$DEST/runs/$(basename "$run")"
  mkdir -p "$to"
  cp "$run/config.json" "$run/metrics.jsonl" "$to/"
  for protocol in eval rest sample; do
    mkdir -p "$to/$protocol"
    cp "$run/$protocol/eval.json" "$to/$protocol/"
  done
done
for base in "$OUT"/baseline_*/; do
  base=${base%/}
  mkdir -p "$DEST/$(basename "$base")"
  cp "$base/eval.json" "$DEST/$(basename "$base")/"
done
mkdir -p "$DEST/report"
cp "$OUT/report/report.md" "$DEST/report/"
if [ -n "$MEDIAN" ]; then
  "$DEVLEARN" slim "$OUT/runs/seed=$MEDIAN/checkpoint_latest.pt" \
    --out "$DEST/runs/seed=$MEDIAN/policy.pt" > /dev/null
fi
