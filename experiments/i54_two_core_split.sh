#!/bin/bash
# Issue #54 item 5: where the default run's time goes on two cores. The default run (`devlearn
# run self_touch`'s automatic workers and threads: 16 envs over 2 worker processes, the policy
# and the update in the training process) beside the same training on one core (`taskset -c 1`,
# `--workers 0 --set torch_threads=1`), STEPS physics steps each (default 163,840: 32
# iterations), seed 1, one after the other. Prints each one's seconds per iteration collecting
# the rollout and updating (every iteration after the first two: the first's start-up and the
# thread plan's first probe), and physics steps per second of learning.
#
#   experiments/i54_two_core_split.sh          # ~3 min on 2 idle cores
#
# Env: STEPS, OUT (default /tmp/two_core_split), PYTHON (default .venv/bin/python).
set -e
cd "$(dirname "$0")/.."
export MUJOCO_GL=egl
S=${STEPS:-163840}
OUT=${OUT:-/tmp/two_core_split}
PY=${PYTHON:-.venv/bin/python}
mkdir -p "$OUT"
rm -rf "$OUT/two_cores" "$OUT/one_core"
"$PY" -m devlearn.cli run self_touch --steps "$S" --seed 1 --out "$OUT/two_cores" > "$OUT/two_cores.log" 2>&1
taskset -c 1 "$PY" -m devlearn.cli run self_touch --steps "$S" --seed 1 --workers 0 \
    --set torch_threads=1 --out "$OUT/one_core" > "$OUT/one_core.log" 2>&1
"$PY" - "$OUT" <<'PY'
import json, pathlib, sys
from devlearn.bench.speed import training_rate
out = pathlib.Path(sys.argv[1])
for name in ("two_cores", "one_core"):
    rows = [json.loads(line) for line in (out / name / "metrics.jsonl").open()][1:]
    kept = rows[1:]  # training_rate(rows) counts these: the steps of each over its seconds
    collect = sum(r["collect_s"] for r in kept) / len(kept)
    update = sum(r["update_s"] for r in kept) / len(kept)
    print(f"{name:9s} {len(kept)} iterations: collect {collect:.3f} s, update {update:.3f} s "
          f"per iteration; {training_rate(rows):,.0f} steps/s of learning")
PY
