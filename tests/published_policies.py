"""What every published policy file does, recorded before issue #31's reward-term pipeline and
replayed by ``tests/test_published_replay.py``: the actor's actions on a fixed batch of
observations, and one deterministic evaluation episode (the mean action, the behaviour's
evaluation stage, seed 0): every decision's reward and action (a SHA-256 of all, the first
20 as numbers), and the episode's ``reward/*`` and ``metrics/*``. The config is read as a run
reads it (old ``weight_*`` fields and all), so the reward terms are the ones the run was
trained with.

Record (only when a change is meant to alter them): ``python tests/published_policies.py``
writes ``tests/data/published/<run>.npz``.
"""

from __future__ import annotations

import hashlib
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from cpu_kind import to_record  # noqa: E402
DATA = ROOT / "tests" / "data" / "published"


def published_policies() -> list[Path]:
    """The tracked ``policy.pt`` files under ``results/``."""
    try:
        out = subprocess.run(
            ["git", "ls-files", "-z", "results"], cwd=ROOT, capture_output=True, check=True
        ).stdout
    except (OSError, subprocess.SubprocessError):
        return []
    return sorted(ROOT / p for p in out.decode().split("\0") if p.endswith(".pt"))


def slug(path: Path) -> str:
    """``self_touch__i20__two_stage_s1__run``: a file name for a policy's recording."""
    parts = path.relative_to(ROOT / "results").parent.parts
    return "__".join(parts).replace("=", "-").replace(",", "_")


def replay(path: Path) -> dict[str, Any]:
    """Load ``path`` as ``devlearn eval`` does and record what its policy does."""
    import torch
    from tensordict import TensorDict

    from devlearn.api.behavior import evaluation_stage
    from devlearn.config.run_config import from_dict
    from devlearn.env.behavior_env import BehaviorEnv
    from devlearn.plugins import PluginRegistry
    from devlearn.training.checkpoint import load_actor, load_checkpoint
    from devlearn.training.checkpoint import observation_batch as _batch

    torch.set_num_threads(1)
    state = load_checkpoint(path)
    registry = PluginRegistry()
    cfg = from_dict(state["config"], registry.behavior(state["behavior"]))
    behavior = registry.create(state["behavior"], cfg.behavior)
    behavior.artifacts().load_policy_artifacts(dict(state.get("artifacts") or {}), path.parent)
    repeat = cfg.env.action_repeat
    env = BehaviorEnv(behavior, 0, training=False, action_repeat=repeat)
    try:
        env.set_stage(evaluation_stage(behavior, int(state.get("env_steps", 0))))
        obs = env.reset()
        actor = load_actor(cfg, state, behavior, obs, env.action_dim)
        rng = np.random.default_rng(7)
        batch = {}
        for key, value in obs.items():
            shape = (8, *np.shape(value))
            if np.asarray(value).dtype == np.uint8:
                batch[key] = torch.from_numpy(rng.integers(0, 256, shape, dtype=np.uint8))
            else:
                batch[key] = torch.from_numpy(rng.normal(0, 1, shape).astype(np.float32))
        with torch.inference_mode():
            batch_actions = actor(TensorDict(batch, [8])).numpy().astype(np.float64)
        rewards, actions, info = [], [], None
        for _ in range(env.episode_steps // repeat):
            with torch.inference_mode():
                action = actor(_batch(obs))[0].numpy()
            actions.append(action.astype(np.float64))
            obs, reward, done, _, episode = env.step(action)
            rewards.append(reward)
            if done:
                info = {k: v for k, v in (episode or {}).items() if isinstance(v, float)}
        return {
            "batch_actions": batch_actions,
            "first_actions": np.array(actions[:20]),
            "actions_sha256": np.array(hashlib.sha256(np.array(actions).tobytes()).hexdigest()),
            "rewards": np.array(rewards, dtype=np.float64),
            "episode_info": np.array(json.dumps(info, sort_keys=True)),
        }
    finally:
        env.close()


def main(argv: list[str]) -> int:
    DATA.mkdir(parents=True, exist_ok=True)
    for path in published_policies():
        if argv and slug(path) not in argv:
            continue
        recorded = replay(path)
        np.savez_compressed(to_record(DATA / f"{slug(path)}.npz"), **recorded)
        print(slug(path), recorded["rewards"].sum(), recorded["episode_info"])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
