"""Checks and fixtures for plugin authors (and our own plugins' tests).

Use :func:`check_behavior` in a plugin's tests::

    from devlearn.testing import check_behavior

    def test_conformance():
        check_behavior(MyBehavior)

It raises :class:`ConformanceError` naming the first broken part of the contract (a term, an
observation, an evaluator metric, an attribute that does not pickle).

:func:`check_learned_reward` for a learned reward (``check_learned_reward(MyTerm)``),
and :func:`registry_for` to build a plugin registry from classes, without installing anything.
Fixtures ``crib_infant`` and ``sitting_infant`` (module-scoped) are available after
``from devlearn.testing import crib_infant, sitting_infant`` in a ``conftest.py``.
"""

from __future__ import annotations

import dataclasses
import pickle
import types
from typing import Any

import numpy as np
import torch

from devlearn.behavior import Behavior, NetworkSpec
from devlearn.conformance import (
    CheckedEvaluator,
    check_batched_observations,
    check_observations,
    check_summaries,
    checked_terms,
    place_hand_on_body,
)
from devlearn.conformance_values import ConformanceError, check_number, check_picklable
from devlearn.conformance_values import require as _require
from devlearn.curriculum import Curriculum
from devlearn.env.guards import TermError
from devlearn.learned_conformance import check_learned_reward
from devlearn.plugins import PluginRegistry, PluginSource
from devlearn.rewards import BatchedIntrinsicReward, IntrinsicReward

__all__ = [
    "ConformanceError",
    "check_batched_observations",
    "check_behavior",
    "check_behavior_class",
    "check_curriculum",
    "check_learned_reward",
    "check_network",
    "check_reward_terms",
    "crib_infant",
    "registry_for",
    "sitting_infant",
]


def check_behavior_class(behavior_cls: type[Behavior]) -> None:
    """Check the class-level contract: name, scene, senses, config dataclass, docstrings."""
    name = getattr(behavior_cls, "name", None)
    _require(isinstance(name, str) and name.isidentifier(), "Behavior.name must be an identifier")
    _require(
        behavior_cls.scene in ("crib", "sitting", "sitting_babybench"),
        "Behavior.scene must be crib, sitting or sitting_babybench",
    )
    valid = {"touch", "proprioception", "vestibular", "eyes"}
    _require(set(behavior_cls.senses) <= valid, f"Behavior.senses must be within {sorted(valid)}")
    _require(dataclasses.is_dataclass(behavior_cls.config_class), "config_class: a dataclass")
    _require(bool(behavior_cls.__doc__), f"{behavior_cls.__name__} needs a docstring")
    config = behavior_cls.config_class()
    check_picklable(behavior_cls(config), f"behavior '{name}'")  # travels to worker processes


def check_reward_terms(terms: list[IntrinsicReward | BatchedIntrinsicReward]) -> None:
    """Check reward terms: unique names, a docstring each, picklable state."""
    names = [t.name for t in terms]
    _require(len(names) == len(set(names)), f"reward term names must be unique: {names}")
    for term in terms:
        batched = isinstance(term, BatchedIntrinsicReward)
        _require(
            batched or isinstance(term, IntrinsicReward),
            f"{term!r} is not an IntrinsicReward or BatchedIntrinsicReward",
        )
        _require(bool(type(term).__doc__), f"reward term '{term.name}' needs a docstring")
        if batched:
            term.bind(1)
            state = term.state_dict(0)
        else:
            state = term.state_dict()
        _require(isinstance(state, dict), f"reward term '{term.name}': state_dict() -> a dict")
        check_picklable(state, f"reward term '{term.name}' state_dict()", "state")
        if batched:
            term.load_state_dict(0, pickle.loads(pickle.dumps(state)))
        else:
            term.load_state_dict(pickle.loads(pickle.dumps(state)))


