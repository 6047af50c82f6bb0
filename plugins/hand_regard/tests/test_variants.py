"""Config switches: the reward (paper or bilateral) and the infant's appearance (skin or
mittens), and old runs without these keys loading as they were trained."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from devlearn_hand_regard import HandRegard, HandRegardConfig
from fake_sitting import FakeSittingInfant

from devlearn.api.errors import UsageError
from devlearn.testing import Play, config_round_trip, load_saved_config, run_config

ROOT = Path(__file__).resolve().parents[3]
PAPER_TERMS = ["hand_count", "motion", "living_penalty"]


def _names(config: HandRegardConfig) -> list[str]:
    return [t.name for t in HandRegard(config).reward_terms()]


def _bilateral_weight(config: HandRegardConfig, weight: float) -> HandRegardConfig:
    config.rewards["bilateral_balance"].weight = weight
    return config


def test_paper_reward_has_no_bilateral_term():
    # The paper's reward (sec. II-B4) whatever the bilateral weight says.
    assert _names(HandRegardConfig(reward="paper")) == PAPER_TERMS
    assert _names(_bilateral_weight(HandRegardConfig(reward="paper"), 2.0)) == PAPER_TERMS


def test_bilateral_reward_adds_the_bilateral_term():
    assert _names(HandRegardConfig(reward="bilateral")) == PAPER_TERMS + ["bilateral_balance"]
    config = _bilateral_weight(HandRegardConfig(reward="bilateral"), 0.5)
    terms = HandRegard(config).reward_terms()
    assert terms[-1].weight == 0.5


def test_reach_into_view_is_off_by_default_and_never_in_the_papers_reward():
    config = HandRegardConfig(reward="bilateral")
    assert config.rewards["reach_into_view"].weight == 0.0
    config.rewards["reach_into_view"].weight = 1.0
    assert _names(config) == PAPER_TERMS + ["bilateral_balance", "reach_into_view"]
    config.reward = "paper"
    assert _names(config) == PAPER_TERMS


def test_reward_switch_on_the_command_line():
    from devlearn.testing import run_command

    done = run_command("config", "hand_regard", "--json", "--set", "behavior.reward=paper")
    assert done.code == 0, done.err
    rows = {r["key"]: r for r in json.loads(done.out)}
    assert rows["behavior.reward"]["default"] == "paper"
    doc = rows["behavior.reward"]["doc"]
    assert "paper" in doc and "bilateral" in doc
    assert rows["behavior.appearance"]["doc"]
    cfg = run_config(HandRegard, ["behavior.reward=paper"])
    assert _names(cfg.behavior) == PAPER_TERMS


@pytest.mark.parametrize(
    ("key", "value", "valid"),
    [
        ("reward", "papr", "paper, bilateral"),
        ("appearance", "gloves", "two_colour_mittens, mittens, skin"),
    ],
)
def test_unknown_choice_names_the_valid_ones(key, value, valid):
    behavior = HandRegard(HandRegardConfig(**{key: value}))
    with pytest.raises(UsageError, match=f"unknown behavior.{key} '{value}'; valid: {valid}"):
        behavior.reward_terms() if key == "reward" else behavior.episode().infant_options


@pytest.mark.parametrize("appearance", ["skin", "mittens"])
def test_env_builds_the_infant_in_the_configured_appearance(appearance):
    built = []

    def factory(scene, senses, **options):
        built.append((scene, options))
        return FakeSittingInfant(scene, senses)

    behavior = HandRegard(HandRegardConfig(appearance=appearance))
    Play(behavior, infant_factory=factory)
    assert built == [("sitting_babybench", {"appearance": appearance, "start": "babybench"})]


def test_old_run_config_loads_with_mittens_and_the_bilateral_term():
    # results/hand_regard/run was trained before these keys existed: mittens, bilateral term.
    saved = json.loads((ROOT / "results/hand_regard/run/config.json").read_text())
    assert "appearance" not in saved["behavior"] and "reward" not in saved["behavior"]
    cfg = load_saved_config(saved, HandRegard)
    assert cfg.behavior.appearance == "mittens" and cfg.behavior.reward == "bilateral"
    assert "bilateral_balance" in _names(cfg.behavior)
    # Its policy file (in git history since 2d704d9) carried this config: the old scene.
    behavior = HandRegard(cfg.behavior)
    assert behavior.episode().infant_options == {"appearance": "mittens", "start": "rest"}
    assert behavior.scene == "sitting" and behavior.config.policy == "cnn"
    # A config saved now keeps its own values; no saved behaviour section: today's defaults.
    fresh = run_config(HandRegard, ["behavior.appearance=skin", "behavior.reward=paper"])
    again = config_round_trip(fresh, HandRegard).behavior
    assert (again.appearance, again.reward) == ("skin", "paper")
    assert load_saved_config({}, HandRegard).behavior.appearance == HandRegardConfig().appearance


def test_policy_spread_bound_reaches_the_network():
    # Default: the paper's unbounded spread, as every issue-19 run trained.
    assert HandRegard(HandRegardConfig()).network().max_std == 0.0
    spec = HandRegard(HandRegardConfig(max_std=1.0)).network()
    assert spec.max_std == 1.0 and spec.init_std == 0.5


@pytest.mark.parametrize("max_std", [-1.0, 0.3, 0.5])
def test_policy_spread_bound_must_exceed_the_initial_spread(max_std):
    """The core's NetworkSpec check answers for this behaviour too, at config time."""
    with pytest.raises(UsageError, match="max_std must be 0 \\(unbounded\\) or above init_std=0.5"):
        run_config(HandRegard, [f"behavior.max_std={max_std}"])
