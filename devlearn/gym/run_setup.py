"""What ``devlearn run`` sets up before its environments, for the Gymnasium envs: the config
(through the one config path), the prepared behaviour, the spaces and the curriculum's clock."""

from __future__ import annotations

import json
import shutil
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from gymnasium import spaces

from devlearn.api.errors import UsageError
from devlearn.config.growth import growth_schedule
from devlearn.config.resolve import RunRequest, resolve_config
from devlearn.env.guards import OBSERVATION_BOUND

if TYPE_CHECKING:
    from devlearn.api.behavior import Behavior
    from devlearn.api.curriculum import Curriculum, Stage
    from devlearn.config.run_config import RunConfig
    from devlearn.plugins import PluginRegistry

Overrides = Mapping[str, Any] | Sequence[str] | None
"""Config values of a Gymnasium env: ``{"env.action_repeat": 5, "seed": 3}`` (key -> value)
or ``["env.action_repeat=5", "seed=3"]``: exactly ``devlearn run``'s ``--set`` items."""


def set_items(overrides: Overrides) -> list[str]:
    """``overrides`` as ``--set KEY=VALUE`` items: a string value as it is, any other as JSON
    (``True`` -> ``true``, ``[1, 2]`` -> ``[1, 2]``), which ``--set`` reads back as that value.

    Raises:
        UsageError: ``overrides`` is neither a mapping nor a list of ``KEY=VALUE`` strings.
    """
    if overrides is None:
        return []
    if isinstance(overrides, Mapping):
        return [f"{k}={v if isinstance(v, str) else json.dumps(v)}" for k, v in overrides.items()]
    if (
        isinstance(overrides, str)
        or not isinstance(overrides, Sequence)  # 5 was a raw TypeError: not iterable
        or not all(isinstance(o, str) for o in overrides)
    ):
        shown = repr(overrides) if len(repr(overrides)) <= 80 else repr(overrides)[:77] + "..."
        raise UsageError(
            "overrides must be a mapping of config keys to values ({'env.action_repeat': 5}) "
            f"or a list of 'KEY=VALUE' strings, got {shown}"
        )
    return list(overrides)


def require_open(env: object, closed: bool, call: str) -> None:
    """Refuse ``call`` (``step``, ``reset``) on a closed env, as Gymnasium's own vector envs
    do (a step after ``close()`` read freed buffers: KeyError 'actions').

    Raises:
        gymnasium.error.ClosedEnvironmentError: ``closed``; the message names the env and
            what to do.
    """
    if closed:
        from gymnasium.error import ClosedEnvironmentError

        raise ClosedEnvironmentError(
            f"{call}() on a closed {type(env).__name__}: close() released its environments; "
            "make a new env to go on"
        )


class RunSetup:
    """A behaviour set up exactly as ``devlearn run`` sets it up, for a Gymnasium env.

    The config comes from :func:`~devlearn.config.resolve.resolve_config` (the behaviour's
    defaults, ``preset``, ``top`` and ``overrides``, every check of ``devlearn run``); the
    behaviour is built under it and prepared (``Behavior.prepare``: hand regard calibrates or
    copies its hand detector) in ``out_dir`` when the config names one, else in a temporary
    folder that :meth:`close` removes.

    Args:
        behavior: The behaviour's registered name.
        overrides: ``--set`` values (:data:`Overrides`).
        preset: A preset of the behaviour (``--preset``); empty: none.
        top: Top-level fields set by the caller (``num_envs``, ``workers``).
        registry: The plugin registry (default: the installed plugins).
    Raises:
        UsageError: What ``devlearn run`` refuses (an unknown behaviour, key or value), or
            learned rewards (``curiosity``), which a foreign learner does not train.
    """

    def __init__(
        self,
        behavior: str,
        overrides: Overrides = None,
        preset: str = "",
        top: dict[str, Any] | None = None,
        registry: PluginRegistry | None = None,
    ) -> None:
        if registry is None:
            from devlearn.plugins import PluginRegistry

            registry = PluginRegistry()
        request = RunRequest(behavior, set_items(overrides), preset or "", dict(top or {}))
        self.config: RunConfig = resolve_config(request, registry)
        if self.config.curiosity:
            raise UsageError(
                f"curiosity={','.join(self.config.curiosity)}: learned rewards are models that "
                "devlearn's runner trains on its rollouts; a Gymnasium env pays the behaviour's "
                "reward terms only (leave curiosity empty)"
            )
        self.behavior: Behavior = registry.create(behavior, self.config.behavior)
        self._temporary: Path | None = None
        if self.config.out_dir:
            self.folder = Path(self.config.out_dir)
            self.folder.mkdir(parents=True, exist_ok=True)
        else:
            self.folder = self._temporary = Path(tempfile.mkdtemp(prefix=f"devlearn-{behavior}-"))
        try:
            self.behavior.artifacts().prepare(self.folder)
        except BaseException:
            self.close()
            raise
        self.config.behavior = self.behavior.config  # as a run records what prepare() set

    def close(self) -> None:
        """Remove the temporary folder (safe to call twice)."""
        if self._temporary is not None:
            shutil.rmtree(self._temporary, ignore_errors=True)
            self._temporary = None


