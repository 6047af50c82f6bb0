"""What the learned term paid, from each run's metrics.jsonl: per-step means over training of
the paper reward (``mean_step_reward``) and the weighted curiosity reward
(``reward/forward_model/step``), its share, and the last row's entropy and raw model error.

    python results/curiosity/term_share.py results/curiosity/i18/*/ \
        results/hand_regard/i19/reward=paper,*/
"""

from __future__ import annotations

import json
import sys
from pathlib import Path


def summary(run: Path) -> dict:
    rows = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]
    paper = sum(r["mean_step_reward"] for r in rows) / len(rows)
    added = [r["reward/forward_model/step"] for r in rows if "reward/forward_model/step" in r]
    term = sum(added) / len(added) if added else 0.0
    return {
        "run": run.name,
        "paper_reward_per_step": round(paper, 3),
        "forward_model_per_step": round(term, 3),
        "forward_model_share": round(term / (term + paper), 3),
        "last_step": rows[-1]["step"],
        "last_entropy": round(rows[-1]["loss/entropy"], 1),
        "last_raw_error": rows[-1].get("reward/forward_model/raw"),
    }


if __name__ == "__main__":
    for folder in sys.argv[1:]:
        print(json.dumps(summary(Path(folder))))
