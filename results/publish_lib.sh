# Shared by the results/*/publish*.sh scripts (sourced, not run).

thin_log() {  # thin_log SRC DEST EVERY: a training log's every EVERY-th row plus the last
  awk -v last="$(wc -l < "$1")" -v every="$3" 'NR % every == 0 || NR == last' "$1" > "$2"
}

copy_baselines() {  # copy_baselines OUT DEST: every OUT/baseline_*/eval.json into DEST
  local base
  for base in "$1"/baseline_*/; do
    [ -f "$base/eval.json" ] || continue
    mkdir -p "$2/$(basename "$base")"
    cp "$base/eval.json" "$2/$(basename "$base")/"
  done
}

run_named() {  # run_named OUT NAMER NAME: the run OUT/*/runs/* that `NAMER RUN` publishes as NAME
  local run
  for run in "$1"/*/runs/*/; do
    [ "$("$2" "${run%/}")" != "$3" ] || { echo "${run%/}"; return; }
  done
  echo "no run of $1 is published as $3" >&2
  return 2
}