def observation_space(observation: Mapping[str, np.ndarray]) -> spaces.Dict:
    """The space of one env's observations: a Box per observation group, with the dtype the
    envs' buffers give it (uint8 images stay uint8, in [0, 255]; everything else float32 within
    the observation guard's bound, which stops a run beyond it, :mod:`devlearn.env.guards`).
    """
    boxes: dict[str, spaces.Space[Any]] = {}
    for name, value in observation.items():
        shape = tuple(np.shape(value))
        if np.asarray(value).dtype == np.uint8:
            boxes[name] = spaces.Box(0, 255, shape, np.uint8)
        else:
            boxes[name] = spaces.Box(-OBSERVATION_BOUND, OBSERVATION_BOUND, shape, np.float32)
    return spaces.Dict(boxes)


def action_space(action_dim: int) -> spaces.Box:
    """(action_dim,) float32 in [-1, 1]: the infant's actuators, as the envs clip them."""
    return spaces.Box(-1.0, 1.0, (int(action_dim),), np.float32)


def as_space(observation: Mapping[str, np.ndarray], space: spaces.Dict) -> dict[str, np.ndarray]:
    """A copy of ``observation`` in ``space``'s dtypes (what a devlearn run's buffers hold)."""
    return {
        name: np.array(observation[name], dtype=box.dtype) for name, box in space.spaces.items()
    }


class CurriculumClock:
    """The curriculum (and the body's age) advanced as a devlearn run advances them.

    A run counts physics steps summed over its environments and, at every iteration boundary
    (``ppo.num_steps_per_env`` decisions), moves the curriculum to that count and merges the
    workers' run-wide reward memory; the Gymnasium envs keep the same rhythm, counting the
    decisions they are stepped. So a foreign learner meets every stage, and every age of a
    growing body (``infant.growth``), at the step count a devlearn run of the same ``num_envs``
    and ``env.action_repeat`` would.

    Args:
        curriculum: The behaviour's curriculum.
        config: The run config: ``env.action_repeat`` physics steps per decision,
            ``ppo.num_steps_per_env`` decisions per iteration; its ``infant`` section gives the
            body's age over the run.
        num_envs: Environments stepped together (each decision adds ``num_envs *
            env.action_repeat`` physics steps).
    """

    def __init__(self, curriculum: Curriculum, config: RunConfig, num_envs: int = 1) -> None:
        self.config = config
        self.growth = growth_schedule(config)  # parsed once, as the runner does
        self.curriculum = curriculum
        self.steps_per_decision = int(num_envs) * config.env.action_repeat
        self.decisions_per_iteration = config.ppo.num_steps_per_env
        self.decisions = 0
        self.physics_steps = 0
        """Physics steps taken, summed over the envs (a run's ``env_steps``)."""
        curriculum.update(0)

    @property
    def stage(self) -> Stage:
        """The active stage."""
        return self.curriculum.stage

    @property
    def age_months(self) -> float | None:
        """The body's age now (``infant.growth``'s at this step and stage, else
        ``infant.age_months``; None: the default body), as a run gives it to its envs before
        each iteration."""
        if self.growth is None:
            return self.config.infant.age_months
        return self.growth.age_at(
            self.physics_steps, self.config.total_steps, self.curriculum.index
        )

    def tick(self) -> tuple[bool, bool]:
        """Count one decision of every env.

        Returns:
            ``(boundary, changed)``: an iteration boundary was reached (merge the run memory),
            and the curriculum moved to another stage there (send its options to the envs).
        """
        self.decisions += 1
        self.physics_steps += self.steps_per_decision
        if self.decisions % self.decisions_per_iteration:
            return False, False
        return True, self.curriculum.update(self.physics_steps)


def step_info(
    term_names: Sequence[str], term_rewards: Sequence[float], stage: str
) -> dict[str, Any]:
    """One env's info for one step: ``reward/<term>`` (each term's weighted reward in this
    decision, float) and ``stage`` (the curriculum stage it ran in)."""
    info: dict[str, Any] = {f"reward/{n}": float(v) for n, v in zip(term_names, term_rewards)}
    info["stage"] = stage
    return info


def episode_info(summary: Mapping[str, Any]) -> dict[str, float]:
    """A finished episode's summary as ``devlearn run`` logs it (``reward/<term>``: weighted
    sums over the episode, ``metrics/<name>``: the evaluator's), each key under ``episode/``;
    the record kept for the run's metrics (not a number) is left out."""
    return {
        f"episode/{key}": float(value)
        for key, value in summary.items()
        if key.startswith(("reward/", "metrics/"))
    }
