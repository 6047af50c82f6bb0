#!/usr/bin/env bash
# Issue #40 item 4 on an idle machine: `devlearn eval` of a trained self-touch policy, 100 episodes,
# the code before issue #40 (OLD, dc6b586^ = 491c9a3: one env, episodes in order) against NEW
# (this commit: automatic envs and workers; and --envs 1 --workers 0, one env in order), two
# alternating turns, wall time by /usr/bin/time. Each code in its own git worktree.
#   bash docs/bench-2026-12-06d/eval_old_new.sh OLD_TREE NEW_TREE OUT
# PYTHON (default: this checkout's .venv/bin/python) runs both codes: the same packages for both.
set -euo pipefail
old=${1:?usage: eval_old_new.sh OLD_TREE NEW_TREE OUT}
new=${2:?usage: eval_old_new.sh OLD_TREE NEW_TREE OUT}
out=${3:?usage: eval_old_new.sh OLD_TREE NEW_TREE OUT}
EPISODES=${EPISODES:-100}
PYTHON=${PYTHON:-$(cd "$(dirname "$0")/../.." && pwd)/.venv/bin/python}
POLICY=results/self_touch/i30/curriculum/runs/seed=4/policy.pt
mkdir -p "$out"
timed() {  # timed TREE LABEL [eval options]: one evaluation, its wall and CPU seconds appended
  local tree=$1 label=$2
  shift 2
  local pp="$tree:$tree/plugins/self_touch/src:$tree/plugins/hand_regard/src:$tree/plugins/curiosity/src:$tree/examples/hand_to_mouth/src"
  (cd "$tree" && PYTHONPATH=$pp /usr/bin/time -f "$label wall_s=%e user_s=%U sys_s=%S" -a -o "$out/times.txt" \
    "$PYTHON" -m devlearn.cli eval self_touch --checkpoint "$tree/$POLICY" \
    --episodes "$EPISODES" --seed 0 --out "$out/$label" "$@" > /dev/null 2>&1)
}
for turn in 1 2; do
  timed "$old" "old_t$turn"
  timed "$new" "new_auto_t$turn"
  timed "$new" "new_one_env_t$turn" --envs 1 --workers 0
done
cat "$out/times.txt"
# the results: every eval.json against the old code's first, less what names the code, the file,
# the age (recorded since issue #41) and the execution (envs, workers, wall seconds)
"$PYTHON" - "$out" <<'PY'
import json, sys
from pathlib import Path

def measured(path):
    d = json.loads(path.read_text())
    for key in ("checkpoint", "age_months", "execution"):
        d.pop(key, None)
    d["protocol"].pop("code", None)
    d["protocol"].pop("age_months", None)
    return d

out = Path(sys.argv[1])
ref = measured(out / "old_t1" / "eval.json")
for path in sorted(out.glob("*/eval.json")):
    print(path.parent.name, "identical to old_t1" if measured(path) == ref else "DIFFERS from old_t1")
PY
