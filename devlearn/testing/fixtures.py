"""Fixtures for plugin tests: a registry built from classes (or the installed plugins':
:class:`PluginRegistry`), module-scoped infants, and the scenes' colours a colour-based
detector must tell apart."""

from __future__ import annotations

import types
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING

import numpy as np

from devlearn.api.behavior import Behavior
from devlearn.infant.body_table import SKIN_RGBA
from devlearn.infant.scenes import TOY_COLOURS
from devlearn.plugins import PluginRegistry, PluginSource

__all__ = [
    "SKIN_RGBA",
    "TOY_COLOURS",
    "PluginRegistry",
    "crib_infant",
    "registry_for",
    "sitting_infant",
]

if TYPE_CHECKING:
    from devlearn.infant import Infant


def registry_for(
    *behaviors: type[Behavior], name: str = "test_plugin", learned_rewards: tuple[type, ...] = ()
) -> PluginRegistry:
    """Build a registry holding the given behaviour classes (and learned rewards), as if one
    plugin registered them."""
    from devlearn.api.hookspecs import hookimpl

    module = types.ModuleType(name)

    @hookimpl
    def register_behaviors(register: Callable[[type], None]) -> None:
        for behavior in behaviors:
            register(behavior)

    module.register_behaviors = register_behaviors  # type: ignore[attr-defined]
    if learned_rewards:

        @hookimpl
        def register_learned_rewards(register: Callable[[type], None]) -> None:
            for term in learned_rewards:
                register(term)

        module.register_learned_rewards = register_learned_rewards  # type: ignore[attr-defined]
    return PluginRegistry([PluginSource(name, module, "test-dist", "0")], disabled=())


def _infant_fixture(scene: str, senses: tuple[str, ...]) -> Callable[[], Iterator[Infant]]:
    import pytest

    @pytest.fixture(scope="module")
    def fixture() -> Iterator[Infant]:
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
