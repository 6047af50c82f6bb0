"""Checks and fixtures for plugin authors (and our own plugins' tests): the conformance kit.

Use :func:`check_behavior` in a plugin's tests::

    from devlearn.testing import check_behavior

    def test_conformance():
        check_behavior(MyBehavior)

It raises :class:`ConformanceError` naming the first broken part of the contract (a term, an
observation, an evaluator metric, an attribute that does not pickle).

:func:`check_gymnasium` checks the behaviour as a Gymnasium env (Gymnasium's own ``check_env``
and the vector env, :mod:`devlearn.gym`): ``check_gymnasium(MyBehavior)``.
:func:`check_learned_reward` for a learned reward (``check_learned_reward(MyTerm)``),
and :func:`registry_for` to build a plugin registry from classes, without installing anything.
:func:`place_hand_on_body` poses an infant with a hand on its body (a scripted contact), and
:func:`random_transitions` gives a learned reward a batch to train on.
Fixtures ``crib_infant`` and ``sitting_infant`` (module-scoped) are available after
``from devlearn.testing import crib_infant, sitting_infant`` in a ``conftest.py``.

For trainings in seconds without MuJoCo: :class:`FakeInfant` (a point moved by its actions, with
faults on demand) through :func:`fake_infant_factory`, the tiny behaviour that learns on it
(:class:`TinyBehavior`, :class:`TinyConfig`), and :class:`HookTracker`, which reports the order
of the episode hooks devlearn calls.

Modules: :mod:`~devlearn.testing.behavior` (the behaviour check), :mod:`~devlearn.testing.gym_env`
(the Gymnasium check), :mod:`~devlearn.testing.learned`
(the learned-reward check), :mod:`~devlearn.testing.values` (value checks and
:class:`ConformanceError`), :mod:`~devlearn.testing.fixtures`,
:mod:`~devlearn.testing.fake_infant`, :mod:`~devlearn.testing.hook_tracker`.
"""

from __future__ import annotations

from devlearn.testing.behavior import (
    check_batched_observations,
    check_behavior,
    check_behavior_class,
    check_curriculum,
    check_evaluator_merge,
    check_network,
    check_reward_terms,
    place_hand_on_body,
)
from devlearn.testing.fake_infant import FakeInfant, TinyBehavior, TinyConfig, fake_infant_factory
from devlearn.testing.fixtures import crib_infant, registry_for, sitting_infant
from devlearn.testing.gym_env import check_gymnasium
from devlearn.testing.hook_tracker import HookTracker
from devlearn.testing.learned import check_learned_reward, random_transitions
from devlearn.testing.runs import run_config
from devlearn.testing.values import ConformanceError

__all__ = [
    "ConformanceError",
    "FakeInfant",
    "HookTracker",
    "TinyBehavior",
    "TinyConfig",
    "check_batched_observations",
    "check_behavior",
    "check_behavior_class",
    "check_curriculum",
    "check_evaluator_merge",
    "check_gymnasium",
    "check_learned_reward",
    "check_network",
    "check_reward_terms",
    "crib_infant",
    "fake_infant_factory",
    "place_hand_on_body",
    "random_transitions",
    "registry_for",
    "run_config",
    "sitting_infant",
]
