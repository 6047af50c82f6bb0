"""Hand-regard metrics: per-(eye, hand) visibility and the detector's agreement with truth.

Paper sec. II-B6: "hand visibility (% of steps with valid detection) across all four eye-hand
pairs ... reporting per-pair visibility and average across all pairs".
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from devlearn import Evaluator, StepContext, episode_stats, write_atomically
from devlearn_hand_regard.visibility import CRITERIA, DETECTOR_TRUTH, HEADLINE, criteria_protocol

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
PAPER_AVERAGE = 0.50625
"""The mean of :data:`PAPER_VISIBILITY`'s four pairs (Table III)."""


def paper_figures() -> tuple[str, dict[str, float]]:
    """The paper's column in ``devlearn report`` (Table III: its reward, 1.85M steps), under
    the eval JSON's metric names."""
    figures = {f"visibility.{k}": v for k, v in PAPER_VISIBILITY.items()}
    return "paper: Table III, 1.85M", {**figures, "average": PAPER_AVERAGE}


def pair_name(eye: int, hand: int) -> str:
    """``left_eye_right_hand`` style key of an (eye, hand) pair."""
    return f"{EYES[eye]}_eye_{HANDS[hand]}_hand"


def visibility_dict(counts: np.ndarray, steps: int) -> dict[str, float]:
    """Turn (2 eyes, 2 hands) step counts into fractions keyed by pair name (paper order)."""
    return {pair_name(e, h): float(counts[e, h]) / max(steps, 1) for e, h in PAIRS}


