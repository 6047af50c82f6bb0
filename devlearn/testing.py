"""Checks and fixtures for plugin authors (and our own plugins' tests).

Use :func:`check_behavior` in a plugin's tests::

    from devlearn.testing import check_behavior

    def test_conformance():
        check_behavior(MyBehavior, steps=20)

:func:`check_learned_reward` for a learned reward (``check_learned_reward(MyTerm)``),
and :func:`registry_for` to build a plugin registry from classes, without installing anything.
Fixtures ``crib_infant`` and ``sitting_infant`` (module-scoped) are available after
``from devlearn.testing import crib_infant, sitting_infant`` in a ``conftest.py``.
"""

from __future__ import annotations

import dataclasses
import io
import pickle
import types
from typing import Any

import numpy as np
import torch

from devlearn.behavior import Behavior, NetworkSpec
from devlearn.curriculum import Curriculum
from devlearn.learned import LearnedReward, LearnedRewardConfig, Transitions
from devlearn.plugins import PluginRegistry, PluginSource
from devlearn.rewards import IntrinsicReward


class ConformanceError(AssertionError):
    """A behaviour breaks the devlearn contract; the message says which part."""


def _require(condition: bool, message: str) -> None:
    if not condition:
        raise ConformanceError(message)


def check_behavior_class(behavior_cls: type[Behavior]) -> None:
    """Check the class-level contract: name, scene, senses, config dataclass, docstrings."""
    name = getattr(behavior_cls, "name", None)
    _require(isinstance(name, str) and name.isidentifier(), "Behavior.name must be an identifier")
    _require(behavior_cls.scene in ("crib", "sitting"), "Behavior.scene must be crib or sitting")
    valid = {"touch", "proprioception", "vestibular", "eyes"}
    _require(set(behavior_cls.senses) <= valid, f"Behavior.senses must be within {sorted(valid)}")
    _require(dataclasses.is_dataclass(behavior_cls.config_class), "config_class: a dataclass")
    _require(bool(behavior_cls.__doc__), f"{behavior_cls.__name__} needs a docstring")
    config = behavior_cls.config_class()
    pickle.loads(pickle.dumps(behavior_cls(config)))  # must travel to worker processes


def check_reward_terms(terms: list[IntrinsicReward]) -> None:
    """Check reward terms: unique names, a docstring each, picklable state."""
    names = [t.name for t in terms]
    _require(len(names) == len(set(names)), f"reward term names must be unique: {names}")
    for term in terms:
        _require(isinstance(term, IntrinsicReward), f"{term!r} is not an IntrinsicReward")
        _require(bool(type(term).__doc__), f"reward term '{term.name}' needs a docstring")
        state = pickle.loads(pickle.dumps(term.state_dict()))
        term.load_state_dict(state)


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


def check_behavior(behavior_cls: type[Behavior], steps: int = 20, seed: int = 0) -> dict[str, Any]:
    """Run the full conformance check: class, terms, curriculum, network, and real env steps.

    Builds the behaviour's real environment, takes ``steps`` random actions and checks
    observation shapes and dtypes stay fixed, rewards are finite, episode info is well formed.

    Returns:
        The first step's observations' shapes, name -> tuple.
    """
    from devlearn.env import BehaviorEnv

    check_behavior_class(behavior_cls)
    behavior = behavior_cls(behavior_cls.config_class())
    check_reward_terms(behavior.reward_terms())
    check_curriculum(behavior.curriculum())
    env = BehaviorEnv(behavior, seed=seed)
    try:
        obs = env.reset()
        shapes = {k: v.shape for k, v in obs.items()}
        check_network(behavior.network(), obs, behavior.obs_groups(list(obs)))
        rng = np.random.default_rng(seed)
        for _ in range(steps):
            action = rng.uniform(-1, 1, env.action_dim)
            obs, reward, done, time_out, info = env.step(action)
            _require(np.isfinite(reward), f"non-finite reward {reward}")
            for key, value in obs.items():
                _require(value.shape == shapes[key], f"observation '{key}' changed shape")
                _require(np.all(np.isfinite(value)), f"observation '{key}' has NaN or inf")
    finally:
        env.close()
    return shapes


