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
and :func:`registry_for` to build a plugin registry from classes, without installing anything
(:class:`PluginRegistry`: the installed plugins').
:func:`place_hand_on_body` poses an infant with a hand on its body (a scripted contact), and
:func:`random_transitions` gives a learned reward a batch to train on. :func:`facts_of` and
:func:`observations_of` give one environment's facts and observations as the core computes
them (a batch of one).
Fixtures ``crib_infant`` and ``sitting_infant`` (module-scoped) are available after
``from devlearn.testing import crib_infant, sitting_infant`` in a ``conftest.py``.

Behaviour-level verbs (:mod:`~devlearn.testing.verbs`, :mod:`~devlearn.testing.runs`): play a
behaviour's environments as training plays them (:class:`Play`: ``reset``, ``step``,
``play(N)``, ``term_values``, ``state``/``load_state``, ``sync_run_memory``), the facts and
observations of one environment (:func:`facts_of`, :func:`observations_of`), a config's round
trip (:func:`run_config`, resolved and checked as ``devlearn run``'s; :func:`saved_config`,
:func:`load_saved_config`, :func:`config_round_trip`), a tiny run (:func:`train`,
:func:`load_checkpoint`, :func:`save_checkpoint`, :func:`policy_network`, :func:`policy_file`,
:func:`evaluate_policy`, :func:`open_scripted_policy`, :func:`run_command`: ``devlearn ARGS``
in a new process). Plugin tests import only ``devlearn``, ``devlearn.api`` and the names
``devlearn.testing`` exports (checked by ``tests/testing/test_plugin_test_imports.py`` and
``tests/testing/test_kit_names.py``): no core internals.

For trainings in seconds without MuJoCo: :class:`FakeInfant` (a point moved by its actions, with
faults on demand) through :func:`fake_infant_factory`, the tiny behaviour that learns on it
(:class:`TinyBehavior`, :class:`TinyConfig`), and :class:`HookTracker`, which reports the order
of the episode hooks devlearn calls.

Modules: :mod:`~devlearn.testing.behavior` (the behaviour check), :mod:`~devlearn.testing.gym_env`
(the Gymnasium check), :mod:`~devlearn.testing.learned`
(the learned-reward check), :mod:`~devlearn.testing.values` (value checks and
:class:`ConformanceError`), :mod:`~devlearn.testing.verbs`, :mod:`~devlearn.testing.fixtures`,
:mod:`~devlearn.testing.fake_infant`, :mod:`~devlearn.testing.hook_tracker`,
:mod:`~devlearn.testing.runs`.
"""

from __future__ import annotations

from devlearn.testing.behavior import (
    check_batched_observations,
    check_behavior,
    check_behavior_class,
    check_contract_members,
    check_curriculum,
    check_evaluator_class,
    check_evaluator_merge,
    check_network,
    check_reward_terms,
    place_hand_on_body,
)
from devlearn.testing.fake_infant import FakeInfant, TinyBehavior, TinyConfig, fake_infant_factory
from devlearn.testing.fixtures import (
    SKIN_RGBA,
    TOY_COLOURS,
    PluginRegistry,
    crib_infant,
    registry_for,
    sitting_infant,
)
from devlearn.testing.gym_env import check_gymnasium
from devlearn.testing.hook_tracker import HookTracker
from devlearn.testing.learned import check_learned_reward, random_transitions
from devlearn.testing.runs import (
    CommandResult,
    config_round_trip,
    evaluate_policy,
    load_checkpoint,
    load_saved_config,
    open_scripted_policy,
    policy_file,
    policy_network,
    run_command,
    run_config,
    save_checkpoint,
    saved_config,
    train,
)
from devlearn.testing.values import ConformanceError
from devlearn.testing.verbs import EPISODE_RECORD, Play, facts_of, observations_of

__all__ = [
    "EPISODE_RECORD",
    "CommandResult",
    "ConformanceError",
    "FakeInfant",
    "HookTracker",
    "Play",
    "PluginRegistry",
    "SKIN_RGBA",
    "TOY_COLOURS",
    "TinyBehavior",
    "TinyConfig",
    "check_batched_observations",
    "check_behavior",
    "check_behavior_class",
    "check_contract_members",
    "check_curriculum",
    "check_evaluator_class",
    "check_evaluator_merge",
    "check_gymnasium",
    "check_learned_reward",
    "check_network",
    "check_reward_terms",
    "config_round_trip",
    "crib_infant",
    "evaluate_policy",
    "facts_of",
    "fake_infant_factory",
    "load_checkpoint",
    "load_saved_config",
    "observations_of",
    "open_scripted_policy",
    "place_hand_on_body",
    "policy_file",
    "policy_network",
    "random_transitions",
    "registry_for",
    "run_command",
    "run_config",
    "save_checkpoint",
    "saved_config",
    "sitting_infant",
    "train",
]
