"""Would a confidence gate on the visibility attribution resist what issue #39's reach arm
learned? An offline analysis (issue #39, after the 1.85M experiment), not the detector's rule.

Run from the repository root (results/hand_regard/i39/README.md gives the committed run)::

    python -m devlearn_hand_regard.analysis.gate --policies P.pt [P2.pt ...] --out FILE.json

Each policy runs ``devlearn eval``'s protocol (10 episodes from BabyBench's start, eval seed
0, its mean action; :func:`~devlearn_hand_regard.analysis.attribution.policy_frames`), and
its frames are scored against the segmentation (``pixels``) by its own calibration under: the
position rule; the visibility rule (the one the runs trained with); and the visibility rule
gated, where an eye in which neither hand is predicted in view (both P(eye sees hand |
posture) below ``tau``) attributes its blobs by position (``fallback position``) or to neither
hand (``fallback none``). Printed and written per policy and rule: pair-averaged precision and
recall, and the largest share of steps a pair is credited while its hand shows no pixel.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from devlearn import write_text_atomically
from devlearn.testing import PluginRegistry
from devlearn_hand_regard.analysis.attribution import (
    brief,
    policy_detector,
    policy_frames,
    policy_name,
)
from devlearn_hand_regard.detector import Blob, DetectorParams, HandDetector
from devlearn_hand_regard.segmentation_score import score

TAUS = (0.05, 0.2)
"""Gate thresholds tried: the largest predicted visibility of the two hands below it."""
FALLBACKS = ("position", "none")
"""What an eye below the gate does: attribute by image position, or credit neither hand."""


class GatedDetector(HandDetector):
    """The visibility rule, except in an eye where neither hand is predicted in view: there
    blobs go by position (``fallback="position"``) or to neither hand (``"none"``)."""

    def __init__(self, params: DetectorParams, tau: float, fallback: str) -> None:
        if fallback not in FALLBACKS:
            raise ValueError(f"unknown fallback {fallback!r}; valid: {', '.join(FALLBACKS)}")
        super().__init__(params, attribution="visibility")
        self.tau, self.fallback = tau, fallback
        self._proprioception: np.ndarray | None = None

    def detect(self, eyes, proprioception=None, hands=None, view_prior=None):  # type: ignore[no-untyped-def]
        """As :meth:`HandDetector.detect`, keeping the posture for the position fallback."""
        self._proprioception = proprioception
        return super().detect(eyes, proprioception, hands, view_prior)

    def attribute_by_visibility(
        self, blobs: list[Blob], eye: int, likelihood: np.ndarray
    ) -> list[list[Blob]]:
        """[left hand's blobs, right hand's blobs] of one eye; below the gate, the fallback's."""
        if not blobs or float(np.max(likelihood)) >= self.tau:
            return super().attribute_by_visibility(blobs, eye, likelihood)
        if self.fallback == "none":
            return [[], []]
        single = self.attribute(blobs, eye, blobs[0].mask.shape[1], self._proprioception)
        return [[blob] if blob is not None else [] for blob in single]


def figures(result: dict[str, Any]) -> dict[str, float]:
    """Pair-averaged precision / recall and the worst false credit (share of steps) of a
    ``segmentation_score.score`` result."""
    short = brief(result)
    return {
        "precision": round(short["pair_mean"]["precision_pixels"], 3),
        "recall": round(short["pair_mean"]["recall_pixels"], 3),
        "credited_absent_max": round(max(p["credited_absent"] for p in short["pairs"].values()), 4),
    }


def rules(params: DetectorParams) -> dict[str, HandDetector]:
    """Every rule compared, by name: position, visibility, and the gated visibility rule at
    each of :data:`TAUS` with each of :data:`FALLBACKS`."""
    found: dict[str, HandDetector] = {
        "position": HandDetector(params),
        "visibility": HandDetector(params, attribution="visibility"),
    }
    for fallback in FALLBACKS:
        for tau in TAUS:
            found[f"gated {tau}, fallback {fallback}"] = GatedDetector(params, tau, fallback)
    return found


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line: see the module docstring. Returns what the JSON file holds."""
    parser = argparse.ArgumentParser(
        prog="python -m devlearn_hand_regard.analysis.gate",
        description=(__doc__ or "").splitlines()[0],
    )
    parser.add_argument("--policies", nargs="+", required=True, help="policy files")
    parser.add_argument("--episodes", type=int, default=10, help="evaluation episodes each")
    parser.add_argument("--out", required=True, help="JSON file for the figures")
    args = parser.parse_args(argv)
    registry = PluginRegistry()
    out: dict[str, Any] = {"argv": sys.argv[1:] if argv is None else argv, "policies": {}}
    for name in args.policies:
        path = Path(name)
        recorded = policy_frames(path, args.episodes, registry)
        data, segmentation = recorded["data"], recorded["segmentation"]
        row = {
            rule: figures(score(detector, data, segmentation))
            for rule, detector in rules(policy_detector(path)).items()
        }
        out["policies"][policy_name(path)] = row
        print(policy_name(path), json.dumps(row), flush=True)
    write_text_atomically(Path(args.out), json.dumps(out, indent=1) + "\n")
    return out


if __name__ == "__main__":
    main()
