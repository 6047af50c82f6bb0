"""What a behaviour does, in its own words, for a plugin's tests: the facts and observations of
one environment as the core computes them (a batch of one), its environments played as training
plays them (:class:`Play`), and a config's round trip through the form runs save."""

from __future__ import annotations

import copy
from typing import Any

import numpy as np

from devlearn.api.batching import EnvBatch
from devlearn.api.behavior import Behavior


def facts_of(behavior: Behavior, infant: Any) -> dict[str, Any]:
    """The facts ``behavior`` gives for ``infant`` in its current state (one environment:
    ``behavior`` is its own, so the call updates its per-environment state as a step would)."""
    return behavior.facts(EnvBatch([infant], [behavior]))[0]


def observations_of(
    behavior: Behavior, infant: Any, facts: dict[str, Any] | None = None
) -> dict[str, np.ndarray]:
    """The observations ``behavior`` gives for ``infant``, name -> array of one environment
    (no batch axis), from ``facts`` (default: :func:`facts_of` the infant now)."""
    if facts is None:
        facts = facts_of(behavior, infant)
    batch = behavior.observe(EnvBatch([infant], [behavior]), [facts])
    return {name: np.asarray(array)[0] for name, array in batch.items()}


Step = tuple[dict[str, np.ndarray], float, bool, bool, "dict[str, Any] | None"]
"""One environment's decision: ``(observations, reward, done, time_out, episode_info)``; on an
episode's last step ``episode_info`` holds ``reward/<term>`` sums and ``metrics/<name>``."""

EPISODE_RECORD = "episode_record"
"""Key of an ended episode's info holding its evaluator's ``episode_record()`` (not a number)."""


class Play:
    """A behaviour's environments played as training plays them, for a plugin's tests.

    ``num_envs`` environments in one batch, as a worker steps them: their facts and
    observations once per step, their batched reward terms shared. One environment plays on
    ``behavior`` itself; several on a copy each. The core's environment classes stay behind
    this object (its methods are what a test needs of them).

    Args:
        behavior: The behaviour to play.
        num_envs: Environments in the batch.
        seed: Seed of the first environment (the others ``seed + i``), or ``seeds``.
        seeds: One seed per environment (overrides ``num_envs`` and ``seed``).
        infant_factory: ``factory(scene, senses=..., **options) -> Infant`` (default: the real
            infant), or one factory per environment.
        training: False: the evaluators are ``devlearn eval``'s.
        action_repeat: Physics steps per decision (``env.action_repeat``).
    """

    def __init__(
        self,
        behavior: Behavior,
        num_envs: int = 1,
        *,
        seed: int = 0,
        seeds: list[int] | None = None,
        infant_factory: Any = None,
        training: bool = True,
        action_repeat: int = 1,
    ) -> None:
        from devlearn.env.behavior_env import BehaviorEnv, share_batched_terms
        from devlearn.env.settings import EnvSettings

        seeds = list(seeds) if seeds is not None else [seed + i for i in range(num_envs)]
        factories = (
            list(infant_factory)
            if isinstance(infant_factory, (list, tuple))
            else [infant_factory] * len(seeds)
        )
        settings = EnvSettings(int(action_repeat))
        self._envs = [
            BehaviorEnv(
                behavior if len(seeds) == 1 else copy.deepcopy(behavior),
                s,
                factory,
                training=training,
                index=i,
                settings=settings,
            )
            for i, (s, factory) in enumerate(zip(seeds, factories))
        ]
        share_batched_terms(self._envs)

    def __enter__(self) -> Play:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def num_envs(self) -> int:
        """Environments in the batch."""
        return len(self._envs)

    @property
    def action_dim(self) -> int:
        """Actions per environment."""
        return self._envs[0].action_dim

    @property
    def infants(self) -> list[Any]:
        """The environments' infants, in batch order."""
        return [env.infant for env in self._envs]

    @property
    def behaviors(self) -> list[Behavior]:
        """The environments' own behaviours, in batch order."""
        return [env.behavior for env in self._envs]

    @property
    def reward_terms(self) -> list[Any]:
        """The batched reward terms the environments share, in the behaviour's order."""
        return list(self._envs[0].terms)

    @property
    def episode_steps(self) -> int:
        """Physics steps per episode; set it to cut episodes short (every environment)."""
        return self._envs[0].episode_steps

    @episode_steps.setter
    def episode_steps(self, steps: int) -> None:
        for env in self._envs:
            env.episode_steps = int(steps)

    def reset(self) -> list[dict[str, np.ndarray]]:
        """Start a new episode in every environment; return their first observations."""
        return [env.reset() for env in self._envs]

    def set_stage(self, options: dict[str, Any]) -> None:
        """Use a curriculum stage's options from now on (``random_pose`` from the next reset)."""
        for env in self._envs:
            env.set_stage(options)

    def step(self, actions: Any = None) -> list[Step]:
        """One decision of every environment.

        Args:
            actions: (num_envs, action_dim) actions, or one (action_dim,) action for every
                environment; None: zeros.
        Returns:
            One :data:`Step` per environment.
        """
        from devlearn.env.behavior_env import step_batch

        if actions is None:
            actions = np.zeros((self.num_envs, self.action_dim))
        actions = np.asarray(actions, dtype=np.float64)
        if actions.ndim == 1:
            actions = np.tile(actions, (self.num_envs, 1))
        return step_batch(self._envs, actions)

    def play(self, steps: int, actions: Any = None) -> list[list[Step]]:
        """``steps`` decisions (:meth:`step`); ``actions`` as there, or ``f(step) -> actions``.

        Returns:
            Per decision, one :data:`Step` per environment.
        """
        return [self.step(actions(t) if callable(actions) else actions) for t in range(steps)]

    def term_values(self, actions: Any = None) -> dict[str, np.ndarray]:
        """One physics step's weighted value of every reward term, without finishing the step
        (no sums, no evaluator, no reset): term name -> (num_envs,) float64."""
        from devlearn.env.batch_advance import advance_batch
        from devlearn.env.behavior_env import term_values

        if actions is None:
            actions = np.zeros((self.num_envs, self.action_dim))
        contexts, _ = advance_batch(self._envs, np.asarray(actions, dtype=np.float64))
        values = term_values(self._envs, contexts)
        return {term.name: values[k] for k, term in enumerate(self._envs[0].terms)}

    def sync_run_memory(self, *others: Play) -> None:
        """Merge the run-wide reward memory of this batch and ``others`` (as the runner merges
        its workers' at an iteration boundary, in this order: each batch one worker) and give
        every batch the merged memory; nothing happens when no term keeps one."""
        from devlearn.env.behavior_env import load_run_memories, merge_run_memories, run_memories

        batches = [self, *others]
        copies = [run_memories(batch._envs) for batch in batches]
        if not copies[0]:
            return
        merged = merge_run_memories(self._envs[0].terms, copies)
        for batch in batches:
            load_run_memories(batch._envs, merged)

    def state(self) -> list[dict[str, Any]]:
        """Every environment's resumable state (reward terms, generator, stage), as a
        checkpoint holds it."""
        return [env.state_dict() for env in self._envs]

    def load_state(self, states: list[dict[str, Any]]) -> None:
        """Restore :meth:`state`'s output (call :meth:`reset` afterwards)."""
        for env, state in zip(self._envs, states):
            env.load_state_dict(state)

    def close(self) -> None:
        """Release the infants."""
        for env in self._envs:
            env.close()