def check_curriculum(curriculum: Curriculum) -> None:
    """Check that a curriculum's state survives a save/restore."""
    total = sum(s.steps or 0 for s in curriculum.stages)
    curriculum.update(total + 1)
    state = pickle.loads(pickle.dumps(curriculum.state_dict()))
    fresh = type(curriculum)(curriculum.stages)
    fresh.load_state_dict(state)
    _require(fresh.index == curriculum.index, "curriculum stage lost on load_state_dict")


def check_network(spec: NetworkSpec, observations: dict[str, np.ndarray], groups: dict) -> None:
    """Check that every observation in the actor/critic groups has an encoder that runs."""
    for group in ("actor", "critic"):
        _require(group in groups, f"obs_groups must have '{group}'")
        for name in groups[group]:
            _require(name in spec.encoders, f"observation '{name}' has no encoder in network()")
    for name, encoder in spec.encoders.items():
        _require(name in observations, f"encoder for unknown observation '{name}'")
        shape = tuple(observations[name].shape)
        module = encoder.build(shape)
        batch = torch.as_tensor(np.stack([observations[name]] * 2)).float()
        out = module(batch)
        _require(
            tuple(out.shape) == (2, encoder.out_dim(shape)),
            f"encoder '{name}' returned {tuple(out.shape)}, expected (2, {encoder.out_dim(shape)})",
        )


def check_behavior(
    behavior_cls: type[Behavior],
    steps: int = 20,
    seed: int = 0,
    *,
    episodes: int = 2,
    episode_steps: int = 200,
    contact_steps: int = 3,
    config: Any | None = None,
) -> dict[str, tuple[int, ...]]:
    """Run the full conformance check: what training and ``devlearn eval`` will exercise.

    In order: the class contract (name, scene, senses, documented config, picklable instance,
    naming the attribute that is not); reward terms (unique names, docstrings, picklable state);
    the curriculum's save/restore; then the behaviour's real environment:

    1. ``steps`` random actions from the first stage's initial pose;
    2. ``episodes`` episodes from random poses (cycling through the curriculum's stages, each
       cut to ``episode_steps`` steps so it ends quickly), so episode ends run too;
    3. ``contact_steps`` steps with a hand placed on the body (a scripted contact), so facts,
       observations and terms that depend on contacts run.

    On every step observations must keep their names and shapes and be finite float32 (or
    uint8) arrays; every reward term must return a finite Python float (the message names the
    term). A training and an evaluation evaluator (``evaluator(training=...)``) record every
    step; their ``end_episode()`` metrics must be finite numbers and their ``summary()``
    JSON-serialisable, and ``write_artifacts`` must return files that exist. A behaviour that
    batches its facts or observations (``batch_facts``, ``batch_observe``) must give on every
    step exactly what ``facts`` and ``observe`` give (:func:`check_batched_observations`).

    Args:
        behavior_cls: The Behavior subclass.
        steps: Random-action steps of phase 1.
        seed: Seed of the environment and of the random actions.
        episodes: Random-pose episodes of phase 2 (at least 1).
        episode_steps: Length of each of those episodes (at most the infant's own).
        contact_steps: Steps with a hand on the body in phase 3.
        config: The behaviour's config (default ``config_class()``).
    Returns:
        The observations' shapes, name -> tuple.
    Raises:
        ConformanceError: The first broken part of the contract, by name.
    """
    import tempfile
    from pathlib import Path

    from devlearn.env import BehaviorEnv
    from devlearn.env.batch_advance import overrides

    check_behavior_class(behavior_cls)
    behavior = behavior_cls(config if config is not None else behavior_cls.config_class())
    check_reward_terms(behavior.reward_terms())
    curriculum = behavior.curriculum()
    check_curriculum(curriculum)
    phase = ["after reset"]  # where the check is, for messages (CheckedTerm reads it)
    env = BehaviorEnv(behavior, seed=seed)
    try:
        env.terms = checked_terms(env.terms, phase)
        checked = CheckedEvaluator(env.evaluator, behavior.evaluator(training=False), phase)
        env.evaluator = checked
        env.episode_steps = max(1, min(env.episode_steps, episode_steps))
        first = env.reset()
        shapes = check_observations(first, None, "after reset")
        check_network(behavior.network(), first, behavior.obs_groups(list(shapes)))
        rng = np.random.default_rng(seed)

        batches = overrides(behavior, "batch_facts") or overrides(behavior, "batch_observe")

        def step(action: np.ndarray, where: str) -> bool:
            phase[0] = where
            try:
                obs, reward, done, _, info = env.step(action)
            except TermError as exc:  # a checked term's own finding: report it as such
                if isinstance(exc.__cause__, ConformanceError):
                    raise exc.__cause__ from None
                raise
            check_number(reward, "the summed reward", where)
            check_observations(obs, shapes, where)
            if batches:
                check_batched_observations(env.behavior, [env.infant], where)
            return done

        for _ in range(steps):
            step(rng.uniform(-1, 1, env.action_dim), "on random actions from the initial pose")
        for i in range(max(1, episodes)):
            stage = curriculum.stages[i % len(curriculum.stages)]
            env.set_stage({**stage.options, "random_pose": True})
            env.reset()
            where = f"in random-pose episode {i + 1} (stage '{stage.name}')"
            while not step(rng.uniform(-1, 1, env.action_dim), where):
                pass
        _require(checked.episodes >= 1, "no episode ended: the evaluator was never closed")
        env.set_stage(behavior.eval_stage())
        _scripted_contacts(env, rng, contact_steps, step)
        check_summaries(checked)
        with tempfile.TemporaryDirectory() as tmp:
            paths = checked.evaluation.write_artifacts(Path(tmp))
            _require(isinstance(paths, list), "write_artifacts() must return a list of paths")
            missing = [str(p) for p in paths if not Path(p).exists()]
            _require(not missing, f"write_artifacts() returned files that do not exist: {missing}")
    finally:
        env.close()
    return shapes


