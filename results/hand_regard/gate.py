"""Issue #39, after the 1.85M experiment: would a confidence gate on the visibility attribution
resist what the reach arm's policies learned? An offline analysis, not the detector's rule.

Run from the repository root::

    python results/hand_regard/gate.py --policies results/hand_regard/i39/*/policy.pt \
        --out results/hand_regard/i39/gate.json

Each policy runs ``devlearn eval``'s protocol (10 episodes from BabyBench's start, eval seed
0, its mean action; :func:`attribution.policy_frames`), and its frames are scored against the
segmentation (``pixels``) by its own calibration under: the position rule; the visibility rule
(the one the runs trained with); and the visibility rule gated, where an eye in which neither
hand is predicted in view (both P(eye sees hand | posture) below ``tau``) attributes its blobs
by position (``fallback position``) or to neither hand (``fallback none``). Printed and written
per policy and rule: pair-averaged precision and recall, and the largest share of steps a pair
is credited while its hand shows no pixel.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np
from attribution import brief, policy_frames
from devlearn_hand_regard.detector import Blob, HandDetector
from devlearn_hand_regard.segmentation_score import score

from devlearn.plugins import PluginRegistry
from devlearn.training.checkpoint import Checkpoint

TAUS = (0.05, 0.2)
"""Gate thresholds tried: the largest predicted visibility of the two hands below it."""


class GatedDetector(HandDetector):
    """The visibility rule, except in an eye where neither hand is predicted in view."""

    def __init__(self, params: Any, tau: float, fallback: str) -> None:
        super().__init__(params, attribution="visibility")
        self.tau, self.fallback = tau, fallback
        self._proprioception: np.ndarray | None = None

    def detect(self, eyes, proprioception=None, hands=None, view_prior=None):  # type: ignore[no-untyped-def]
        self._proprioception = proprioception
        return super().detect(eyes, proprioception, hands, view_prior)

    def attribute_by_visibility(
        self, blobs: list[Blob], eye: int, likelihood: np.ndarray
    ) -> list[list[Blob]]:
        if not blobs or float(np.max(likelihood)) >= self.tau:
            return super().attribute_by_visibility(blobs, eye, likelihood)
        if self.fallback == "none":
            return [[], []]
        single = self.attribute(blobs, eye, blobs[0].mask.shape[1], self._proprioception)
        return [[blob] if blob is not None else [] for blob in single]


def figures(result: dict[str, Any]) -> dict[str, float]:
    """Pair-averaged precision / recall and the worst false credit (share of steps)."""
    short = brief(result)
    return {
        "precision": round(short["pair_mean"]["precision_pixels"], 3),
        "recall": round(short["pair_mean"]["recall_pixels"], 3),
        "credited_absent_max": round(max(p["credited_absent"] for p in short["pairs"].values()), 4),
    }


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line: see the module docstring."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--policies", nargs="+", required=True, help="policy files")
    parser.add_argument("--episodes", type=int, default=10, help="evaluation episodes each")
    parser.add_argument("--out", required=True, help="JSON file for the figures")
    args = parser.parse_args(argv)
    registry = PluginRegistry()
    out: dict[str, Any] = {"argv": sys.argv[1:] if argv is None else argv, "policies": {}}
    for path in args.policies:
        name = f"{Path(path).parent.parent.name}/{Path(path).parent.name}"
        recorded = policy_frames(Path(path), args.episodes, registry)
        data, segmentation = recorded["data"], recorded["segmentation"]
        params = Checkpoint.open(Path(path), registry, "hand_regard").behavior().detector.params
        rules: dict[str, HandDetector] = {
            "position": HandDetector(params),
            "visibility": HandDetector(params, attribution="visibility"),
        }
        for fallback in ("position", "none"):
            for tau in TAUS:
                rules[f"gated {tau}, fallback {fallback}"] = GatedDetector(params, tau, fallback)
        row = {rule: figures(score(d, data, segmentation)) for rule, d in rules.items()}
        out["policies"][name] = row
        print(name, json.dumps(row), flush=True)
    Path(args.out).write_text(json.dumps(out, indent=1) + "\n")
    return out


if __name__ == "__main__":
    main()
