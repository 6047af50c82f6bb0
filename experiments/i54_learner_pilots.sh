#!/usr/bin/env bash
# Issue #54's pilots: one difference at a time between devlearn's PPO and SB3's, on self-touch.
# Each arm x seed is trained with one torch thread, in process (--workers 0), then evaluated
# under one protocol (self-touch's default: random starts, EPISODES episodes, eval seed 0) with
# the mean action and with sampled actions. Restartable: a finished step is skipped.
#   bash experiments/i54_learner_pilots.sh OUT LANE LANES [ARM...]
# runs the jobs i with i % LANES == LANE (one lane per core, pinned by the caller with taskset).
set -euo pipefail
OUT=$1; LANE=$2; LANES=$3; shift 3
STEPS=${STEPS:-512000}
EPISODES=${EPISODES:-50}
SEEDS=${SEEDS:-"1 2 3 4 5"}
HERE=$(cd "$(dirname "$0")/.." && pwd)
DEVLEARN=${DEVLEARN:-$HERE/.venv/bin/devlearn}
PY=${PY:-$HERE/.venv/bin/python}
declare -A ARM=(
  [default]=""
  [sb3like]="network.encoders=flat network.activation=tanh network.init=orthogonal network.head=free network.init_std=1.0 ppo.adam_eps=1e-5 ppo.normalize_advantage_per_mini_batch=true"
  [free]="network.head=free network.init_std=1.0"
  [free05]="network.head=free"
  [flat]="network.encoders=flat"
  [tanh]="network.activation=tanh"
  [ortho]="network.init=orthogonal"
  [adam]="ppo.adam_eps=1e-5 ppo.normalize_advantage_per_mini_batch=true"
  [squashed]="network.head=squashed"
  [normall]="network.normalize=all"
  [gclip]="ppo.max_grad_norm=0.5"
  [std02]="network.init_std=0.2"
  [std01]="network.init_std=0.1"
  [final]="network.final_std=0.1"
  [free_final]="network.head=free network.init_std=1.0 network.final_std=0.1"
  [sb3like_final]="network.encoders=flat network.activation=tanh network.init=orthogonal network.head=free network.init_std=1.0 ppo.adam_eps=1e-5 ppo.normalize_advantage_per_mini_batch=true network.final_std=0.1"
  [free_ent0]="network.head=free network.init_std=1.0 ppo.entropy_coef=0"
  [sb3like_ent0]="network.encoders=flat network.activation=tanh network.init=orthogonal network.head=free network.init_std=1.0 ppo.adam_eps=1e-5 ppo.normalize_advantage_per_mini_batch=true ppo.entropy_coef=0"
)
ARMS=("$@")
[ ${#ARMS[@]} -gt 0 ] || ARMS=(default sb3 sb3like free flat squashed tanh ortho adam normall)
i=0
for arm in "${ARMS[@]}"; do
  for seed in $SEEDS; do
    if [ $((i % LANES)) -ne "$LANE" ]; then i=$((i + 1)); continue; fi
    i=$((i + 1))
    run=$OUT/$arm/seed=$seed
    log=$OUT/logs/$arm-seed=$seed.log
    mkdir -p "$run" "$OUT/logs"
    if [ "$arm" = sb3 ]; then
      if [ ! -f "$run/train.json" ]; then
        "$PY" "$HERE/examples/sb3/train.py" --algo ppo --steps "$STEPS" --seed "$seed" \
          --workers 0 --threads 1 --out "$run" > "$log" 2>&1
      fi
      policy=$run/policy.pt
    else
      if [ ! -f "$run/done" ]; then
        # the fixed-pose stage for the whole run, as issue #45's runs (the default before
        # issue #55 scaled the stages to the run)
        sets=(--set torch_threads=1 --set behavior.fixed_pose_steps=4000000)
        for kv in ${ARM[$arm]}; do sets+=(--set "$kv"); done
        if [ -f "$run/checkpoint_latest.pt" ]; then
          "$DEVLEARN" run self_touch --resume "$run" > "$log" 2>&1
        else
          "$DEVLEARN" run self_touch --steps "$STEPS" --workers 0 --seed "$seed" --force \
            --out "$run" "${sets[@]}" > "$log" 2>&1
        fi
        touch "$run/done"
      fi
      policy=$run/checkpoint_latest.pt
    fi
    [ -f "$run/eval/eval.json" ] || "$DEVLEARN" eval self_touch --checkpoint "$policy" \
      --episodes "$EPISODES" --seed 0 --workers 0 --out "$run/eval" > /dev/null 2>&1
    if [ "$arm" != sb3 ] && [ ! -f "$run/eval_sample/eval.json" ]; then
      "$DEVLEARN" eval self_touch --checkpoint "$policy" --episodes "$EPISODES" --seed 0 \
        --workers 0 --action sample --out "$run/eval_sample" > /dev/null 2>&1
    fi
    echo "$(date -u +%H:%M:%S) done $arm seed=$seed"
  done
done
if [ "$LANE" = 0 ]; then
  for base in zero random; do
    [ -f "$OUT/baseline_$base/eval.json" ] || "$DEVLEARN" eval self_touch --policy $base \
      --episodes "$EPISODES" --seed 0 --workers 0 --out "$OUT/baseline_$base" > /dev/null 2>&1
  done
fi
