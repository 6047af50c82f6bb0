"""Plugin discovery: loading, isolation of broken plugins, duplicates, disabling."""

from __future__ import annotations

import dataclasses
import types

import pytest
from fake_plugins import fake_plugin

from devlearn import Behavior, hookimpl
from devlearn.api.errors import UsageError
from devlearn.plugins import PluginRegistry, PluginSource, entry_point_sources


@dataclasses.dataclass
class _Config:
    """No options."""


def _behavior(name: str) -> type[Behavior]:
    class _B(Behavior):
        """A test behaviour."""

        scene = "crib"
        config_class = _Config

        def observe(self, batch, facts):
            return {}

        def network(self):
            raise NotImplementedError

        def reward_terms(self):
            return []

    _B.name = name
    return _B


def _plugin(name: str, *behaviors: type[Behavior]) -> PluginSource:
    return fake_plugin(name, "register_behaviors", *behaviors, version="1.2")


def _raising_loader():
    raise ImportError("No module named 'missing_dependency'")


def test_good_plugins_register_their_behaviors():
    registry = PluginRegistry([_plugin("a", _behavior("reach")), _plugin("b", _behavior("kick"))])
    assert list(registry.behaviors()) == ["kick", "reach"]
    assert registry.plugins["a"].behaviors == ["reach"]
    assert registry.plugins["a"].hooks == ["register_behaviors"]
    assert registry.plugin_of("kick").distribution == "dist-b"
    assert registry.errors == []


def test_unknown_behavior_lists_installed():
    registry = PluginRegistry([_plugin("a", _behavior("reach"), _behavior("kick"))])
    with pytest.raises(UsageError, match=r"unknown behavior 'rech'; installed: kick, reach"):
        registry.behavior("rech")


def test_import_error_is_isolated():
    broken = PluginSource("broken", _raising_loader, "dist-broken", "0.1")
    registry = PluginRegistry([broken, _plugin("good", _behavior("reach"))])
    assert "reach" in registry.behaviors()
    assert "missing_dependency" in registry.plugins["broken"].error
    assert registry.errors[0].startswith("plugin 'broken' (dist-broken):")


def test_wrong_hook_signature_is_isolated():
    module = types.ModuleType("wrong")

    @hookimpl
    def register_behaviors(register, extra):
        pass

    module.register_behaviors = register_behaviors
    registry = PluginRegistry(
        [PluginSource("wrong", module, "dist-wrong"), _plugin("good", _behavior("reach"))]
    )
    assert "extra" in registry.plugins["wrong"].error
    assert list(registry.behaviors()) == ["reach"]


def test_unknown_hook_name_is_reported():
    module = types.ModuleType("typo")

    @hookimpl
    def register_behavior(register):  # missing "s"
        pass

    module.register_behavior = register_behavior
    registry = PluginRegistry([PluginSource("typo", module, "dist-typo")])
    assert "unknown hook 'register_behavior'" in registry.plugins["typo"].error


def test_duplicate_behavior_names_both_plugins():
    registry = PluginRegistry(
        [_plugin("first", _behavior("reach")), _plugin("second", _behavior("reach"))]
    )
    assert registry.plugin_of("reach").name == "first"
    assert any("'second'" in e and "'first'" in e and "reach" in e for e in registry.errors)


def test_invalid_registration_is_reported():
    registry = PluginRegistry([_plugin("bad", object)])  # type: ignore[arg-type]
    assert "not a Behavior subclass" in registry.plugins["bad"].error


def test_disabled_plugin_is_skipped():
    registry = PluginRegistry([_plugin("a", _behavior("reach"))], disabled={"a"})
    assert registry.plugins["a"].disabled
    assert registry.behaviors() == {}


def test_disabling_through_environment(monkeypatch, tmp_path):
    monkeypatch.setenv("DEVLEARN_CONFIG_DIR", str(tmp_path))
    monkeypatch.setenv("DEVLEARN_DISABLE_PLUGINS", "a, c")
    registry = PluginRegistry([_plugin("a", _behavior("reach")), _plugin("b", _behavior("kick"))])
    assert list(registry.behaviors()) == ["kick"]


def test_builtin_plugins_are_entry_points():
    names = {s.name for s in entry_point_sources()}
    assert {"self_touch", "hand_regard"} <= names


def test_create_turns_config_errors_into_usage_errors():
    class Picky(_behavior("picky")):
        """Rejects its config."""

        def __init__(self, config=None):
            raise ValueError("unknown curriculum 'bogus'; valid: a, b")

    registry = PluginRegistry([_plugin("p", Picky)])
    with pytest.raises(UsageError, match=r"invalid config for behavior 'picky': unknown curr"):
        registry.create("picky")
