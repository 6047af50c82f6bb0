"""Short recorded rollouts of the built-in behaviours, replayed bit for bit by
``tests/env/test_recorded_rollouts.py`` (issue #31: the reward-term pipeline must not change a
single reward).

Each rollout steps a :class:`~devlearn.env.DevVecEnv` in process (its envs share their batched
terms) with actions from a seeded generator and records, per decision: the rewards (N,), every
term's running per-episode sum (T, N) (``BehaviorEnv._sums``, weighted), the dones, each
observation's float64 sum per env, and a SHA-256 over every observation's bytes; plus the
finished episodes' summaries (``reward/*`` and ``metrics/*``).

Record (only when the behaviour is meant to change; the file is the reference):
``python tests/env/recorded_rollouts.py`` writes ``tests/data/rollouts/<name>.npz``.
"""

from __future__ import annotations

import hashlib
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data" / "rollouts"
HAND_REGARD_CHECKPOINT = ROOT / "results/hand_regard/i29/bilateral/policy.pt"
"""A published hand-regard run whose config and calibrated detector the rollout uses (its
detector sees hands, so the hand terms pay something; its reward is ``bilateral``: 4 terms)."""

ROLLOUTS: dict[str, dict[str, Any]] = {
    # batched terms, run-wide (shared) memory, 5 physics steps per decision, past an episode end
    "self_touch": {"num_envs": 3, "decisions": 230, "action_repeat": 5, "stage": "random"},
    # per-environment terms, facts once per decision (eyes and detector)
    "hand_regard": {"num_envs": 2, "decisions": 210, "action_repeat": 5, "stage": "eval"},
    # the example plugin: per-environment terms, a decision every physics step
    "hand_to_mouth": {"num_envs": 2, "decisions": 1050, "action_repeat": 1, "stage": "fixed"},
}


def build_behavior(name: str) -> Any:
    """The behaviour a rollout runs (hand regard: the published run's config and detector)."""
    from devlearn.plugins import PluginRegistry

    registry = PluginRegistry()
    if name != "hand_regard":
        return registry.create(name, None)
    from devlearn.config.run_config import from_dict
    from devlearn.training.checkpoint import load_checkpoint

    state = load_checkpoint(HAND_REGARD_CHECKPOINT)
    cfg = from_dict(state["config"], registry.behavior(name))
    # the stored detector as a file: env copies of the behaviour load it by path
    detector = Path(tempfile.mkdtemp()) / "hand_detector.json"
    detector.write_text(json.dumps(state["artifacts"]["hand_detector"]))
    cfg.behavior.detector_file = str(detector)
    return registry.create(name, cfg.behavior)


def rollout(name: str) -> dict[str, np.ndarray]:
    """Run one recorded rollout now; returns the arrays the recording holds."""
    import torch

    from devlearn.env import DevVecEnv

    spec = ROLLOUTS[name]
    behavior = build_behavior(name)
    n = spec["num_envs"]
    env = DevVecEnv(behavior, n, seed=11, workers=0, action_repeat=spec["action_repeat"])
    try:
        stage = {"random": {"random_pose": True}, "fixed": {"random_pose": False}}.get(
            spec["stage"], behavior.evaluation().stage
        )
        env.set_stage(stage)
        rng = np.random.default_rng(2026)
        names = sorted(env.observation_shapes)
        digest = hashlib.sha256()
        rewards, sums, dones, obs_sums, infos = [], [], [], [], []
        for _ in range(spec["decisions"]):
            actions = torch.from_numpy(rng.uniform(-1.2, 1.2, (n, env.num_actions)))
            obs, reward, done, extras = env.step(actions.float())
            rewards.append(reward.numpy().astype(np.float64))
            dones.append(done.numpy().astype(bool))
            sums.append([[e._sums[t] for e in env._envs] for t in env._envs[0]._sums])
            rows = []
            for key in names:
                array = np.ascontiguousarray(obs[key].numpy())
                digest.update(array.tobytes())
                rows.append(array.reshape(n, -1).astype(np.float64).sum(axis=1))
            obs_sums.append(rows)
            for info in extras["episode_infos"]:
                infos.append({k: v for k, v in info.items() if isinstance(v, float)})
        return {
            "rewards": np.array(rewards),
            "term_sums": np.array(sums),
            "term_names": np.array(list(env._envs[0]._sums)),
            "dones": np.array(dones),
            "obs_sums": np.array(obs_sums),
            "obs_names": np.array(names),
            "obs_sha256": np.array(digest.hexdigest()),
            "episode_infos": np.array(json.dumps(infos, sort_keys=True)),
        }
    finally:
        env.close()


def main(argv: list[str]) -> int:
    DATA.mkdir(parents=True, exist_ok=True)
    for name in argv or list(ROLLOUTS):
        recorded = rollout(name)
        np.savez_compressed(DATA / f"{name}.npz", **recorded)
        print(name, recorded["rewards"].shape, recorded["term_names"], recorded["obs_sha256"])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
