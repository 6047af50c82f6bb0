"""What hand regard's reward pays from the rest pose (training's start) for doing nothing,
against Gaussian action noise of a given spread: training episodes.

Run from the repository root::

    python results/hand_regard/rest_pose_return.py            # ~1 min on one core

The behaviour is built as the issue-19 runs train it (mittens, ``reward=paper`` and
``reward=bilateral``, both arms, the babbling-calibrated detector of
``detector/mittens_detector.json``, which every issue-19 run used); each episode starts at the
rest pose (``random_pose`` False, as every training episode does) and runs 1,000 steps of either
zero actions or actions drawn i.i.d. from N(0, std^2) and clipped to [-1, 1] (what a
policy whose mean is 0 does while training with that spread; seeds 0, 1, 2 of the noise).
Prints each episode's return, its reward terms and the detector's average visibility, as the
training metrics count them, then all of it as JSON.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from devlearn_hand_regard import HandRegardConfig

from devlearn.env.behavior_env import BehaviorEnv
from devlearn.plugins import PluginRegistry

DETECTOR = Path(__file__).resolve().parent / "detector" / "mittens_detector.json"
SPREADS = (0.0, 0.5, 1.0, 2.7)
"""Action noise std: 0 (zero action), 0.5 (the policy's initial spread), 1.0, and 2.7 (the
spread the paper-reward run of seed 1 reached at 300k steps)."""


def episode(reward: str, std: float, seed: int = 0) -> dict[str, float]:
    """One 1,000-step episode from the rest pose; returns its reward terms and metrics."""
    config = HandRegardConfig(reward=reward, detector_file=str(DETECTOR))
    behavior = PluginRegistry().create("hand_regard", config)
    env = BehaviorEnv(behavior, seed, None, training=True)
    try:
        env.set_stage({"active_arms": ["left", "right"], "random_pose": False})
        env.reset()
        rng = np.random.default_rng(seed)
        total, info = 0.0, None
        while info is None:
            action = np.clip(rng.normal(0.0, std, env.action_dim), -1, 1) if std else None
            _, r, _, _, info = env.step(np.zeros(env.action_dim) if action is None else action)
            total += float(r)
        return {"return": total, **info}
    finally:
        env.close()


SEEDS = (0, 1, 2)
"""Episodes per noisy setting (the noise and nothing else differs between them)."""


def main() -> None:
    rows = []
    settings = [("paper", std) for std in SPREADS] + [("bilateral", 0.0)]
    for reward, std in settings:
        for seed in SEEDS if std else SEEDS[:1]:  # zero action: one episode is every episode
            result = episode(reward, std, seed)
            rows.append({"reward": reward, "action_std": std, "seed": seed, **result})
            terms = {
                k.removeprefix("reward/"): round(v, 1)
                for k, v in result.items()
                if k.startswith("reward/")
            }
            print(
                f"reward={reward} std={std} seed={seed}: return {result['return']:.1f} {terms} "
                f"detector average {result['metrics/average']:.3f}",
                flush=True,
            )
    print(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
