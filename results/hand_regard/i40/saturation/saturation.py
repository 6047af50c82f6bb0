"""Why issue #40's seed 1 falls short with its mean action (results/hand_regard/i40/README.md):
each seed's policy played from BabyBench's start (the evaluation stage, the env's generator at
eval seed 0, as `devlearn eval` seeds its one env) with two deterministic actions:

- ``mean``: the Gaussian's mean clipped to [-1, 1], as `devlearn eval` applies it;
- ``expected_clipped``: E[clip(mu + sigma * eps, -1, 1)], the action the env applies on average
  when the policy samples, as in training.

Per seed and action: the `pixels` average of each episode (ground truth, the protocol's
headline measure beside the detector's) and how far the mean lies past the bounds (the share of
action components with |mu| > 1, their mean excess, and how many components are past a bound on
most decisions). If the mean action fails because it sits past the bounds where training's
clipped samples did not, the expected clipped action recovers the sampled policy's score.

    python results/hand_regard/i40/saturation/saturation.py RUNS_DIR --episodes 10 --out FILE.json
(RUNS_DIR: both_hands.sh's OUT/cnn/runs, each seed's checkpoint_latest.pt.)
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import torch

from devlearn.api.stats import mean_ci
from devlearn.env import BehaviorEnv
from devlearn.evaluation.episodes import prepare_env
from devlearn.evaluation.evaluate import EvalRequest, evaluation_conditions, open_subject
from devlearn.plugins import PluginRegistry
from devlearn.training.checkpoint import observation_batch


def expected_clipped(mu: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """E[clip(X, -1, 1)] for X ~ N(mu, sigma), per component."""
    from scipy.stats import norm

    a, b = (-1.0 - mu) / sigma, (1.0 - mu) / sigma
    inside = mu * (norm.cdf(b) - norm.cdf(a)) + sigma * (norm.pdf(a) - norm.pdf(b))
    return -norm.cdf(a) + inside + norm.sf(b)


def play(path: Path, action: str, episodes: int, registry: PluginRegistry) -> dict:
    # the setting `devlearn eval --checkpoint PATH --seed 0 --envs 1 --workers 0` plays in
    request = EvalRequest(behavior="hand_regard", checkpoint=path, episodes=episodes)
    subject = open_subject(request, registry)
    conditions = evaluation_conditions(request, subject)
    repeat = subject.config.env.action_repeat
    env = BehaviorEnv(subject.behavior, request.seed, training=False, action_repeat=repeat)
    try:
        prepare_env(env, conditions.stage, conditions.infant_start)
        env.rng = np.random.default_rng(request.seed)
        obs = env.reset()
        actor = subject.policy.actor(obs, env.action_dim)
        distribution = actor.distribution
        sigma = distribution.current_std().detach().numpy().astype(np.float64)
        mus, pixels = [], []
        while len(pixels) < episodes:
            with torch.inference_mode():
                batch = observation_batch(obs)
                raw = actor.mlp(actor.encode({k: batch[k] for k in actor.obs_groups}))
                mean_action = distribution.deterministic_output(raw)[0].numpy()
            mu = raw[0].numpy().astype(np.float64)
            mus.append(mu)
            act = mean_action if action == "mean" else expected_clipped(mu, sigma)
            obs, *_, info = env.step(np.asarray(act, dtype=np.float32))
            if info is not None and "metrics/average_pixels" in info:
                pixels.append(float(info["metrics/average_pixels"]))
        m = np.abs(np.stack(mus))
        past = m > 1.0
        spread = mean_ci(pixels)
        return {
            "pixels_per_episode": pixels,
            "pixels_mean": spread["mean"],
            "pixels_ci95": [spread["ci_low"], spread["ci_high"]],
            "share_of_mean_past_bounds": float(past.mean()),
            "mean_excess_where_past": float((m[past] - 1.0).mean()) if past.any() else 0.0,
            "components_past_on_most_decisions": int((past.mean(axis=0) > 0.5).sum()),
            "action_dim": int(m.shape[1]),
            "sigma_mean": float(sigma.mean()),
        }
    finally:
        env.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", type=Path)
    parser.add_argument("--episodes", type=int, default=10)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    torch.set_num_threads(1)
    registry = PluginRegistry()
    found: dict = {}
    for run in sorted(args.runs.glob("seed=*")):
        for action in ("mean", "expected_clipped"):
            r = play(run / "checkpoint_latest.pt", action, args.episodes, registry)
            found.setdefault(run.name, {})[action] = r
            print(
                run.name,
                action,
                round(r["pixels_mean"], 3),
                r["pixels_ci95"],
                "past bounds",
                round(r["share_of_mean_past_bounds"], 3),
                flush=True,
            )
    args.out.write_text(json.dumps(found, indent=1) + "\n")


if __name__ == "__main__":
    main()
