"""Scripted policy files: a policy trained by another learner (through :mod:`devlearn.gym`) as
TorchScript plus what ``devlearn eval`` needs to evaluate it under the same protocol."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
import torch
import torch.nn as nn

from devlearn.api.errors import UsageError
from devlearn.api.json_files import parse_json
from devlearn.config.growth import start_age
from devlearn.config.run_config import from_dict
from devlearn.evaluation.policy import Actions, Observations, batch_of_one, batch_rows
from devlearn.training.checkpoint import SCRIPTED_METADATA, SavedPolicy

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry

SCRIPTED_FORMAT = "devlearn-scripted-policy/1"
"""The ``format`` of a scripted policy's metadata."""
METADATA = SCRIPTED_METADATA
"""The TorchScript extra file holding the metadata (``torch.jit.load(_extra_files=...)``)."""


class ObservationOrder(nn.Module):
    """A policy that takes one tensor per observation group, in :attr:`names` order (what a
    scripted policy file holds, and ``devlearn export --format torchscript`` writes).

    Args:
        policy: ``policy(*observations)`` -> (N, action_dim) actions in [-1, 1], each
            observation (N, *shape) in its group's dtype (uint8 images, float32 otherwise).
        names: The observation groups, in the order the policy takes them.
    """

    def __init__(self, policy: nn.Module, names: list[str]) -> None:
        super().__init__()
        self.policy = policy
        self.names = list(names)

    def forward(self, *observations: torch.Tensor) -> torch.Tensor:
        return self.policy(*observations)


def save_scripted_policy(
    policy: ObservationOrder,
    observation: dict[str, np.ndarray],
    path: str | Path,
    *,
    behavior: str,
    config: dict[str, Any],
    env_steps: int,
    learner: str,
    artifacts: dict[str, Any] | None = None,
) -> Path:
    """Trace ``policy`` on ``observation`` and write it as TorchScript with its metadata.

    Args:
        policy: The policy, its inputs in ``policy.names`` order (deterministic: the action
            the evaluation protocol takes, a trained Gaussian's mean).
        observation: One env's observation (name -> unbatched array) to trace it on.
        path: The file to write (e.g. ``OUT/policy.pt``).
        behavior: The behaviour it was trained on.
        config: The resolved run config of its environments (``to_dict``), which the
            evaluation builds its env from (decision rate, the behaviour's options).
        env_steps: Physics steps it trained for, summed over its envs (devlearn's count).
        learner: Who trained it, e.g. ``sb3_ppo`` (``devlearn report`` tells learners apart).
        artifacts: The behaviour's ``policy_artifacts()`` (hand regard's detector).
    Returns:
        The path written.
    Raises:
        UsageError: An unwritable path (:func:`~devlearn.evaluation.export.export_policy`).
    """
    from devlearn.evaluation.export import export_policy

    metadata = {
        "format": SCRIPTED_FORMAT,
        "behavior": behavior,
        "observations": [
            {"name": n, "shape": list(np.shape(observation[n])), "dtype": str(observation[n].dtype)}
            for n in policy.names
        ],
        "config": config,
        "env_steps": int(env_steps),
        "learner": learner,
        "artifacts": artifacts or {},
    }
    extra = {METADATA: json.dumps(metadata)}
    return export_policy(policy, observation, "torchscript", Path(path), extra_files=extra)


