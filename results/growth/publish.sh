#!/usr/bin/env bash
# Publish issue #41's finished runs (experiment.sh's OUT) into DEST with the same layout, so that
# table.py reads either: per run its config, the sweep's record (command, commit, host, wall time
# of every attempt), its training log thinned to every 20th iteration plus the last and its
# evaluations at 6, 12 and 18 months; and the baselines. A run without all three evaluations is
# skipped, so sessions can split the seeds (experiment.sh OUT 1-2, then 3-4, ...) and publish
# what each finished; DEST then gathers them.
#   bash results/growth/publish.sh OUT DEST     # e.g. /work/sweeps/growth results/growth/i41
set -euo pipefail
USAGE="usage: publish.sh OUT DEST"
out=${1:?$USAGE}
dest=${2:?$USAGE}
# shellcheck source=results/publish_lib.sh
source "$(dirname "$0")/../publish_lib.sh"
shopt -s nullglob
for run in "$out"/fixed/runs/*/ "$out"/grow/runs/*/; do
  run=${run%/}
  arm=$(basename "$(dirname "$(dirname "$run")")")
  name=$(basename "$run")
  missing=0
  for age in 6 12 18; do [ -f "$run/at_${age}_months/eval.json" ] || missing=1; done
  if ((missing)); then echo "$run: not evaluated at every age yet, skipped" >&2; continue; fi
  to=$dest/$arm/runs/$name
  mkdir -p "$to"
  cp "$run/config.json" "$to/"
  # the sweep's record without its copy of the own-age evaluation (at_AGE_months has it)
  [ ! -f "$out/$arm/records/$name.json" ] || python3 -c 'import json, sys
record = json.load(open(sys.argv[1]))
record.pop("eval", None)
json.dump(record, open(sys.argv[2], "w"), separators=(",", ":"))' \
    "$out/$arm/records/$name.json" "$to/sweep_record.json"
  thin_log "$run/metrics.jsonl" "$to/metrics.jsonl" 20
  for age in 6 12 18; do  # every field, written without indentation (a third of the bytes)
    mkdir -p "$to/at_${age}_months"
    python3 -m json.tool --compact "$run/at_${age}_months/eval.json" > "$to/at_${age}_months/eval.json"
  done
  echo "published $arm/$name"
done
copy_baselines "$out" "$dest"