def _scripted_contacts(env: Any, rng: np.random.Generator, count: int, step) -> None:
    """Take ``count`` steps on which a hand touches the body (placed there before each step)."""
    infant = env.infant
    if count <= 0 or not hasattr(infant, "_qpos_index"):  # a fake infant: nothing to place
        return
    done = 0
    for _ in range(20 * count):
        if env.episode_step >= env.episode_steps - 1:
            env.reset()  # keep the placed pose clear of an automatic reset
        if not place_hand_on_body(infant, rng):
            continue
        step(np.zeros(env.action_dim), "on a step with a hand placed on the body")
        done += bool(infant.hand_contacts().any())
        if done >= count:
            return
    raise RuntimeError(f"devlearn.testing could not script a hand contact in {infant.scene}")


def registry_for(
    *behaviors: type[Behavior], name: str = "test_plugin", learned_rewards: tuple[type, ...] = ()
) -> PluginRegistry:
    """Build a registry holding the given behaviour classes (and learned rewards), as if one
    plugin registered them."""
    from devlearn.hookspecs import hookimpl

    module = types.ModuleType(name)

    @hookimpl
    def register_behaviors(register):
        for behavior in behaviors:
            register(behavior)

    module.register_behaviors = register_behaviors
    if learned_rewards:

        @hookimpl
        def register_learned_rewards(register):
            for term in learned_rewards:
                register(term)

        module.register_learned_rewards = register_learned_rewards
    return PluginRegistry([PluginSource(name, module, "test-dist", "0")], disabled=())


def _infant_fixture(scene: str, senses: tuple[str, ...]):
    import pytest

    @pytest.fixture(scope="module")
    def fixture():
        from devlearn.infant import build_infant

        infant = build_infant(scene, senses=senses)
        infant.reset(np.random.default_rng(0))
        yield infant
        infant.close()

    return fixture


crib_infant = _infant_fixture("crib", ("touch", "proprioception", "vestibular"))
"""A crib-scene infant with touch, proprioception and vestibular senses (module-scoped)."""
sitting_infant = _infant_fixture("sitting", ("proprioception", "eyes"))
"""A sitting-scene infant with proprioception and eyes (module-scoped)."""
