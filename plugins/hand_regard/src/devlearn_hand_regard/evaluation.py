"""Hand-regard metrics: per-(eye, hand) visibility and the detector's agreement with truth.

Paper sec. II-B6: "hand visibility (% of steps with valid detection) across all four eye-hand
pairs ... reporting per-pair visibility and average across all pairs".
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from devlearn.behavior import Evaluator
from devlearn.rewards import StepContext

EYES = ("left", "right")
HANDS = ("left", "right")
PAIRS = tuple((e, h) for h in range(2) for e in range(2))
"""(eye, hand) index pairs in the paper's table order: LL, RL, LR, RR."""
PAPER_VISIBILITY = {
    "left_eye_left_hand": 0.996,
    "right_eye_left_hand": 0.985,
    "left_eye_right_hand": 0.0,
    "right_eye_right_hand": 0.044,
}
"""The paper's result (Table III), for comparison."""


def pair_name(eye: int, hand: int) -> str:
    """``left_eye_right_hand`` style key of an (eye, hand) pair."""
    return f"{EYES[eye]}_eye_{HANDS[hand]}_hand"


def visibility_dict(counts: np.ndarray, steps: int) -> dict[str, float]:
    """Turn (2 eyes, 2 hands) step counts into fractions keyed by pair name (paper order)."""
    return {pair_name(e, h): float(counts[e, h]) / max(steps, 1) for e, h in PAIRS}


class HandRegardEvaluator(Evaluator):
    """Counts, per (eye, hand) pair, the steps in which the hand is in view.

    Args:
        ground_truth: True (``devlearn eval``): visibility from ``infant.hand_visibility()``
            (the renderer's segmentation), plus the detector's agreement with it. False
            (training): visibility from the detector's output in the step facts, which costs
            nothing extra.
    """

    def __init__(self, ground_truth: bool) -> None:
        self.ground_truth = ground_truth
        self.episodes = 0
        self.steps = 0
        self.truth = np.zeros((2, 2), dtype=np.int64)  # steps in view, all episodes
        self.detected = np.zeros((2, 2), dtype=np.int64)
        # Detector vs truth confusion counts per pair: true/false positives/negatives.
        self.confusion = {k: np.zeros((2, 2), dtype=np.int64) for k in ("tp", "fp", "fn", "tn")}
        self._episode_steps = 0
        self._episode = np.zeros((2, 2), dtype=np.int64)

    def record(self, ctx: StepContext) -> None:
        detected = np.asarray(ctx.facts["hand_detections"], dtype=bool)
        self.detected += detected
        self._episode_steps += 1
        if self.ground_truth:
            truth = np.asarray(ctx.infant.hand_visibility(), dtype=bool)
            self.truth += truth
            self._episode += truth
            self.confusion["tp"] += detected & truth
            self.confusion["fp"] += detected & ~truth
            self.confusion["fn"] += ~detected & truth
            self.confusion["tn"] += ~detected & ~truth
        else:
            self._episode += detected

    def end_episode(self) -> dict[str, float]:
        if self._episode_steps == 0:
            return {}
        metrics = visibility_dict(self._episode, self._episode_steps)
        metrics["average"] = float(np.mean(list(metrics.values())))
        self.episodes += 1
        self.steps += self._episode_steps
        self._episode_steps = 0
        self._episode[:] = 0
        return metrics

    def agreement(self) -> dict[str, dict[str, float | None]]:
        """Per pair: accuracy, precision and recall of the detector against the segmentation.

        Precision is ``None`` when the detector never fired for that pair, recall ``None`` when
        the hand was never in view.
        """
        c = self.confusion
        out: dict[str, dict[str, float | None]] = {}
        for e, h in PAIRS:
            tp, fp, fn, tn = (int(c[k][e, h]) for k in ("tp", "fp", "fn", "tn"))
            total = tp + fp + fn + tn
            out[pair_name(e, h)] = {
                "accuracy": (tp + tn) / total if total else None,
                "precision": tp / (tp + fp) if tp + fp else None,
                "recall": tp / (tp + fn) if tp + fn else None,
            }
        return out

    def summary(self) -> dict[str, Any]:
        steps = self.steps + self._episode_steps  # finished episodes and any still open
        source = self.truth if self.ground_truth else self.detected
        visibility = visibility_dict(source, steps)
        result: dict[str, Any] = {
            "episodes": self.episodes,
            "steps": steps,
            "visibility_source": "segmentation" if self.ground_truth else "detector",
            "visibility": visibility,
            "average": float(np.mean(list(visibility.values()))),
            "detector_visibility": visibility_dict(self.detected, steps),
            "paper": {"visibility": PAPER_VISIBILITY, "average": 0.50625},
        }
        if self.ground_truth:
            result["detector_agreement"] = self.agreement()
        return result

    def write_artifacts(self, out_dir: Path) -> list[Path]:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        summary = self.summary()
        names = list(summary["visibility"])
        labels = [n.replace("_eye_", " eye\n").replace("_hand", " hand") for n in names]
        x = np.arange(len(names))
        fig, ax = plt.subplots(figsize=(6.4, 3.6))
        ax.bar(x - 0.2, [summary["visibility"][n] for n in names], 0.4,
               label=f"ours ({summary['visibility_source']})")
        ax.bar(x + 0.2, [PAPER_VISIBILITY[n] for n in names], 0.4, label="paper", alpha=0.5)
        ax.set_xticks(x, labels)
        ax.set_ylim(0, 1.05)
        ax.set_ylabel("fraction of steps in view")
        ax.set_title(f"Hand regard: average {summary['average']:.3f} "
                     f"({summary['episodes']} episodes)")
        ax.legend(loc="upper right", fontsize=8)
        fig.tight_layout()
        out_dir = Path(out_dir)
        out_dir.mkdir(parents=True, exist_ok=True)
        path = out_dir / "hand_regard_visibility.png"
        fig.savefig(path, dpi=120)
        plt.close(fig)
        return [path]
