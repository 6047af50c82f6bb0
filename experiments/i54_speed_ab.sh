#!/bin/bash
# Issue #54 item 5's alternated speed checks (results/learners/README.md, "Speed on two idle
# cores"), on an otherwise idle machine:
#   env      self-touch, 16 envs in this process (DevVecEnv, a decision every 5 physics steps),
#            physics steps per CPU second, best of 3 x 60 decisions, for the code in each of
#            the worktrees given (e.g. before and after deferred observations: 2814e9c, 98a8489)
#   omp      `devlearn run self_touch --seed 1 --steps 153600` (automatic workers and threads)
#            with OMP_WAIT_POLICY=PASSIVE (devlearn's setting before 38d7dce) and without,
#            alternated twice: training steps/s, update and rollout seconds per iteration
#   update   one self-touch PPO update (16 envs x 64 decisions) 8 times on 2 threads, devlearn
#            imported before torch, passive and default waits
#
#   experiments/i54_speed_ab.sh env WORKTREE_A WORKTREE_B
#   experiments/i54_speed_ab.sh omp
#   experiments/i54_speed_ab.sh update
set -e
cd "$(dirname "$0")/.."
export MUJOCO_GL=egl
PY=${PYTHON:-$PWD/.venv/bin/python}
paths() { echo "$1:$1/plugins/self_touch/src:$1/plugins/hand_regard/src:$1/plugins/curiosity/src:$1/examples/hand_to_mouth/src"; }
case "$1" in
env)
  for rep in 1 2; do for W in "$2" "$3"; do
    (cd "$W" && PYTHONPATH=$(paths "$W") "$PY" - <<'PY'
import time, torch
from devlearn.env import DevVecEnv
from devlearn.plugins import PluginRegistry
env = DevVecEnv(PluginRegistry().create("self_touch", None), num_envs=16, seed=0, workers=0,
                action_repeat=5)
gen = torch.Generator().manual_seed(0)
for _ in range(10):
    env.step(torch.rand(16, env.num_actions, generator=gen) * 2 - 1)
best = 1e9
for _ in range(3):
    t = time.process_time()
    for _ in range(60):
        env.step(torch.rand(16, env.num_actions, generator=gen) * 2 - 1)
    best = min(best, time.process_time() - t)
import os
print(f"{os.getcwd()}: {60 * 16 * 5 / best:.0f} physics steps per CPU second")
env.close()
PY
    ); done; done ;;
omp)
  OUT=$(mktemp -d)
  for rep in 1 2; do for POL in PASSIVE default; do
    rm -rf "$OUT/run"
    if [ $POL = PASSIVE ]; then export OMP_WAIT_POLICY=PASSIVE; else unset OMP_WAIT_POLICY; fi
    "$PY" -m devlearn.cli run self_touch --seed 1 --steps 153600 --out "$OUT/run" > /dev/null 2>&1
    unset OMP_WAIT_POLICY
    "$PY" - "$OUT/run/metrics.jsonl" $POL <<'PY'
import json, sys
from devlearn.bench.speed import training_rate
rows = [json.loads(line) for line in open(sys.argv[1])]
r = rows[1:]
print(f"{sys.argv[2]}: {training_rate(rows):.0f} steps/s, update {sum(x['update_s'] for x in r) / len(r):.3f} s,"
      f" rollout {sum(x['collect_s'] for x in r) / len(r):.3f} s, update threads {sorted({x['update_threads'] for x in r})}")
PY
  done; done ;;
update)
  for POL in PASSIVE default; do
    if [ $POL = PASSIVE ]; then export OMP_WAIT_POLICY=PASSIVE; else unset OMP_WAIT_POLICY; fi
    "$PY" - $POL <<'PY'
import sys, time
import devlearn  # before torch, as devlearn run imports it
import torch
from devlearn.bench.learner import build_learner, collect_random
from devlearn.plugins import PluginRegistry
reg = PluginRegistry()
alg, obs = build_learner(reg.create("self_touch", None), "separate", 16, 64, registry=reg)
times = []
for _ in range(8):
    torch.set_num_threads(1)
    collect_random(alg, obs, 64)
    torch.set_num_threads(2)
    t = time.perf_counter(); alg.update(); times.append(time.perf_counter() - t)
print(sys.argv[1], "2-thread update s:", [round(x, 3) for x in times])
PY
  done ;;
*) echo "usage: $0 env WORKTREE_A WORKTREE_B | omp | update" >&2; exit 2 ;;
esac