class HandRegardEvaluator(Evaluator):
    """Counts, per (eye, hand) pair, the steps in which the hand is in view.

    In evaluation (``ground_truth``) a hand is in view under five criteria side by side:
    ``detector``, the calibrated detector's own detections (the paper's measure and the
    headline: ``visibility`` and ``average``), and from the scene
    (:mod:`devlearn_hand_regard.visibility`) ``pixels`` (ground truth: at least 20 of the
    hand's pixels in the eye's segmentation), ``babybench`` (BabyBench's official counter,
    computed in our geometry), ``cone`` (the true optical axis within 15 degrees) and
    ``any_pixel``. The detector's precision and recall are measured against ``pixels``.
    Each episode's average visibility is kept, so :meth:`summary` reports its mean, standard
    deviation and 95% t-interval per criterion.

    Args:
        ground_truth: True (``devlearn eval``): visibility from the scene (geometry and the
            renderer's segmentation), plus the detector's agreement with it. False
            (training): visibility from the detector's output in the step facts, which costs
            nothing extra.
        measure: ``measure(infant) -> {criterion: (2, 2) bool}`` (tests script it); default
            :func:`~devlearn_hand_regard.visibility.measure_visibility`.
    """

    mergeable = True  # merge() below: devlearn eval may play its episodes in several envs

    def __init__(
        self, ground_truth: bool, measure: Callable[[Any], dict[str, np.ndarray]] | None = None
    ) -> None:
        if measure is None:
            from devlearn_hand_regard.visibility import measure_visibility

            measure = measure_visibility
        self.ground_truth = ground_truth
        self.measure: Callable[[Any], dict[str, np.ndarray]] = measure
        self.episodes = 0
        self.steps = 0
        names = ("detector", *CRITERIA) if ground_truth else ("detector",)
        self.counts = {k: np.zeros((2, 2), dtype=np.int64) for k in names}  # all episodes
        self._episode = {k: np.zeros((2, 2), dtype=np.int64) for k in names}
        self.episode_averages: dict[str, list[float]] = {k: [] for k in names}
        self.detected = np.zeros((2, 2), dtype=np.int64)
        # Detector vs truth confusion counts per pair: true/false positives/negatives.
        self.confusion = {k: np.zeros((2, 2), dtype=np.int64) for k in ("tp", "fp", "fn", "tn")}
        # Per hand [left, right]: its mask's pixels on that hand, mask pixels, the hand's pixels.
        self.pixel_counts = np.zeros((3, 2), dtype=np.int64)
        self._episode_steps = 0

    @property
    def headline(self) -> str:
        """Criterion behind ``visibility`` and ``average``."""
        return HEADLINE if self.ground_truth else "detector"

    def record(self, ctx: StepContext) -> None:
        detected = np.asarray(ctx.facts["hand_detections"], dtype=bool)
        self.detected += detected
        self._episode_steps += 1
        if self.ground_truth:
            verdicts = {k: np.asarray(v, dtype=bool) for k, v in self.measure(ctx.infant).items()}
            verdicts["detector"] = detected
            truth = verdicts[DETECTOR_TRUTH]
            self.confusion["tp"] += detected & truth
            self.confusion["fp"] += detected & ~truth
            self.confusion["fn"] += ~detected & truth
            self.confusion["tn"] += ~detected & ~truth
            if "hand_masks" in ctx.facts and hasattr(ctx.infant, "eyes_segmentation"):
                self._count_pixels(ctx.infant, np.asarray(ctx.facts["hand_masks"], dtype=bool))
        else:
            verdicts = {"detector": detected}
        for k in self.counts:
            if k in verdicts:  # a scripted measure may leave a criterion out
                self.counts[k] += verdicts[k]
                self._episode[k] += verdicts[k]

    def end_episode(self) -> dict[str, float]:
        if self._episode_steps == 0:
            return {}
        metrics: dict[str, float] = {}
        for k, counts in self._episode.items():
            pairs = visibility_dict(counts, self._episode_steps)
            average = float(np.mean(list(pairs.values())))
            self.episode_averages[k].append(average)
            if k == self.headline:
                metrics.update(pairs, average=average)
            else:
                metrics[f"average_{k}"] = average
            counts[:] = 0
        self.episodes += 1
        self.steps += self._episode_steps
        self._episode_steps = 0
        return metrics

    def merge(self, later: Evaluator) -> None:
        """Add ``later``'s episodes after this one's (``devlearn eval --envs N``): step
        counts summed, per-episode averages joined in order."""
        assert isinstance(later, HandRegardEvaluator)
        self.episodes += later.episodes
        self.steps += later.steps
        for k in self.counts:
            self.counts[k] += later.counts[k]
            self.episode_averages[k] += later.episode_averages[k]
        self.detected += later.detected
        for k in self.confusion:
            self.confusion[k] += later.confusion[k]
        self.pixel_counts += later.pixel_counts

    def _count_pixels(self, infant: Any, masks: np.ndarray) -> None:
        """Add one step's pixel counts: masks (2 eyes, 2 hands, H, W) against the segmentation."""
        seg = np.asarray(infant.eyes_segmentation())  # (2 eyes, H, W), cached by the infant
        for h, side in enumerate(HANDS):
            truth = seg == infant.hand_labels[side]
            self.pixel_counts[:, h] += [(masks[:, h] & truth).sum(), masks[:, h].sum(), truth.sum()]

    def pixel_agreement(self) -> dict[str, dict[str, float | None]]:
        """Per hand, both eyes pooled: ``precision``, the share of the pixels the detector
        attributed to that hand that are that hand in the segmentation, and ``recall``, the
        share of that hand's pixels inside its detected mask (``None`` without any)."""
        on, mask, truth = self.pixel_counts
        return {
            f"{side}_hand": {
                "precision": float(on[h] / mask[h]) if mask[h] else None,
                "recall": float(on[h] / truth[h]) if truth[h] else None,
            }
            for h, side in enumerate(HANDS)
        }

    def agreement(self) -> dict[str, dict[str, float | None]]:
        """Per pair and their mean (``average``): accuracy, precision and recall of the
        detector against ``pixels`` (at least 20 of the hand's pixels in the segmentation).

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
        pairs = list(out.values())
        out["average"] = {}
        for k in ("accuracy", "precision", "recall"):
            values = [v for p in pairs if (v := p[k]) is not None]
            out["average"][k] = float(np.mean(values)) if values else None
        return out

    def summary(self) -> dict[str, Any]:
        steps = self.steps + self._episode_steps  # finished episodes and any still open
        criteria: dict[str, Any] = {}
        for k in self.counts:
            visibility = visibility_dict(self.counts[k] + self._episode[k], steps)
            criteria[k] = {
                "visibility": visibility,
                "average": float(np.mean(list(visibility.values()))),
                **episode_stats("average", self.episode_averages[k]),
            }
        head = criteria[self.headline]
        result: dict[str, Any] = {
            "episodes": self.episodes,
            "steps": steps,
            "visibility_source": "scene" if self.ground_truth else "detector",
            "headline_criterion": self.headline,
            "visibility": head["visibility"],
            "average": head["average"],
            **{k: v for k, v in head.items() if k.startswith("episode_")},
            "criteria": criteria,
            "detector_visibility": visibility_dict(self.detected, steps),
            "paper": {"visibility": PAPER_VISIBILITY, "average": PAPER_AVERAGE},
        }
        if self.ground_truth:
            result["detector_agreement"] = self.agreement()
            result["detector_pixels"] = self.pixel_agreement()
        return result

    def protocol(self) -> dict[str, Any]:
        """Criteria names and thresholds (recorded in every eval JSON)."""
        if not self.ground_truth:
            return {"criteria": {"detector": {}}, "headline": "detector"}
        return {
            "settle_steps": 0,
            "criteria": criteria_protocol(),
            "headline": HEADLINE,
            "detector_truth": DETECTOR_TRUTH,
        }

    def write_artifacts(self, out_dir: Path) -> list[Path]:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        summary = self.summary()
        names = list(summary["visibility"])
        labels = [n.replace("_eye_", " eye\n").replace("_hand", " hand") for n in names]
        x = np.arange(len(names))
        fig, ax = plt.subplots(figsize=(6.4, 3.6))
        width = 0.8 / (len(summary["criteria"]) + 1)
        for i, (k, c) in enumerate(summary["criteria"].items()):
            ax.bar(
                x - 0.4 + (i + 0.5) * width,
                [c["visibility"][n] for n in names],
                width,
                label=f"ours: {k}",
            )
        ax.bar(
            x + 0.4 - 0.5 * width,
            [PAPER_VISIBILITY[n] for n in names],
            width,
            label="paper",
            alpha=0.5,
        )
        ax.set_xticks(x, labels)
        ax.set_ylim(0, 1.05)
        ax.set_ylabel("fraction of steps in view")
        ax.set_title(
            f"Hand regard: average {summary['average']:.3f} "
            f"({summary['headline_criterion']}, {summary['episodes']} episodes)"
        )
        ax.legend(loc="upper right", fontsize=8)
        fig.tight_layout()
        out_dir = Path(out_dir)
        out_dir.mkdir(parents=True, exist_ok=True)
        path = out_dir / "hand_regard_visibility.png"
        try:
            write_atomically(path, lambda f: fig.savefig(f, format="png", dpi=120))
        finally:
            plt.close(fig)
        return [path]
