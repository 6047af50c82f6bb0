#!/usr/bin/env bash
# Idle window: two hand-regard runs side by side (one per core, taskset), old (d045db0) against
# new (d2def3e), alternating: the proprioception policy in the both-arms stage with the sides
# detector, and the CNN actor with the asymmetric critic; then the full suite on main.
cd /work/sweeps
while pgrep -f "devlearn (run|sweep|eval)" > /dev/null || pgrep -f "experiment.sh|pil39r2.sh|pil39t.sh|pytest" > /dev/null; do sleep 15; done
echo "$(date +%T) idle4 starts" >> sched.log
mkdir -p idle4
uptime > idle4/uptime_before.txt
DET=results/hand_regard/detector/babybench_mittens_sides_detector.json
pair() {  # pair NAME WORKTREE STEPS SETTINGS...
  local name=$1 W=$2 steps=$3
  shift 3
  for core in 0 1; do
    ( cd $W; rm -rf /tmp/pair_${name}_$core
      PYTHONPATH=$W:$W/plugins/self_touch/src:$W/plugins/hand_regard/src:$W/plugins/curiosity/src \
      /usr/bin/time -f "$name core $core wall %e s" taskset -c $core .venv/bin/devlearn run hand_regard --steps $steps --envs 8 --workers 0 --seed $((core+1)) \
        --set torch_threads=1 --set behavior.detector_file=$DET "$@" --out /tmp/pair_${name}_$core > /dev/null 2>> /work/sweeps/idle4/pairs_time.txt
      cp /tmp/pair_${name}_$core/metrics.jsonl /work/sweeps/idle4/metrics_${name}_$core.jsonl ) &
  done
  wait
}
PROPRIO=(--set behavior.left_arm_steps=0 --set behavior.right_arm_steps=0)
CNN=(--set behavior.policy=cnn --set behavior.critic=proprio --set behavior.reward=paper)
for turn in 1 2; do
  if [ $turn = 1 ]; then order="old new"; else order="new old"; fi
  for which in $order; do
    if [ $which = old ]; then W=/work/wt41; else W=/work/wtbench; fi
    pair proprio_${which}_$turn $W 12800 "${PROPRIO[@]}"
    pair cnn_${which}_$turn $W 7680 "${CNN[@]}"
  done
done
echo "$(date +%T) idle4 pairs done" >> /work/sweeps/sched.log
