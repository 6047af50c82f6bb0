#!/usr/bin/env bash
# Idle window: two hand-regard CNN runs side by side (one per core, taskset), old (809f510)
# against new (the commit given), alternating old / new / new / old: the paper's CNN actor with
# the asymmetric critic, the paper's reward, the sides detector, 12,800 steps each (5 iterations
# of 8 envs x 64 decisions x 5 physics steps; steps/s read from metrics.jsonl after the first).
#   bash docs/bench-2026-12-06c/pairs.sh OLD_WORKTREE NEW_WORKTREE OUT
OLD=${1:?usage: pairs.sh OLD_WORKTREE NEW_WORKTREE OUT}
NEW=${2:?}
OUT=${3:?}
mkdir -p "$OUT"
uptime > "$OUT/uptime_before.txt"
DET=results/hand_regard/detector/babybench_mittens_sides_detector.json
pair() {  # pair NAME WORKTREE
  local name=$1 W=$2
  for core in 0 1; do
    ( cd "$W" && rm -rf "/tmp/pair_${name}_$core"
      PYTHONPATH=$W:$W/plugins/self_touch/src:$W/plugins/hand_regard/src:$W/plugins/curiosity/src \
      /usr/bin/time -f "$name core $core wall %e s" taskset -c $core .venv/bin/devlearn run \
        hand_regard --steps 12800 --envs 8 --workers 0 --seed $((core + 1)) \
        --set torch_threads=1 --set behavior.detector_file=$DET --set behavior.policy=cnn \
        --set behavior.critic=proprio --set behavior.reward=paper \
        --out "/tmp/pair_${name}_$core" > /dev/null 2>> "$OUT/wall_times.txt"
      cp "/tmp/pair_${name}_$core/metrics.jsonl" "$OUT/metrics_${name}_$core.jsonl" ) &
  done
  wait
}
for turn in 1 2; do
  if [ $turn = 1 ]; then order="old new"; else order="new old"; fi
  for which in $order; do
    if [ $which = old ]; then W=$OLD; else W=$NEW; fi
    pair "cnn_${which}_$turn" "$W"
  done
done
uptime > "$OUT/uptime_after.txt"
