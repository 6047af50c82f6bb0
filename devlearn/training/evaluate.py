"""evaluate(): run a trained policy deterministically and collect the behaviour's metrics."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import numpy as np
import torch
from rsl_rl.utils import resolve_class, resolve_obs_groups
from tensordict import TensorDict
from tqdm import tqdm

from devlearn.env.behavior_env import BehaviorEnv
from devlearn.training.checkpoint import check_behavior, load_checkpoint
from devlearn.training.config import RunConfig, from_dict, to_rsl_rl
from devlearn.training.runner import quiet

VIDEO_FPS = 25
"""Frame rate of evaluation videos (every k-th control step is rendered to match it)."""


def _batch(obs: dict[str, np.ndarray]) -> TensorDict:
    """One env's observations as a batch of one (copied): groups (1, *shape)."""
    return TensorDict({k: torch.from_numpy(np.array(v)[None]) for k, v in obs.items()}, [1])


def load_actor(
    cfg: RunConfig,
    checkpoint: dict[str, Any],
    behavior,
    obs: dict[str, np.ndarray],
    action_dim: int,
):
    """Rebuild the checkpoint's policy network for ``behavior`` (eval mode, CPU)."""
    train_cfg = to_rsl_rl(cfg, behavior, list(obs))
    batch = _batch(obs)
    with quiet():  # rsl-rl prints the resolved sets
        groups = resolve_obs_groups(batch, train_cfg["obs_groups"], ["actor", "critic"])
    actor_class, actor_kwargs = resolve_class(train_cfg["actor"])
    actor = actor_class(batch, groups, "actor", action_dim, **actor_kwargs)
    actor.load_state_dict(checkpoint["actor_state_dict"])
    return actor.eval()


def evaluate(
    behavior_name: str,
    checkpoint: str | Path,
    episodes: int,
    registry,
    video: str | Path | None = None,
    seed: int = 0,
    out_dir: str | Path | None = None,
    infant_factory=None,
    progress: bool = True,
) -> dict[str, Any]:
    """Run ``episodes`` deterministic episodes (the policy's mean action) and summarise them.

    The env uses ``behavior.eval_stage()`` options and ``behavior.evaluator(training=False)``.

    Args:
        behavior_name: The behaviour the checkpoint must belong to.
        checkpoint: Path of a devlearn checkpoint.
        episodes: Number of full episodes.
        registry: Plugin registry.
        video: Write an MP4 of the first episode here (needs imageio-ffmpeg).
        seed: Seed of the env's initial poses.
        out_dir: Write ``eval.json`` and the evaluator's artifacts here.
        infant_factory: Infant builder (tests); default the real infant.
        progress: Show a progress bar (steps, episodes) on stderr.
    Returns:
        ``evaluator.summary()`` (JSON-serialisable) and ``checkpoint_env_steps``, the
        environment steps the checkpoint was trained for (x axis of ``devlearn curve`` on
        evaluation folders).
    Raises:
        UsageError: Missing, corrupt or foreign checkpoint.
    """
    state = load_checkpoint(checkpoint)
    check_behavior(state, checkpoint, behavior_name)
    behavior_cls = registry.behavior(behavior_name)
    cfg = from_dict(state["config"], behavior_cls)
    behavior = registry.create(behavior_name, cfg.behavior)
    torch.manual_seed(seed)
    threads = torch.get_num_threads()
    # A batch of one gains nothing from more threads, and several threads on a core that
    # another program uses are many times slower (measured: a 64x64 eye CNN 85 ms vs 11 ms).
    torch.set_num_threads(1)
    env = BehaviorEnv(behavior, seed, infant_factory, training=False)
    writer = None
    try:
        env.set_stage(behavior.eval_stage())
        obs = env.reset()
        actor = load_actor(cfg, state, behavior, obs, env.action_dim)
        if video is not None:
            import imageio.v2 as imageio

            Path(video).parent.mkdir(parents=True, exist_ok=True)
            writer = imageio.get_writer(str(video), fps=VIDEO_FPS, macro_block_size=1)
            stride = max(1, round(1.0 / (env.step_dt * VIDEO_FPS)))
        bar = tqdm(
            total=episodes * env.episode_steps,
            unit="step",
            disable=not progress,
            desc=f"eval {behavior_name}",
            file=sys.stderr,
            dynamic_ncols=True,
        )
        for episode in range(episodes):
            bar.set_postfix(episode=f"{episode + 1}/{episodes}")
            for t in range(env.episode_steps):
                bar.update()
                if writer is not None and episode == 0 and t % stride == 0:
                    writer.append_data(env.behavior.render_frame(env.infant))
                with torch.inference_mode():
                    action = actor(_batch(obs))[0].numpy()
                obs, _, _, _, _ = env.step(action)
        bar.close()
        summary = env.evaluator.summary()
        summary["checkpoint_env_steps"] = int(state.get("env_steps", 0))
        if out_dir is not None:
            out = Path(out_dir)
            out.mkdir(parents=True, exist_ok=True)
            (out / "eval.json").write_text(json.dumps(summary, indent=2, default=float) + "\n")
            env.evaluator.write_artifacts(out)
        return summary
    finally:
        if writer is not None:
            writer.close()
        env.close()
        torch.set_num_threads(threads)
