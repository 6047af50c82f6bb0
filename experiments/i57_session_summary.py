"""Issue #57: mean and 95% t-interval over seeds of the coded session figures in eval.json files
laid out as ROOT/[SUB]seed=N/PROTOCOL/eval.json (an experiment publication's arm folder, or
experiments/i57_paper_sessions.sh's output).

    python experiments/i57_session_summary.py ROOT PROTOCOL 1,2,3,4,5 [SUB]
    python experiments/i57_session_summary.py results/self_touch/likeness/paper_8M eval_sessions_mean 1,2,3,4,5
"""

import json
import math
import statistics as st
import sys

from scipy import stats

root, proto, seeds = sys.argv[1], sys.argv[2], [int(x) for x in sys.argv[3].split(",")]
sub = sys.argv[4] if len(sys.argv) > 4 else ""
KEYS = ("episode_score_mean", "all_touches_per_minute", "touches_per_minute",
        "surface_touches_per_minute", "contact_time_share", "bout_seconds_mean",
        "between_touches_time_share", "upper_body_share")  # fmt: skip
UPPER = ("head_face", "trunk", "arms", "hands")
cols: dict[str, list[float]] = {k: [] for k in KEYS}
for s in seeds:
    with open(f"{root}/{sub}seed={s}/{proto}/eval.json") as f:
        d = json.load(f)
    coded = d["likeness_coded"]
    for k in KEYS:
        if k == "episode_score_mean":
            v = d[k]
        elif k == "upper_body_share":
            v = sum(coded["touch_share_by_area"][a] or 0 for a in UPPER)
        else:
            v = coded[k] or 0.0
        cols[k].append(float(v))
for k, v in cols.items():
    m = st.mean(v)
    h = stats.t.ppf(0.975, len(v) - 1) * st.stdev(v) / math.sqrt(len(v)) if len(v) > 1 else math.nan
    print(f"{k}: {m:.3f} [{m - h:.3f}, {m + h:.3f}]  per seed {', '.join(f'{x:.3f}' for x in v)}")
