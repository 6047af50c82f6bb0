"""Policy files: the part of a training checkpoint that evaluation needs, sized for sharing."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from devlearn.evaluation.export import actor_on_one_observation
from devlearn.training.checkpoint import FORMAT, Checkpoint, save_atomic

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry

KEPT = ("behavior", "config", "iteration", "env_steps", "age_months", "actor_state_dict")
"""Training-checkpoint keys a policy file keeps; the critic, optimiser, curriculum, env and rng
states (what only resuming needs) are left out."""


def slim_checkpoint(
    source: str | Path, target: str | Path, registry: PluginRegistry
) -> dict[str, Any]:
    """Write a policy file: policy weights, config, training steps and the behaviour's
    :meth:`~devlearn.Behavior.policy_artifacts` (e.g. hand_regard's detector calibration).

    The result evaluates anywhere (``devlearn eval --checkpoint``) but cannot resume training;
    it holds only tensors, dicts, lists, numbers and strings (loads with ``weights_only``).

    Args:
        source: A training checkpoint (or a policy file: then it is rewritten as one).
        target: Where to write it (e.g. ``RUN/policy.pt``); may not be ``source``.
        registry: Plugin registry (the behaviour gathers its artifacts).
    Returns:
        The state written.
    Raises:
        UsageError: Unreadable checkpoint, or something its evaluation needs is missing.
    """
    from devlearn.api.errors import UsageError

    source, target = Path(source), Path(target)
    if target.resolve() == source.resolve():
        raise UsageError(f"slim {source}: --out must differ from the checkpoint itself")
    opened = Checkpoint.open(source, registry)
    state = opened.state
    actor_on_one_observation(opened)  # a file eval would refuse is not written
    slim = {"format": FORMAT, "policy_only": True}
    slim.update({k: state[k] for k in KEPT if k in state})
    slim["artifacts"] = opened.behavior().artifacts().policy_artifacts()
    target.parent.mkdir(parents=True, exist_ok=True)
    save_atomic(slim, target)
    return slim
