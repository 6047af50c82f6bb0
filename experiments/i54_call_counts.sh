#!/bin/bash
# Issue #54 item 5: Python function calls per policy decision in devlearn's rollouts+updates and
# in SB3's PPO, training self-touch on the same env (16 envs, one core each, the speed pair's
# settings). Calls are counted by cProfile, which does not depend on the machine's load (its
# times do: they are not reported). Each learner trains twice, 2 and 6 iterations (10,240 and
# 30,720 physics steps); the difference cancels start-up, leaving 4 iterations' calls, divided
# by the 256 decisions per env they hold.
#
#   experiments/i54_call_counts.sh [OUT]      # ~3 min on an idle core, longer beside other work
set -e
cd "$(dirname "$0")/.."
export MUJOCO_GL=egl
OUT=${1:-/tmp/i54_call_counts}
PY=${PYTHON:-.venv/bin/python}
mkdir -p "$OUT"
common=(--seed 6 --workers 0 --set behavior.fixed_pose_steps=4000000)
for S in 10240 30720; do
  rm -rf "$OUT/ours_$S" "$OUT/sb3_$S"
  "$PY" -m cProfile -o "$OUT/ours_$S.prof" -m devlearn.cli run self_touch --out "$OUT/ours_$S" \
      --steps $S "${common[@]}" --set torch_threads=1 > "$OUT/ours_$S.log" 2>&1
  "$PY" -m cProfile -o "$OUT/sb3_$S.prof" examples/sb3/train.py --algo ppo --behavior self_touch \
      --steps $S --envs 16 --threads 1 --out "$OUT/sb3_$S" "${common[@]}" > "$OUT/sb3_$S.log" 2>&1
done
"$PY" - "$OUT" <<'PY'
import pstats, sys
out = sys.argv[1]
decisions = (30720 - 10240) // 5 // 16
def calls(name, steps):
    st = pstats.Stats(f"{out}/{name}_{steps}.prof")
    per = {f"{k[0].split('site-packages/')[-1]}:{k[1]}:{k[2]}": v[1] for k, v in st.stats.items()}
    return per, st.total_calls
for name, label in (("ours", "devlearn"), ("sb3", "SB3 PPO")):
    a, ta = calls(name, 10240)
    b, tb = calls(name, 30720)
    print(f"{label}: {(tb - ta) / decisions:.0f} Python calls per decision (16 envs)")
    diff = sorted(((b.get(k, 0) - a.get(k, 0)) / decisions, k) for k in set(a) | set(b))
    for v, k in diff[-8:][::-1]:
        print(f"  {v:8.1f}  {k}")
PY
