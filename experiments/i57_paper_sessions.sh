#!/bin/bash
# Issue #57 item 5: the paper's reward under the video-coding protocol, at the paper's budget.
# Issue #30's five 8M curriculum policies (the paper's reward; seed 4's policy in the tree, the
# others restored from git history at b92feb7) evaluated in whole 5-minute sessions from rest
# (mean action, 2 sessions: without motor noise the second repeats the first) on the 18-month
# body and on a 1.5-month-old's, as the infant-like arms are (experiments/self_touch_infantlike*.toml's
# sessions_mean and sessions_mean_1.5mo protocols). Writes DEST/seed=N/eval_sessions_mean{,_1.5mo}/
# eval.json (compact, without the per-episode part lists or per-limb figures: the tree's size)
# and prints the coded figures per seed and their mean.
#
#   experiments/i57_paper_sessions.sh results/self_touch/likeness/paper_8M   # ~8 min on one core
set -e
cd "$(dirname "$0")/.."
DEST=${1:?usage: $0 DEST}
PY=${PYTHON:-.venv/bin/python}
DL=${DEVLEARN:-.venv/bin/devlearn}
TMP=$(mktemp -d)
for s in 1 2 3 4 5; do
  if [ "$s" = 4 ]; then P=results/self_touch/i30/curriculum/two_stage/policy.pt
  else P=$TMP/st30_s$s.pt; git show b92feb7:results/self_touch/i30/curriculum/runs/seed=$s/policy.pt > "$P"; fi
  for age in "" 1.5; do
    name=eval_sessions_mean${age:+_${age}mo}
    "$DL" eval self_touch --checkpoint "$P" --out "$DEST/seed=$s/$name" --episodes 2 --seed 0 \
        --start rest --workers 0 --json --action mean --session 300 \
        ${age:+--set infant.age_months=$age} > /dev/null
  done
done
rm -rf "$TMP"
"$PY" - "$DEST" <<'PY'
import json, pathlib, statistics, sys
dest = pathlib.Path(sys.argv[1])
for f in dest.rglob("eval.json"):  # compact, as the pilots' publications
    d = json.loads(f.read_text()); d.pop("episode_parts", None)
    if isinstance(d.get("likeness_coded"), dict):
        d["likeness_coded"].pop("limbs", None)
    f.write_text(json.dumps(d, separators=(",", ":")) + "\n")
for f in dest.rglob("*"):
    if f.is_file() and f.name != "eval.json":
        f.unlink()
keys = ("all_touches_per_minute", "touches_per_minute", "surface_touches_per_minute",
        "contact_time_share", "bout_seconds_mean", "between_touches_time_share")
for proto in ("eval_sessions_mean", "eval_sessions_mean_1.5mo"):
    rows = []
    for s in range(1, 6):
        d = json.loads((dest / f"seed={s}" / proto / "eval.json").read_text())
        L = d["likeness_coded"]
        upper = sum(L["touch_share_by_area"][a] or 0 for a in ("head_face", "trunk", "arms", "hands"))
        rows.append([d["episode_score_mean"], *(L[k] or 0.0 for k in keys), upper])
        print(proto, f"seed {s}:", " ".join(f"{v:.3f}" for v in rows[-1]))
    means = [statistics.mean(c) for c in zip(*rows)]
    print(proto, "mean:", " ".join(f"{v:.3f}" for v in means))
print("columns: coverage per session,", ", ".join(keys) + ", upper body's share of touches")
PY
