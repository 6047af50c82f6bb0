"""Issue #31: every behaviour's reward terms are config keys (``behavior.rewards.TERM.weight``,
``.params.NAME``), and configs saved with the old ``weight_*`` fields load into them."""

from __future__ import annotations

import json

import pytest

from devlearn.api.errors import UsageError
from devlearn.config.run_config import RunConfig, from_dict, to_dict
from devlearn.config.values import apply_overrides, valid_keys
from devlearn.plugins import PluginRegistry
from devlearn.testing import run_config


@pytest.fixture(scope="module")
def registry():
    return PluginRegistry()


@pytest.mark.parametrize(
    "name, term",
    [("self_touch", "balance"), ("hand_regard", "motion"), ("hand_to_mouth", "action_cost")],
)
def test_any_term_weight_is_set_from_the_command_line(registry, name, term):
    cls = registry.behavior(name)
    cfg = run_config(cls, [f"behavior.rewards.{term}.weight=0"])
    assert cfg.behavior.rewards[term].weight == 0.0
    assert f"behavior.rewards.{term}.weight" in valid_keys(cfg)
    behavior = registry.create(name, cfg.behavior)
    weights = {t.name: t.weight for t in behavior.reward_terms()}
    assert weights.get(term, 0.0) == 0.0  # hand_regard leaves zero-weight terms out


def test_a_term_param_is_set_and_converted(registry):
    cfg = run_config(
        registry.behavior("self_touch"), ["behavior.rewards.balance.params.tolerance=5"]
    )
    assert cfg.behavior.rewards["balance"].params["tolerance"] == 5
    terms = {t.name: t for t in registry.create("self_touch", cfg.behavior).reward_terms()}
    assert terms["balance"].tolerance == 5


def test_a_misspelled_term_names_the_valid_ones(registry):
    cfg = run_config(registry.behavior("self_touch"))
    with pytest.raises(UsageError, match=r"did you mean 'balance'.*touch_novelty, contact_novelty"):
        apply_overrides(cfg, ["behavior.rewards.balanse.weight=0"])
    with pytest.raises(UsageError, match=r"no 'tolerence'.*valid: reward, tolerance, min_parts"):
        apply_overrides(cfg, ["behavior.rewards.balance.params.tolerence=2"])


def test_an_old_config_with_weight_fields_loads_into_rewards(registry):
    cls = registry.behavior("self_touch")
    saved = to_dict(RunConfig(behavior_name="self_touch", behavior=cls.config_class()))
    old = dict(saved["behavior"])
    del old["rewards"]
    old.update(weight_balance=0.5, balance_min_parts=2, milestones=[10, 20], decay_rate=0.25)
    cfg = from_dict({**saved, "behavior": old}, cls)
    rewards = cfg.behavior.rewards
    assert rewards["balance"].weight == 0.5 and rewards["balance"].params["min_parts"] == 2
    assert list(rewards["diversity_milestones"].params["milestones"]) == [10, 20]
    assert rewards["touch_novelty"].params["rate"] == 0.25
    json.dumps(to_dict(cfg))  # and saves again as JSON


def test_a_saved_new_config_round_trips(registry):
    cls = registry.behavior("hand_regard")
    cfg = run_config(cls, ["behavior.rewards.bilateral_balance.params.horizon=50"])
    again = from_dict(json.loads(json.dumps(to_dict(cfg))), cls)
    assert again.behavior.rewards == cfg.behavior.rewards
