"""Trim a publication (``devlearn experiment publish``'s folder) for the tree's 25 MB, as issue
#54's publications of 2026-12-07 were: no policy file, no curves, and eval.json files without
their copy of the run's config (config.json is beside each), per-episode parts, part touch
steps and the self-touch coding's per-limb figures (``devlearn experiment table`` reads none of
them). ``--scores-only`` also drops the self-touch coding's likeness figures (``likeness``,
``likeness_coded``: a table of the per-episode score alone needs neither; a table with
``--metric`` on them does). Prints the folder's bytes after.

    python3 experiments/trim_publication.py results/learners/i54/linear
    python3 experiments/trim_publication.py results/learners/i54/parts_update --scores-only
"""

import json
import pathlib
import sys

dest = pathlib.Path(sys.argv[1])
scores_only = "--scores-only" in sys.argv[2:]
for p in dest.rglob("policy.pt"):
    p.unlink()
for p in dest.rglob("curve.jsonl"):
    p.unlink()
for p in dest.rglob("eval.json"):
    d = json.loads(p.read_text())
    for k in ("config", "episode_parts", "part_touch_steps"):
        d.pop(k, None)
    if isinstance(d.get("likeness_coded"), dict):
        d["likeness_coded"].pop("limbs", None)
    if scores_only:
        d.pop("likeness", None)
        d.pop("likeness_coded", None)
    p.write_text(json.dumps(d) + "\n")
exp = dest / "experiment.json"
if exp.exists():
    e = json.loads(exp.read_text())
    for pol in (e.get("policies") or {}).values():
        pol["file"] = None
        pol["not_kept"] = "the tree's 25 MB; the experiment file remakes it"
    exp.write_text(json.dumps(e, indent=1) + "\n")
print(sum(f.stat().st_size for f in dest.rglob("*") if f.is_file()))
