"""Runs for tests: a behaviour's run config resolved as ``devlearn run`` resolves it, and the
few entry points into the training and evaluation floors a plugin's tests need (train a tiny
run, open its checkpoint, rebuild a policy, evaluate it, run a command), so that those tests
import only ``devlearn``, ``devlearn.api`` and ``devlearn.testing``.

Each is a thin door onto the core's one way of doing the thing (``resolve_config``,
``train``, the checkpoint format, ``evaluate``, the CLI): when the core changes, this module
changes, not every plugin's tests. torch and rsl-rl load when a function needs them.
Saved configs are read and written as runs read and write them: :func:`saved_config` (the
dict a run saves), :func:`load_saved_config` (a saved dict, keys it lacks taking the values it
was trained with, or a run folder's ``config.json``), :func:`config_round_trip`.
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from devlearn.config.resolve import RunRequest, load_run_config, resolve_config
from devlearn.config.run_config import RunConfig, from_dict, to_dict
from devlearn.testing.fixtures import registry_for

if TYPE_CHECKING:
    import numpy as np

    from devlearn.api.behavior import Behavior
    from devlearn.env.behavior_env import InfantFactory
    from devlearn.evaluation.scripted_policy import ScriptedPolicy
    from devlearn.plugins import PluginRegistry
    from devlearn.training.networks import MultiSenseModel
    from devlearn.training.train import TrainResult

__all__ = [
    "CommandResult",
    "config_round_trip",
    "evaluate_policy",
    "load_checkpoint",
    "load_saved_config",
    "open_scripted_policy",
    "policy_file",
    "policy_network",
    "run_command",
    "run_config",
    "save_checkpoint",
    "saved_config",
    "train",
]


def run_config(
    behavior: type[Behavior],
    overrides: Sequence[str] = (),
    preset: str | None = "",
    *,
    registry: PluginRegistry | None = None,
    **top: Any,
) -> RunConfig:
    """The config ``devlearn run NAME --preset PRESET --set OVERRIDES`` (plus top-level
    options ``top``: ``total_steps``, ``num_envs``, ``workers``, ``seed``, ``out_dir``...)
    would train ``behavior`` with: resolved and checked exactly as the run's
    (:func:`devlearn.config.resolve.resolve_config`).

    Args:
        behavior: The behaviour class.
        overrides: ``--set`` items, e.g. ``["behavior.max_std=0.5"]``.
        preset: One of the behaviour's ``presets``; empty: none.
        registry: Where the behaviour is registered (default: a registry of ``behavior``
            alone, :func:`~devlearn.testing.fixtures.registry_for`).
        top: Top-level fields of the run config; None values are skipped.
    Raises:
        UsageError: What ``devlearn run`` refuses, in its words.
    """
    out_dir = str(top.pop("out_dir", "") or "")
    request = RunRequest(behavior.name, list(overrides), preset or "", top, out_dir=out_dir)
    return resolve_config(request, registry or registry_for(behavior))


def saved_config(cfg: RunConfig) -> dict[str, Any]:
    """``cfg`` as a run saves it (its ``config.json``, a checkpoint's config): plain data."""
    return to_dict(cfg)


def load_saved_config(
    saved: dict[str, Any] | str | Path,
    behavior: type[Behavior] | PluginRegistry,
    base: RunConfig | None = None,
) -> RunConfig:
    """A saved config read as runs read it: a dict (keys it lacks take the values the run was
    trained with, or ``base``'s) or a run folder (its ``config.json``).

    Args:
        saved: The saved dict, or a run folder.
        behavior: The behaviour's class (for a folder: or a registry that has it).
        base: For a dict: the config whose values the keys it lacks take.
    """
    if isinstance(saved, dict):
        if isinstance(behavior, type):
            return from_dict(saved, behavior, base)
        return from_dict(saved, behavior.behavior(str(saved.get("behavior_name", ""))), base)
    registry = registry_for(behavior) if isinstance(behavior, type) else behavior
    return load_run_config(Path(saved), registry)


def config_round_trip(cfg: RunConfig, behavior: type[Behavior]) -> RunConfig:
    """``cfg`` saved and read back as a run saves and reads it."""
    return from_dict(to_dict(cfg), behavior)


def train(cfg: RunConfig | None, registry: PluginRegistry, **options: Any) -> TrainResult:
    """Train as ``devlearn run`` trains (:func:`devlearn.training.train.train`: ``resume``,
    ``start_from``, ``infant_factory``, ``progress``, ``force``...); return where and how far
    the run got (``run_dir``, ``env_steps``, ``iterations``, ``last`` metrics row)."""
    from devlearn.training.train import train as train_run

    return train_run(cfg, registry, **options)


def load_checkpoint(path: str | Path) -> dict[str, Any]:
    """A checkpoint or policy file's state, loaded as ``devlearn eval`` loads it (as data,
    ``weights_only``): ``config``, ``env_steps``, ``actor_state_dict``, ``env`` (a training
    checkpoint's reward-term states)...

    Raises:
        UsageError: A missing, corrupt or foreign file.
    """
    from devlearn.training.checkpoint import load_checkpoint as load

    return load(path)


def save_checkpoint(state: dict[str, Any], path: str | Path) -> None:
    """Write a checkpoint or policy file's ``state`` to ``path`` as runs write theirs
    (atomically: a reader sees the old file or the new, never half of one)."""
    from devlearn.training.checkpoint import save_atomic

    save_atomic(state, Path(path))


def policy_network(
    cfg: RunConfig,
    behavior: Behavior,
    obs: dict[str, np.ndarray],
    action_dim: int,
    weights: dict[str, Any] | None = None,
) -> MultiSenseModel:
    """The policy network a run of ``behavior`` under ``cfg`` trains (eval mode, CPU), built
    for one observation ``obs`` (name -> unbatched array); with ``weights`` (an
    ``actor_state_dict``) loaded, checked to fit as ``devlearn eval`` checks them.

    Raises:
        UsageError: ``weights`` do not fit the network ``cfg`` builds.
    """
    from devlearn.training.checkpoint import build_actor, load_actor

    if weights is None:
        return build_actor(cfg, behavior, obs, action_dim)
    return load_actor(cfg, {"actor_state_dict": weights}, behavior, obs, action_dim)


def policy_file(
    config: dict[str, Any],
    behavior: Behavior,
    actor_state: dict[str, Any],
    env_steps: int = 0,
) -> dict[str, Any]:
    """The state of a policy file (what ``devlearn slim`` writes, what ``devlearn eval`` reads)
    for a run config saved as data (``config``, e.g. an old run's ``config.json``), the
    policy weights ``actor_state`` and ``behavior``'s ``policy_artifacts()``; write it with
    :func:`save_checkpoint`."""
    from devlearn.training.checkpoint import FORMAT

    return {
        "format": FORMAT,
        "behavior": behavior.name,
        "config": config,
        "policy_only": True,
        "iteration": 0,
        "env_steps": env_steps,
        "actor_state_dict": actor_state,
        "artifacts": behavior.artifacts().policy_artifacts(),
    }


def evaluate_policy(
    behavior: str,
    checkpoint: str | Path | None,
    episodes: int,
    registry: PluginRegistry,
    *,
    infant_factory: InfantFactory | None = None,
    progress: bool = True,
    **request: Any,
) -> dict[str, Any]:
    """Evaluate as ``devlearn eval`` does: ``episodes`` episodes of ``checkpoint`` (a
    checkpoint, policy file or run folder; None with ``policy="zero"`` or ``"random"``: a
    baseline) under the behaviour's evaluation protocol; return the summary ``eval.json``
    holds. ``request``: the other fields of
    :class:`~devlearn.evaluation.evaluate.EvalRequest` (``seed``, ``out_dir``, ``policy``,
    ``start``, ``overrides``, ``envs``, ``workers``...); ``infant_factory`` and ``progress``
    as :class:`~devlearn.evaluation.evaluate.Evaluation` takes them."""
    from devlearn.evaluation.evaluate import EvalRequest, Evaluation

    asked = EvalRequest(behavior=behavior, checkpoint=checkpoint, episodes=episodes, **request)
    return Evaluation(asked, registry, infant_factory, progress).run()


def open_scripted_policy(
    path: str | Path, registry: PluginRegistry, behavior: str = ""
) -> ScriptedPolicy:
    """Another learner's policy file (``devlearn.gym.save_policy``: TorchScript plus its config)
    as ``devlearn eval`` opens it; ``.act(obs)`` is its deterministic action for one
    observation (name -> array).

    Raises:
        UsageError: Unreadable, not a scripted policy, or trained for another behaviour.
    """
    from devlearn.evaluation.scripted_policy import ScriptedPolicy

    return ScriptedPolicy.open(path, registry, behavior)


@dataclass
class CommandResult:
    """What a ``devlearn`` command did: its exit code (2: refused, with a one-line message)
    and what it printed."""

    code: int
    out: str
    err: str


def run_command(*args: str, timeout: float = 600) -> CommandResult:
    """Run ``devlearn ARGS...`` as a user runs it, in a new process (this Python, this
    environment: ``PYTHONPATH``, ``DEVLEARN_DISABLE_PLUGINS``...), and return its exit code
    and output."""
    done = subprocess.run(
        [sys.executable, "-m", "devlearn.cli", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    return CommandResult(done.returncode, done.stdout, done.stderr)
