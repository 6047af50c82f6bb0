#!/usr/bin/env bash
# Publish finished runs of a hand-regard sweep into results/: for each run, the policy file
# (`devlearn slim`: weights, config and detector calibration), its evaluation (written by the
# sweep's `devlearn eval`), config, metrics, calibrated detector, the sweep's record (the code
# commit of every training attempt), and an evaluation from the rest pose (`--start rest`,
# one episode, into eval_rest/). A run's calibrated detector that equals the measured one
# (results/hand_regard/detector/<appearance>_detector.json: babbling seed 0, as every run of
# the sweep) is measured already; any other is measured on the same 2,000 random-start frames
# (`devlearn_hand_regard.measure`, ~75 s) into detector_check.json.
#
#   bash results/hand_regard/publish.sh SWEEP_DIR DEST_DIR [RUN_NAME ...]
#   bash results/hand_regard/publish.sh runs/hand_regard_300k results/hand_regard/i19
#
# Without run names it publishes every run of the sweep whose evaluation is written.
set -euo pipefail
cd "$(dirname "$0")/../.."
sweep=${1:?usage: publish.sh SWEEP_DIR DEST_DIR [RUN_NAME ...]}
dest=${2:?usage: publish.sh SWEEP_DIR DEST_DIR [RUN_NAME ...]}
shift 2
names=("$@")
if [ ${#names[@]} -eq 0 ]; then
  for run in "$sweep"/runs/*/; do
    [ -f "$run/eval/eval.json" ] && names+=("$(basename "$run")")
  done
fi
py=.venv/bin/python
for name in "${names[@]}"; do
  run="$sweep/runs/$name"
  out="$dest/$name"
  [ -f "$run/eval/eval.json" ] || { echo "$run: not evaluated yet (no eval/eval.json)" >&2; exit 2; }
  mkdir -p "$out/eval"
  cp "$run/config.json" "$run/metrics.jsonl" "$run/hand_detector.json" "$out/"
  cp "$run/eval/"* "$out/eval/"
  cp "$sweep/records/$name.json" "$out/sweep_record.json"
  .venv/bin/devlearn slim "$run" --out "$out/policy.pt"
  # the diagnostic from the rest pose (training's start; one episode: the policy is deterministic)
  .venv/bin/devlearn eval hand_regard --checkpoint "$out/policy.pt" --episodes 1 --seed 0 \
    --start rest --out "$out/eval_rest"
  appearance=$("$py" -c "import json,sys; print(json.load(open(sys.argv[1]))['behavior']['appearance'])" "$run/config.json")
  measured=results/hand_regard/detector/${appearance}_detector.json
  if "$py" -c "import json,sys; sys.exit(json.load(open(sys.argv[1])) != json.load(open(sys.argv[2])))" \
    "$run/hand_detector.json" "$measured"; then
    echo "$name: detector identical to $measured (measured in detector/$appearance.json)"
  else
    "$py" -m devlearn_hand_regard.measure --appearance "$appearance" \
      --detector "$run/hand_detector.json" --out "$out/detector_check.json"
  fi
  echo "published $name -> $out"
done
