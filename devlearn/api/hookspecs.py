"""The devlearn plugin API: every hook a plugin may implement, documented here.

A plugin is a module listed under the ``devlearn`` entry-point group. It implements hooks by
decorating functions with :data:`devlearn.hookimpl`. Hooks only register things: each receives
a ``register`` callable; the core validates, names and de-duplicates what is registered and
reports clashes with the names of both plugins.

Example::

    import devlearn

    @devlearn.hookimpl
    def register_behaviors(register):
        register(MyBehavior)
"""

from __future__ import annotations

from collections.abc import Callable

import pluggy

hookspec = pluggy.HookspecMarker("devlearn")
hookimpl = pluggy.HookimplMarker("devlearn")


@hookspec
def register_behaviors(register: Callable[[type], None]) -> None:
    """Register behaviours (subclasses of :class:`devlearn.Behavior`).

    Call ``register(BehaviorClass)`` once per behaviour. The class's ``name`` must be unique
    across all installed plugins; a duplicate is reported with both plugins' names and the
    second registration is ignored.

    Args:
        register: Callable taking one Behavior subclass.
    """


@hookspec
def register_learned_rewards(register: Callable[[type], None]) -> None:
    """Register learned intrinsic rewards (subclasses of :class:`devlearn.LearnedReward`).

    Call ``register(LearnedRewardClass)`` once per term. A learned reward is a model trained
    in the learner on each rollout batch (e.g. random network distillation, a forward
    model); any behaviour's run adds it by config, ``--set curiosity=NAME[,NAME...]``, with
    options ``--set learned.NAME.OPTION=VALUE``. The class's ``name`` must be unique across
    installed plugins (lower_snake_case) and its ``config_class`` a dataclass subclassing
    :class:`devlearn.LearnedRewardConfig`; a duplicate is reported with both plugins' names
    and the second registration is ignored.

    Args:
        register: Callable taking one LearnedReward subclass.
    """
