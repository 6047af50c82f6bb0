#!/usr/bin/env bash
# Issue #40 item 4 on an idle machine: `devlearn eval` of a trained self-touch policy, 100 episodes,
# the code before issue #40 (OLD, dc6b586^ = 491c9a3: one env, episodes in order) against NEW
# (this commit: automatic envs and workers; and --envs 1 --workers 0, one env in order), two
# alternating turns, wall time by /usr/bin/time. Each code in its own git worktree.
#   bash docs/bench-2026-12-06d/eval_old_new.sh OLD_TREE NEW_TREE OUT
set -euo pipefail
old=${1:?usage: eval_old_new.sh OLD_TREE NEW_TREE OUT}
new=${2:?usage: eval_old_new.sh OLD_TREE NEW_TREE OUT}
out=${3:?usage: eval_old_new.sh OLD_TREE NEW_TREE OUT}
EPISODES=${EPISODES:-100}
POLICY=results/self_touch/i30/curriculum/runs/seed=4/policy.pt
mkdir -p "$out"
timed() {  # timed TREE LABEL [eval options]: one evaluation, its wall and CPU seconds appended
  local tree=$1 label=$2
  shift 2
  local pp="$tree:$tree/plugins/self_touch/src:$tree/plugins/hand_regard/src:$tree/plugins/curiosity/src:$tree/examples/hand_to_mouth/src"
  (cd "$tree" && PYTHONPATH=$pp /usr/bin/time -f "$label wall_s=%e user_s=%U sys_s=%S" -a -o "$out/times.txt" \
    /work/main/.venv/bin/python -m devlearn.cli eval self_touch --checkpoint "$tree/$POLICY" \
    --episodes "$EPISODES" --seed 0 --out "$out/$label" "$@" > /dev/null 2>&1)
}
for turn in 1 2; do
  timed "$old" "old_t$turn"
  timed "$new" "new_auto_t$turn"
  timed "$new" "new_one_env_t$turn" --envs 1 --workers 0
done
cat "$out/times.txt"
