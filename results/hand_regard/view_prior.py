"""Issue #39: what the visibility model predicts on a policy's own evaluation frames.

Run from the repository root::

    python results/hand_regard/view_prior.py \
        results/hand_regard/i39/reward=reach_t4,seed=2/policy.pt

Each policy runs ``devlearn eval``'s protocol (10 episodes from BabyBench's start, eval seed 0;
:func:`attribution.policy_frames`); printed per eye: the median over its frames of the posture's
predicted P(this eye sees the left hand) and P(... the right hand), the share of frames where
the right hand's is the larger, and the evaluation's `pixels` visibility beside them.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from attribution import policy_frames

from devlearn.plugins import PluginRegistry
from devlearn.training.checkpoint import Checkpoint


def main(paths: list[str]) -> None:
    """Print the view prior's medians for each policy file in ``paths``."""
    registry = PluginRegistry()
    for path in paths:
        recorded = policy_frames(Path(path), 10, registry)
        detector = Checkpoint.open(Path(path), registry, "hand_regard").behavior().detector
        prior = np.stack([detector.view_prior(p) for p in recorded["data"].proprioception])
        print(path, "frames", len(prior))
        for e, eye in enumerate(("left eye", "right eye")):
            left, right = prior[:, e, 0], prior[:, e, 1]
            print(
                f"  {eye}: P(sees left hand) median {np.median(left):.3f}, P(sees right hand) "
                f"median {np.median(right):.3f}, right > left on {np.mean(right > left):.2f}"
            )
        print("  pixels", recorded["summary"]["criteria"]["pixels"]["visibility"])


if __name__ == "__main__":
    main(sys.argv[1:])
