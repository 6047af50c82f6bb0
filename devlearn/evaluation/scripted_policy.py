"""Scripted policy files: a policy trained by another learner (through :mod:`devlearn.gym`) as
TorchScript plus what ``devlearn eval`` needs to evaluate it under the same protocol."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import torch
import torch.nn as nn

from devlearn.api.errors import UsageError
from devlearn.api.json_files import parse_json
from devlearn.config.growth import start_age
from devlearn.config.run_config import from_dict
from devlearn.training.checkpoint import SCRIPTED_METADATA, behavior_with_artifacts

if TYPE_CHECKING:
    from devlearn.api.behavior import Behavior
    from devlearn.config.run_config import RunConfig
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
class ScriptedPolicy:
    """An opened scripted policy file, read as ``devlearn eval`` reads a checkpoint
    (:class:`~devlearn.training.checkpoint.Checkpoint`): its config, its behaviour (with the
    artifacts it carries) and a deterministic actor. Open with :meth:`open`.

    Loading it runs TorchScript (a restricted program of tensor operations, no Python
    pickle): open only files you trust, as with any model file that holds code.
    """

    path: Path
    """The file."""
    state: dict[str, Any]
    """Its metadata (``behavior``, ``observations``, ``config``, ``env_steps``, ``learner``)."""
    config: RunConfig
    """The run config of the environments it trained on."""
    registry: PluginRegistry
    """The registry its behaviour is built from."""
    module: Any = field(repr=False)
    """The TorchScript policy."""
    _behavior: Behavior | None = field(default=None, repr=False)

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
        return cls(path, state, config, registry, module.eval())

    @property
    def behavior_name(self) -> str:
        """The behaviour it was trained for."""
        return str(self.state["behavior"])

    @property
    def env_steps(self) -> int:
        """Physics steps it was trained for (0 where it does not say)."""
        return int(self.state.get("env_steps", 0))

    @property
    def age_months(self) -> float | None:
        """The body's age it last trained at: its config's growth schedule at its steps, else
        ``infant.age_months`` (None: the default body)."""
        stage = self.behavior().curriculum().stage_index_at(self.env_steps)
        return start_age(self.config, self.env_steps, stage)

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

    def behavior(self) -> Behavior:
        """Its behaviour under its config, with the artifacts the file carries; built once."""
        if self._behavior is None:
            self._behavior = behavior_with_artifacts(
                self.registry, self.config, self.state, self.path
            )
        return self._behavior

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """The policy's action for one env's observation: (action_dim,) float64.

        Raises:
            UsageError: The observation lacks a group the policy takes, or has another shape.
        """
        inputs = []
        for spec in self.state["observations"]:
            name, shape = spec["name"], tuple(spec["shape"])
            value = obs.get(name)
            if value is None or tuple(np.shape(value)) != shape:
                got = None if value is None else tuple(np.shape(value))
                raise UsageError(
                    f"scripted policy {self.path} takes observation '{name}' {shape}; the "
                    f"env gives {got} (a config other than the one it trained with?)"
                )
            inputs.append(torch.from_numpy(np.array(value, dtype=spec["dtype"])[None]))
        with torch.inference_mode():
            return self.module(*inputs)[0].numpy().astype(np.float64)
