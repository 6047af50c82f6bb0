"""What the visibility model predicts on a policy's own evaluation frames (issue #39).

Run from the repository root (results/hand_regard/i39/README.md gives the committed run)::

    python -m devlearn_hand_regard.analysis.view_prior P.pt [P2.pt ...]

Each policy runs ``devlearn eval``'s protocol (10 episodes from BabyBench's start, eval seed 0;
:func:`~devlearn_hand_regard.analysis.attribution.policy_frames`); printed per eye: the median
over its frames of the posture's predicted P(this eye sees the left hand) and P(... the right
hand), the share of frames where the right hand's is the larger, and the evaluation's
``pixels`` visibility beside them.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from devlearn import UsageError
from devlearn.testing import PluginRegistry
from devlearn_hand_regard.analysis.attribution import policy_detector, policy_frames
from devlearn_hand_regard.detector import HandDetector

EYES = ("left eye", "right eye")


def prior_medians(prior: np.ndarray) -> list[dict[str, float]]:
    """Per eye, from the (T, 2 eyes, 2 hands) predicted visibilities of T frames: the median
    P(sees the left hand), the median P(sees the right hand), and the share of frames where
    the right hand's is the larger. Returns 2 dicts (left eye, right eye)."""
    if prior.ndim != 3 or prior.shape[1:] != (2, 2):
        raise ValueError(f"expected (frames, 2 eyes, 2 hands) predictions, got {prior.shape}")
    return [
        {
            "left_median": float(np.median(prior[:, e, 0])),
            "right_median": float(np.median(prior[:, e, 1])),
            "right_larger_share": float(np.mean(prior[:, e, 1] > prior[:, e, 0])),
        }
        for e in range(2)
    ]


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line: see the module docstring. Returns each policy's figures by its path."""
    parser = argparse.ArgumentParser(
        prog="python -m devlearn_hand_regard.analysis.view_prior",
        description=(__doc__ or "").splitlines()[0],
    )
    parser.add_argument("policies", nargs="+", help="policy files")
    parser.add_argument("--episodes", type=int, default=10, help="evaluation episodes each")
    args = parser.parse_args(argv)
    registry = PluginRegistry()
    found: dict[str, Any] = {}
    for name in args.policies:
        recorded = policy_frames(Path(name), args.episodes, registry)
        detector = HandDetector(policy_detector(Path(name)), attribution="visibility")
        priors = [detector.view_prior(p) for p in recorded["data"].proprioception]
        if any(p is None for p in priors):
            raise UsageError(f"{name}: its detector has no visibility model (issue #39's)")
        medians = prior_medians(np.stack(priors))  # type: ignore[arg-type]
        pixels = recorded["summary"]["criteria"]["pixels"]["visibility"]
        print(name, "frames", len(priors))
        for eye, m in zip(EYES, medians):
            print(
                f"  {eye}: P(sees left hand) median {m['left_median']:.3f}, P(sees right hand) "
                f"median {m['right_median']:.3f}, right > left on {m['right_larger_share']:.2f}"
            )
        print("  pixels", pixels)
        found[name] = {"frames": len(priors), "eyes": medians, "pixels": pixels}
    return found


if __name__ == "__main__":
    main()
