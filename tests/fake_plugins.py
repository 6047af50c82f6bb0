"""Plugins made in a test: a module whose one hook registers what the test gives it."""

from __future__ import annotations

import types
from collections.abc import Callable

from devlearn import hookimpl
from devlearn.plugins import PluginSource


def fake_plugin(name: str, hook: str, *registered: object, version: str = "1") -> PluginSource:
    """The plugin ``name`` (distribution ``dist-NAME``) whose hook ``hook`` (e.g.
    ``register_behaviors``) registers each of ``registered``, in order."""
    module = types.ModuleType(name)

    @hookimpl
    def register_all(register: Callable[[object], None]) -> None:
        for thing in registered:
            register(thing)

    setattr(module, hook, register_all)
    return PluginSource(name, module, f"dist-{name}", version)
