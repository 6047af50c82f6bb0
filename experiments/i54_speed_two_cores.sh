#!/bin/bash
# Issue #54 items 2 and 5 on the machine a user has: devlearn's default learner and SB3's PPO
# each given both cores of an idle 2-core machine, one after the other, alternated ROUNDS times
# (default 2): devlearn with its automatic workers and threads (`devlearn run`'s defaults),
# SB3's PPO through devlearn's Gymnasium vector env with a worker per core (examples/sb3/train.py's
# defaults). The training is the 2M comparison's (self-touch, the fixed-pose stage throughout,
# seed 6) for STEPS physics steps (default 327,680: 64 iterations of 16 envs x 64 decisions x 5).
# Prints, per run, the seconds of learning (devlearn: collect_s + update_s summed over
# metrics.jsonl; SB3: the seconds inside learn()) and physics steps per second of learning.
#
#   experiments/i54_speed_two_cores.sh          # ~5 min on 2 idle cores
#
# Env: STEPS, ROUNDS, OUT (default /tmp/speed2), PYTHON (default .venv/bin/python).
set -e
cd "$(dirname "$0")/.."
export MUJOCO_GL=egl
S=${STEPS:-327680}
OUT=${OUT:-/tmp/speed2}
PY=${PYTHON:-.venv/bin/python}
mkdir -p "$OUT"
common=(--seed 6 --set behavior.fixed_pose_steps=4000000)
for round in $(seq 1 "${ROUNDS:-2}"); do
    for learner in devlearn sb3; do
        dir="$OUT/${learner}_$round"
        rm -rf "$dir"
        if [ "$learner" = devlearn ]; then
            "$PY" -m devlearn.cli run self_touch --out "$dir" --steps "$S" "${common[@]}" \
                > "$dir.log" 2>&1
        else
            "$PY" examples/sb3/train.py --algo ppo --behavior self_touch --steps "$S" --envs 16 \
                --out "$dir" "${common[@]}" > "$dir.log" 2>&1
        fi
        "$PY" - "$dir" "$learner" "$round" <<'PY'
import json, pathlib, sys
run, learner, rnd = pathlib.Path(sys.argv[1]), sys.argv[2], sys.argv[3]
if learner == "devlearn":
    rows = [json.loads(line) for line in (run / "metrics.jsonl").open()]
    seconds = sum(r["collect_s"] + r["update_s"] for r in rows)
    steps = rows[-1]["step"]
else:
    record = json.loads((run / "train.json").read_text())
    seconds, steps = record["learn_s"], record["env_steps"]
print(f"round {rnd} {learner:8s} {steps} steps in {seconds:.1f} s of learning: "
      f"{steps / seconds:,.0f} steps/s", flush=True)
PY
    done
done
