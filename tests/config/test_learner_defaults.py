"""Issue #38: issue #28's evidence-based learner is the core default for every behaviour, a
behaviour overrides only what its own evidence supports, and runs saved before load as they
were trained."""

from __future__ import annotations

import dataclasses
import json
from typing import Any

import pytest

import devlearn
from devlearn.cli import main
from devlearn.config.run_config import (
    from_dict,
    new_config,
    to_dict,
)
from devlearn.testing import run_config
from devlearn.testing.fake_infant import TinyBehavior

LEARNER = {
    "env.action_repeat": 5,
    "ppo.gamma": 0.99,
    "ppo.num_steps_per_env": 64,
    "ppo.schedule": "fixed",
    "ppo.normalize_rewards": True,
    "network.layout": "separate",
    "network.head": "free",
    "network.init_std": 0.0,  # the free head's own: 1.0
    "network.final_std": 0.3,
    "network.encoders": "flat",
    "network.activation": "tanh",
    "network.init": "orthogonal",
    "ppo.adam_eps": 1e-5,
    "ppo.normalize_advantage_per_mini_batch": True,
    "network.exploration_beta": 1.0,
    "ppo.full_rate_steps": 1_024_000,
}
"""The values results/learner/README.md (issue #28) chose (decision rate, discount, rollout
length, schedule, reward normalisation, layout) and results/learners/README.md (issue #54:
network, initialisation, head and its spread, Adam's epsilon, advantages, exploration, the
step size of long runs)."""
ISSUE_28 = {
    "network.head": "gaussian",
    "network.final_std": 0.0,
    "network.encoders": "behavior",
    "network.activation": "relu",
    "network.init": "torch",
    "ppo.adam_eps": 1e-8,
    "ppo.normalize_advantage_per_mini_batch": False,
    "network.exploration_beta": 0.0,
    "ppo.full_rate_steps": 0,
}
"""Issue #28's learner where issue #54 changed it: what hand regard keeps."""
OLD = {
    "env.action_repeat": 1,
    "ppo.schedule": "adaptive",
    "ppo.normalize_rewards": False,
    "network.layout": "separate",
    "network.head": "paper",
    "network.exploration_beta": 0.0,
    "ppo.full_rate_steps": 0,
}
"""What a run saved before those fields existed was trained with."""


class Plain(TinyBehavior):
    """A third-party behaviour that declares no learner settings."""

    name = "plain"
    about = devlearn.About()


def value(cfg: Any, key: str) -> Any:
    section, name = key.split(".")
    return getattr(getattr(cfg, section), name)


def test_the_core_defaults_are_the_evidence_based_learner():
    cfg = new_config(Plain)
    assert {key: value(cfg, key) for key in LEARNER} == LEARNER
    from pathlib import Path

    from devlearn.config.run_config import LEARNER_EVIDENCE

    root = Path(__file__).resolve().parents[2]
    assert "action_repeat" in (root / "results/learner/README.md").read_text()  # issue #28
    assert "final_std" in (root / LEARNER_EVIDENCE).read_text()  # issue #54


@pytest.mark.parametrize("behavior", ["self_touch", "hand_to_mouth"])
def test_a_behaviour_without_evidence_of_its_own_gets_the_core_learner(behavior, capsys):
    assert main(["config", behavior, "--json"]) == 0
    rows = {row["key"]: row for row in json.loads(capsys.readouterr().out)}
    for key, expected in LEARNER.items():
        assert rows[key]["default"] == expected, key
        assert rows[key]["set_by"] == "core", key  # said where it comes from


def test_hand_regard_overrides_only_what_its_evidence_supports(capsys):
    assert main(["config", "hand_regard", "--json"]) == 0
    rows = {row["key"]: row for row in json.loads(capsys.readouterr().out)}
    learner = {k: (rows[k]["default"], rows[k]["set_by"]) for k in [*LEARNER, "ppo.entropy_coef"]}
    assert learner == {**{k: (v, "core") for k, v in LEARNER.items()},
                       **{k: (v, "behavior") for k, v in ISSUE_28.items()},
                       "ppo.entropy_coef": (0.0, "behavior")}  # fmt: skip


def test_a_run_saved_before_loads_as_it_was_trained():
    cfg = from_dict({"behavior_name": "plain"}, Plain)
    assert {key: value(cfg, key) for key in OLD} == OLD


def test_a_run_saved_before_pink_exploration_explores_white():
    """Issue #54: a config saved with a ``network`` section but before
    ``network.exploration_beta`` trained with white exploration; a new run gets pink."""
    saved = from_dict({"behavior_name": "plain", "network": {"head": "free"}}, Plain)
    assert saved.network.exploration_beta == 0.0
    assert new_config(Plain).network.exploration_beta == 1.0


def test_a_new_runs_config_file_gets_todays_defaults():
    cfg = from_dict({"behavior_name": "plain"}, Plain, run_config(Plain))
    assert {key: value(cfg, key) for key in LEARNER} == LEARNER
    assert to_dict(cfg) == to_dict(run_config(Plain))


def test_run_config_with_an_empty_file_trains_todays_learner(monkeypatch, tmp_path, capsys):
    import functools

    import devlearn.plugins
    from devlearn.testing import registry_for
    from devlearn.testing.fake_infant import fake_infant_factory

    registry = registry_for(Plain)
    monkeypatch.setattr(devlearn.plugins, "PluginRegistry", lambda *a, **k: registry)
    fake = functools.partial(fake_infant_factory, episode_steps=10)
    monkeypatch.setattr("devlearn.env.behavior_env.build_default_infant", fake)
    (tmp_path / "empty.json").write_text("{}")
    out = tmp_path / "run"
    argv = ["run", "plain", "--config", str(tmp_path / "empty.json"), "--out", str(out),
            "--steps", "640", "--envs", "2", "--workers", "0"]  # fmt: skip
    assert main(argv) == 0
    saved = json.loads((out / "config.json").read_text())
    assert {k: saved[k.split(".")[0]][k.split(".")[1]] for k in LEARNER} == LEARNER
    assert dataclasses.asdict(new_config(Plain).ppo)["gamma"] == saved["ppo"]["gamma"]