def _random_transitions(
    shapes: dict[str, tuple[int, ...]], action_dim: int, size: int, seed: int
) -> Transitions:
    """Random transitions: uint8 images for (H, W, C) shapes, normal floats otherwise."""
    gen = torch.Generator().manual_seed(seed)

    def draw() -> dict[str, torch.Tensor]:
        return {
            name: torch.randint(0, 256, (size, *shape), generator=gen, dtype=torch.uint8)
            if len(shape) == 3
            else torch.randn(size, *shape, generator=gen)
            for name, shape in shapes.items()
        }

    actions = torch.rand(size, action_dim, generator=gen) * 2 - 1
    return Transitions(draw(), actions, draw())


def check_learned_reward(
    term_cls: type[LearnedReward],
    observation_shapes: dict[str, tuple[int, ...]] | None = None,
    action_dim: int = 3,
    batch_size: int = 32,
    seed: int = 0,
) -> LearnedReward:
    """Check a learned reward: class contract, shapes, training, and a save/restore.

    Builds the term on random transitions (``observation_shapes`` default: a (6,) vector
    ``proprioception`` and an (8, 8, 3) ``eyes`` image) and checks: a docstring, a
    lower_snake_case ``name``, a :class:`~devlearn.LearnedRewardConfig` dataclass; rewards
    (B,) and finite, the same when asked twice; an update changes trainable parameters and
    reports finite ``raw``, ``loss`` and ``weight``; the state (model, optimiser, scale)
    survives ``torch.save`` / ``torch.load(weights_only=True)`` into a fresh instance, which
    then rewards and trains exactly like the original.

    Returns:
        The trained term.
    """
    from devlearn.plugins import _NAME

    shapes = observation_shapes or {"proprioception": (6,), "eyes": (8, 8, 3)}
    _require(bool(term_cls.__doc__), f"{term_cls.__name__} needs a docstring")
    name = getattr(term_cls, "name", None)
    _require(isinstance(name, str) and bool(_NAME.match(name)), "name: lower_snake_case")
    config_cls = term_cls.config_class
    _require(
        dataclasses.is_dataclass(config_cls) and issubclass(config_cls, LearnedRewardConfig),
        "config_class must be a dataclass subclassing LearnedRewardConfig",
    )
    torch.manual_seed(seed)
    term = term_cls(config_cls(), shapes, action_dim)
    batch = _random_transitions(shapes, action_dim, batch_size, seed)
    term.observe(batch)
    with torch.no_grad():
        first, second = term.compute_reward(batch), term.compute_reward(batch)
    _require(tuple(first.shape) == (batch_size,), f"compute_reward gave {tuple(first.shape)}, "
             f"expected ({batch_size},)")
    _require(bool(torch.isfinite(first).all()), "compute_reward gave NaN or inf")
    _require(torch.equal(first, second), "compute_reward changed on the same batch")
    before = [p.detach().clone() for p in term.model.parameters() if p.requires_grad]
    reward, log = term.update(batch, env_steps=0)
    _require(tuple(reward.shape) == (batch_size,), "update must return a (B,) reward")
    _require(set(log) >= {"raw", "loss", "weight"}, f"update log lacks raw/loss/weight: {log}")
    _require(all(np.isfinite(v) for v in log.values()), f"non-finite update log {log}")
    after = [p.detach() for p in term.model.parameters() if p.requires_grad]
    _require(any(not torch.equal(a, b) for a, b in zip(before, after)), "update trained nothing")
    buffer = io.BytesIO()
    torch.save(term.state_dict(), buffer)
    buffer.seek(0)
    fresh = term_cls(config_cls(), shapes, action_dim)
    fresh.load_state_dict(torch.load(buffer, weights_only=True))
    later = _random_transitions(shapes, action_dim, batch_size, seed + 1)
    results = []
    for copy in (term, fresh):
        torch.manual_seed(seed + 2)  # the same mini-batch order for both
        reward, _ = copy.update(later, env_steps=batch_size)
        results.append((reward, [p.detach().clone() for p in copy.model.parameters()]))
    _require(torch.equal(results[0][0], results[1][0]), "restored term rewards differently")
    for a, b in zip(results[0][1], results[1][1]):
        _require(torch.equal(a, b), "restored term trains differently (optimiser state lost?)")
    return term


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
