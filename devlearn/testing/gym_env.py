"""The Gymnasium check of the conformance kit (:func:`check_gymnasium`): Gymnasium's own
``check_env`` on a behaviour's env made as a user makes it, then its vector env."""

from __future__ import annotations

import functools
import warnings
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import gymnasium
import numpy as np

from devlearn.testing.fixtures import registry_for
from devlearn.testing.values import ConformanceError, require

if TYPE_CHECKING:
    from devlearn.api.behavior import Behavior
    from devlearn.env.behavior_env import InfantFactory
    from devlearn.gym.vector import DevlearnVectorEnv

CHECK_NAMESPACE = "devlearn-check"
"""Namespace of the ids :func:`check_gymnasium` registers while it runs (then removes)."""


def check_gymnasium(
    behavior_cls: type[Behavior],
    overrides: Mapping[str, Any] | Sequence[str] | None = None,
    *,
    vector_steps: int = 3,
    infant_factory: InfantFactory | None = None,
) -> None:
    """Check that ``behavior_cls`` works as a Gymnasium environment (:mod:`devlearn.gym`).

    The behaviour is registered under a temporary id, as ``import devlearn.gym`` registers an
    installed one, and made with ``gymnasium.make``; Gymnasium's ``check_env`` then checks its
    spaces, seeded resets, a deterministic step, fresh data on every call, the ``rgb_array``
    render mode and a double close, every Gymnasium warning counted as an error. Then its
    vector env (two envs in this process): same-step autoreset
    declared, a seeded reset that repeats, ``vector_steps`` random steps with observations in
    the space and a finite reward and ``reward/<term>`` per env.

    Args:
        behavior_cls: The Behavior subclass.
        overrides: Config values as ``devlearn run --set`` takes them (e.g. hand regard's
            ``{"behavior.detector_file": PATH}``, so that it need not babble).
        vector_steps: Random steps of the vector env.
        infant_factory: Infant builder (default the real infant).
    Raises:
        ConformanceError: What Gymnasium's checker or the vector check found, by name.
    """
    # imported here: devlearn.gym registers the installed behaviours when first imported,
    # which importing the kit (as a plugin's tests do) need not do
    from gymnasium.utils.env_checker import check_env

    from devlearn.gym import env_id
    from devlearn.gym.env import DevlearnEnv
    from devlearn.gym.vector import DevlearnVectorEnv

    registry = registry_for(behavior_cls)
    name = behavior_cls.name
    check_id = env_id(name).replace("devlearn/", f"{CHECK_NAMESPACE}/", 1)
    gymnasium.register(
        check_id,
        entry_point=functools.partial(
            DevlearnEnv, registry=registry, infant_factory=infant_factory
        ),
        kwargs={"behavior": name, "overrides": overrides},
    )
    try:
        with warnings.catch_warnings():
            # Gymnasium's checker reports through its logger: every "WARN:" is a failure
            warnings.filterwarnings("error", message=".*WARN:")
            env = gymnasium.make(check_id)
            try:
                check_env(env.unwrapped)
            except (AssertionError, UserWarning, gymnasium.error.Error) as exc:
                raise ConformanceError(f"gymnasium check_env on {check_id}: {exc}") from exc
            finally:
                env.close()
        envs = DevlearnVectorEnv(
            name, 2, 0, overrides, registry=registry, infant_factory=infant_factory
        )
        _check_vector(envs, vector_steps)
    finally:
        gymnasium.registry.pop(check_id, None)


def _check_vector(envs: DevlearnVectorEnv, steps: int) -> None:
    """Two envs: autoreset mode, seeded resets, random steps; then closed."""
    from gymnasium.vector import AutoresetMode

    try:
        mode = envs.metadata.get("autoreset_mode")
        require(mode == AutoresetMode.SAME_STEP, f"vector env autoreset_mode is {mode!r}")
        first, _ = envs.reset(seed=0)
        again, _ = envs.reset(seed=0)
        require(
            all(np.array_equal(first[k], again[k]) for k in first),
            "vector env: reset(seed=0) twice gave different observations",
        )
        envs.action_space.seed(0)
        terms = envs.term_names
        for step in range(steps):
            obs, rewards, terminated, truncated, info = envs.step(envs.action_space.sample())
            where = f"vector env step {step + 1}"
            require(obs in envs.observation_space, f"{where}: observations outside the space")
            require(
                rewards.shape == (2,) and bool(np.isfinite(rewards).all()),
                f"{where}: rewards {rewards!r} are not 2 finite numbers",
            )
            require(terminated.shape == truncated.shape == (2,), f"{where}: flags not (2,)")
            missing = [t for t in terms if f"reward/{t}" not in info]
            require(not missing, f"{where}: info lacks reward/<term> for {missing}")
    finally:
        envs.close()