@dataclass
class ScriptedPolicy(SavedPolicy):
    """An opened scripted policy file, read as ``devlearn eval`` reads a checkpoint
    (:class:`~devlearn.training.checkpoint.Checkpoint`): its config, its behaviour (with the
    artifacts it carries) and a deterministic actor; a
    :class:`~devlearn.evaluation.policy.Policy`. Open with :meth:`open`.

    Loading it runs TorchScript (a restricted program of tensor operations, no Python
    pickle): open only files you trust, as with any model file that holds code.
    """

    module: Any = field(default=None, repr=False)
    """The TorchScript policy."""
    name: ClassVar[str] = "checkpoint"

    @classmethod
    def open(
        cls, path: str | Path, registry: PluginRegistry, behavior_name: str = ""
    ) -> ScriptedPolicy:
        """Load ``path`` and rebuild its config.

        Raises:
            UsageError: Unreadable, not ours, or trained for another (or no installed)
                behaviour.
        """
        from devlearn.evaluation.export import known_exporter_noise_silenced

        path = Path(path)
        extra = {METADATA: ""}
        try:
            with known_exporter_noise_silenced():
                module = torch.jit.load(str(path), map_location="cpu", _extra_files=extra)
            state = parse_json(extra[METADATA], f"{path}'s metadata")
        except (RuntimeError, ValueError, UsageError) as exc:
            reason = " ".join(str(exc).split())[:160]
            raise UsageError(f"scripted policy {path} is unreadable: {reason}") from None
        if not isinstance(state, dict) or state.get("format") != SCRIPTED_FORMAT:
            raise UsageError(f"{path} is not a devlearn scripted policy ({SCRIPTED_FORMAT})")
        if behavior_name and state.get("behavior") != behavior_name:
            raise UsageError(
                f"scripted policy {path} was trained for '{state.get('behavior')}', "
                f"not '{behavior_name}'"
            )
        config = from_dict(state["config"], registry.behavior(state["behavior"]))
        return cls(path, state, config, registry, module=module.eval())

    @property
    def age_months(self) -> float | None:
        """The body's age it last trained at: its config's growth schedule at its steps, else
        ``infant.age_months`` (None: the default body)."""
        steps = self.env_steps or 0
        stage = self.behavior().curriculum().stage_index_at(steps)
        return start_age(self.config, steps, stage)

    @property
    def learner(self) -> str:
        """Who trained it (``sb3_ppo``, ``sb3_sac``...)."""
        return str(self.state.get("learner", ""))

    def __getstate__(self) -> dict[str, Any]:
        """Pickled (to an env worker of ``devlearn eval``) as its file, config and metadata:
        the TorchScript program is loaded again on the other side; the registry and the
        behaviour stay here."""
        return {"path": self.path, "state": self.state, "config": self.config}

    def __setstate__(self, saved: dict[str, Any]) -> None:
        from devlearn.evaluation.export import known_exporter_noise_silenced

        self.path, self.state, self.config = saved["path"], saved["state"], saved["config"]
        self.registry, self._behavior = None, None  # type: ignore[assignment]
        with known_exporter_noise_silenced():
            self.module = torch.jit.load(str(self.path), map_location="cpu").eval()

    def actions(self, obs: Observations, action_dim: int, seed: int, action: str) -> Actions:
        """Its deterministic action (nothing to draw, nothing to skip).

        Raises:
            UsageError: ``sample`` or ``expected_clipped``: it has no distribution.
        """
        if action != "mean":
            raise sampling_refused(self.path, action)
        return ScriptedActions(self, batch_rows(obs), action_dim)

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """The policy's action for one env's observation: (action_dim,) float64.

        Raises:
            UsageError: The observation lacks a group the policy takes, or has another shape.
        """
        return self.act_batch(batch_of_one(obs))[0]

    def act_batch(self, obs: Observations) -> np.ndarray:
        """The policy's actions for a batch of observations ((N, *shape) per group):
        (N, action_dim) float64.

        Raises:
            UsageError: The observations lack a group the policy takes, or have another shape.
        """
        inputs = []
        for spec in self.state["observations"]:
            name, shape = spec["name"], tuple(spec["shape"])
            value = obs.get(name)
            if value is None or tuple(np.shape(value))[1:] != shape:
                got = None if value is None else tuple(np.shape(value))[1:]
                raise UsageError(
                    f"scripted policy {self.path} takes observation '{name}' {shape}; the "
                    f"env gives {got} (a config other than the one it trained with?)"
                )
            inputs.append(torch.from_numpy(np.asarray(value, dtype=spec["dtype"])))
        with torch.inference_mode():
            return self.module(*inputs).numpy().astype(np.float64)


def sampling_refused(path: str | Path, action: str = "sample") -> UsageError:
    """The error for ``--action sample`` (or ``expected_clipped``) with the scripted policy
    ``path``."""
    return UsageError(
        f"--action {action}: a scripted policy ({path}) gives one deterministic action; "
        f"{action} needs a devlearn checkpoint's distribution (valid here: mean)"
    )


class ScriptedActions(Actions):
    """A scripted policy's deterministic actions (:class:`ScriptedPolicy`): nothing to draw,
    nothing to skip; they travel to env workers as the policy's file, loaded again there."""

    def __init__(self, scripted: ScriptedPolicy, rows: int, action_dim: int) -> None:
        super().__init__(rows, action_dim)
        self.scripted = scripted

    def act(self, obs: Observations) -> np.ndarray:
        return self.scripted.act_batch(obs)

    def for_slot(self) -> Actions:
        return self
