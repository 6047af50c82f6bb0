# Shared by curriculum.sh and ablation.sh (sourced, not run): one evaluation protocol for the
# trained runs and the baselines. Needs DEVLEARN and EPISODES set by the sourcing script.

evaluate() {  # evaluate DIR ARGS...: one evaluation (eval seed 0) unless DIR/eval.json exists
  local dir=$1
  shift
  [ -f "$dir/eval.json" ] || "$DEVLEARN" eval self_touch "$@" --episodes "$EPISODES" --seed 0 \
    --json --out "$dir" > /dev/null
}

baselines() {  # baselines OUT: zero and random actions, from random poses and from the rest pose
  local out=$1 policy
  for policy in zero random; do
    evaluate "$out/baseline_$policy" --policy "$policy"
    evaluate "$out/baseline_${policy}_rest" --policy "$policy" --start rest
  done
}
