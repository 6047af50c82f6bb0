"""Why the mean action fails where sampled actions reach (issue #54 item 3): a stall.

Plays a hand_to_mouth policy from random poses (the curriculum's second stage, as ``devlearn
eval``'s stage start) with its mean action, or with Gaussian noise of a given spread added,
and reports per episode whether the hand reached the mouth and how fast the joints moved over
the last 40 decisions (the last second). A failed episode whose joints are near still is a
stall: a posture the deterministic closed loop holds and never leaves.

    python -m devlearn_hand_to_mouth.stalls CHECKPOINT --episodes 30 --noise 0
    python -m devlearn_hand_to_mouth.stalls CHECKPOINT --episodes 30 --noise 0.3

The starts are the Play verb's environments seeded 200, 201... (not ``devlearn eval``'s
seed-0 starts); the noise is drawn from numpy's generator seeded 0.
"""

from __future__ import annotations

import argparse
import json
from typing import Any

import numpy as np
import torch

from devlearn.testing import Play, load_checkpoint, load_saved_config, policy_network, registry_for
from devlearn_hand_to_mouth.behavior import HandToMouth

STALL_SPEED = 0.05
"""Mean absolute joint velocity (rad/s) over the last second below which a failed episode is a
stall (``devlearn eval``'s ``ends_still`` threshold)."""
LAST_DECISIONS = 40
"""The decisions averaged: one simulated second at hand_to_mouth's 5 physics steps each."""


def stalls(checkpoint: str, episodes: int, noise: float, first_seed: int = 200) -> dict[str, Any]:
    """Play ``episodes`` random-pose episodes of ``checkpoint`` together (one env each) with the
    mean action plus N(0, ``noise``); return the reach share, the failed episodes' and the
    successful ones' joint speed over the last second, and how many failed episodes stalled."""
    registry = registry_for(HandToMouth)
    state = load_checkpoint(checkpoint)
    cfg = load_saved_config(state["config"], registry)
    behavior = registry.create("hand_to_mouth", cfg.behavior)
    rng = np.random.default_rng(0)
    seeds = list(range(first_seed, first_seed + episodes))
    with Play(behavior, seeds=seeds, training=False, action_repeat=cfg.env.action_repeat) as play:
        play.set_stage({"random_pose": True})
        obs = play.reset()
        actor = policy_network(cfg, behavior, obs[0], play.action_dim, state["actor_state_dict"])
        decisions = play.episode_steps // cfg.env.action_repeat
        speed = np.zeros((decisions, episodes))
        ends: list[dict[str, Any]] = [{} for _ in seeds]
        for t in range(decisions):
            batch = {k: torch.as_tensor(np.stack([o[k] for o in obs])).float() for k in obs[0]}
            with torch.no_grad():
                actions = actor(batch).numpy()
            steps = play.step(actions + rng.normal(size=actions.shape) * noise)
            obs = [s[0] for s in steps]
            speed[t] = [np.abs(infant.data.qvel).mean() for infant in play.infants]
            for i, (_, _, done, _, info) in enumerate(steps):
                if done:
                    ends[i] = info or {}
    reached = np.array([float(e.get("metrics/reached", np.nan)) for e in ends])
    # the last decision's body is the next episode's start: the 40 before it
    late = speed[-LAST_DECISIONS - 1 : -1].mean(axis=0)
    failed = late[reached == 0]
    succeeded = late[reached == 1]
    return {
        "checkpoint": checkpoint,
        "noise": noise,
        "episodes": episodes,
        "reached": float(np.nanmean(reached)),
        "failed": int(len(failed)),
        "failed_stalled": int((failed < STALL_SPEED).sum()),
        "failed_end_speed": [round(float(v), 4) for v in failed],
        "reached_end_speed_mean": float(succeeded.mean()) if len(succeeded) else None,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("checkpoint")
    parser.add_argument("--episodes", type=int, default=30)
    parser.add_argument("--noise", type=float, default=0.0, help="spread of the added noise")
    args = parser.parse_args(argv)
    print(json.dumps(stalls(args.checkpoint, args.episodes, args.noise), indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
