"""The CLI's plugin listing and its one-line errors with exit code 2."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest


def devlearn(*args: str, env: dict | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "devlearn.cli", *args],
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
    )


def test_plugins_json_lists_builtin_and_example():
    result = devlearn("plugins", "--json")
    assert result.returncode == 0, result.stderr
    plugins = {p["name"]: p for p in json.loads(result.stdout)}
    for name in ("self_touch", "hand_regard", "hand_to_mouth"):
        assert set(plugins[name]) >= {"name", "distribution", "version", "behaviors", "hooks"}
        assert plugins[name]["behaviors"] == [name]
        assert plugins[name]["hooks"] == ["register_behaviors"]
    assert plugins["hand_to_mouth"]["distribution"] == "devlearn-hand-to-mouth"


def test_plugins_table():
    result = devlearn("plugins")
    assert result.returncode == 0
    assert "self_touch" in result.stdout and "devlearn-self-touch" in result.stdout


def test_unknown_behavior_is_one_line_exit_2():
    result = devlearn("info", "self_tuch")
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    assert "unknown behavior 'self_tuch'; installed:" in result.stderr
    assert "self_touch" in result.stderr


def test_disable_plugin_for_one_command():
    result = devlearn("--disable-plugin", "hand_to_mouth", "plugins", "--json")
    plugins = {p["name"]: p for p in json.loads(result.stdout)}
    assert plugins["hand_to_mouth"]["disabled"] is True
    assert plugins["hand_to_mouth"]["behaviors"] == []


def test_disabling_a_plugin_that_is_not_installed_is_refused():
    # issue #55, fault 14: a misspelt name said nothing and left the plugin it meant enabled
    result = devlearn("--disable-plugin", "hand_to_mouht", "plugins")
    assert result.returncode == 2 and result.stdout == ""
    assert result.stderr.startswith(
        "devlearn: error: --disable-plugin hand_to_mouht: no such plugin; installed: "
    )
    assert result.stderr.count("\n") == 1 and "hand_to_mouth, self_touch" in result.stderr


def test_a_damaged_settings_file_disables_nothing(tmp_path):
    # issue #55, fault 8: a deep or odd plugins.json was a traceback on every command
    import os

    env = dict(os.environ, DEVLEARN_CONFIG_DIR=str(tmp_path))
    for text in (
        '{"disabled": ' + "[" * 100_000 + "]" * 100_000 + "}",
        "[1]",
        '{"disabled": [[1]]}',
    ):
        (tmp_path / "plugins.json").write_text(text)
        result = devlearn("plugins", "--json", env=env)
        assert result.returncode == 0, result.stderr
        assert not any(p["disabled"] for p in json.loads(result.stdout))


def test_disable_and_enable_persistently(tmp_path):
    import os

    env = dict(os.environ, DEVLEARN_CONFIG_DIR=str(tmp_path))
    assert devlearn("plugins", "--disable", "hand_to_mouth", env=env).returncode == 0
    result = devlearn("info", "hand_to_mouth", env=env)
    assert result.returncode == 2 and "unknown behavior 'hand_to_mouth'" in result.stderr
    assert devlearn("plugins", "--enable", "hand_to_mouth", env=env).returncode == 0
    plugins = json.loads(devlearn("plugins", "--json", env=env).stdout)
    assert not next(p for p in plugins if p["name"] == "hand_to_mouth")["disabled"]


def test_unknown_plugin_to_disable():
    result = devlearn("plugins", "--disable", "nope")
    assert result.returncode == 2 and "unknown plugin 'nope'" in result.stderr


@pytest.mark.slow
@pytest.mark.parametrize("behavior,action_dim", [("self_touch", 30), ("hand_regard", 17)])
def test_info_json(behavior, action_dim):
    result = devlearn("info", behavior, "--json")
    assert result.returncode == 0, result.stderr
    info = json.loads(result.stdout)
    keys = {
        "behavior",
        "observations",
        "action_dim",
        "touch_sensors",
        "skin_regions",
        "regions_per_side",
        "physics_timestep",
        "action_repeat",
        "decision_interval",
        "episode_steps",
    }
    assert keys <= set(info)
    assert info["behavior"] == behavior and info["action_dim"] == action_dim
    assert info["skin_regions"] == 68 and info["regions_per_side"] == 34
    assert 4500 <= info["touch_sensors"] <= 7000
    assert info["physics_timestep"] == 0.005 and info["episode_steps"] == 1000
    assert "control_timestep" not in info  # it read 0.005 where a decision is every 0.025 s
    assert info["action_repeat"] == 5 and info["decision_interval"] == 0.025
    assert all(isinstance(s, list) for s in info["observations"].values())
