#!/bin/bash
# Issue #54 item 5: devlearn's default learner and SB3's PPO trained side by side on the same
# env, one per core, and their seconds of learning split into rollouts and updates
# (devlearn: metrics.jsonl's collect_s / update_s; SB3: train.json's collect_s, from its rollout
# callbacks, and the rest of learn()). Run it on an otherwise idle machine, twice with the
# cores swapped:
#
#   experiments/i54_speed_pair.sh 0 1 A && experiments/i54_speed_pair.sh 1 0 B
#
# Args: the core of devlearn's run, the core of SB3's, a tag; STEPS (default 163,840: 32
# iterations of 16 envs x 64 decisions x 5 physics steps); OUT (default /tmp).
set -e
cd "$(dirname "$0")/.."
export MUJOCO_GL=egl
S=${STEPS:-163840}
OUT=${OUT:-/tmp}
PY=${PYTHON:-.venv/bin/python}
mkdir -p "$OUT"
rm -rf "$OUT/pair_ours_$3" "$OUT/pair_sb3_$3"
common=(--seed 6 --workers 0 --set behavior.fixed_pose_steps=4000000)
taskset -c "$1" "$PY" -m devlearn.cli run self_touch --out "$OUT/pair_ours_$3" --steps "$S" \
    "${common[@]}" --set torch_threads=1 > "$OUT/pair_ours_$3.log" 2>&1 &
A=$!
taskset -c "$2" "$PY" examples/sb3/train.py --algo ppo --behavior self_touch --steps "$S" \
    --envs 16 --threads 1 --out "$OUT/pair_sb3_$3" "${common[@]}" > "$OUT/pair_sb3_$3.log" 2>&1 &
B=$!
wait $A $B
"$PY" - "$OUT" "$3" <<'PY'
import json, sys
out, tag = sys.argv[1], sys.argv[2]
rows = [json.loads(line) for line in open(f"{out}/pair_ours_{tag}/metrics.jsonl")]
collect, update = sum(r["collect_s"] for r in rows), sum(r["update_s"] for r in rows)
sb3 = json.load(open(f"{out}/pair_sb3_{tag}/train.json"))
print(
    f"{tag}: devlearn collect {collect:.1f} s, update {update:.1f} s, total {collect + update:.1f} s"
    f" | SB3 collect {sb3['collect_s']:.1f} s, rest {sb3['learn_s'] - sb3['collect_s']:.1f} s,"
    f" total {sb3['learn_s']:.1f} s"
)
PY
