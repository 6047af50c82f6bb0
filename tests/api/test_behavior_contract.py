"""The Behavior contract: optional capabilities are composed objects with defaults (never
found by ``hasattr`` or by checking overrides), and a behaviour checks its config."""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import pytest

import devlearn
from devlearn.api.behavior import Behavior, BehaviorConfig, Evaluator
from devlearn.api.capabilities import EpisodeHooks
from devlearn.api.errors import UsageError
from devlearn.api.rewards import RewardTermCfg
from devlearn.testing import TinyBehavior
from devlearn.testing.fake_infant import TinyConfig


def test_the_composed_capabilities_default_to_nothing_special():
    behavior = TinyBehavior()
    assert Behavior.__abstractmethods__ == {"observe", "network"}
    episode = Behavior.episode(behavior)
    assert episode.senses == ("touch", "proprioception", "vestibular") and episode.seconds is None
    assert episode.facts_every_physics_step and type(episode.hooks) is EpisodeHooks
    # the evaluation's defaults say "as trained"
    evaluation = Behavior.evaluation(behavior)
    assert evaluation.start is None and evaluation.stage is None
    assert evaluation.run_metrics is None and evaluation.render_frame is None
    assert type(evaluation.evaluator(True)) is Evaluator
    assert Evaluator().episode_record() is None and Evaluator.mergeable is False
    assert type(Behavior.artifacts(behavior)).policy_artifacts(None) == {}
    about = Behavior.about
    assert about.presets == {} and about.train_defaults == {}
    assert about.length_defaults(100) == {} and about.paper_figures({}) is None


class Hold(devlearn.IntrinsicReward):
    """A reward term for the config checks below (pays nothing)."""

    name = "hold"

    def __init__(self, weight: float = 1.0, scale: float = 1.0) -> None:
        super().__init__(weight)
        self.scale = scale

    def __call__(self, ctx: devlearn.StepContext) -> float:
        return 0.0


@dataclass
class CheckedConfig(TinyConfig, BehaviorConfig):
    """A tiny config that declares a check and a reward table."""

    rewards: dict[str, RewardTermCfg] = field(
        default_factory=lambda: {"hold": RewardTermCfg(Hold, 0.5)}
    )

    def validate(self) -> None:
        if self.target < 0:
            raise ValueError(f"target must be at least 0, got {self.target}")


class Checked(TinyBehavior):
    config_class = CheckedConfig


def test_a_behaviour_checks_its_config_whenever_it_is_built():
    # ``--set`` assigns fields after the config was made: the behaviour built on it checks
    # them (its config's declared validate, and the reward table), whoever builds it.
    assert Checked().config.rewards["hold"].weight == 0.5
    config = CheckedConfig()
    config.target = -1.0
    with pytest.raises(ValueError, match="target must be at least 0, got -1.0"):
        Checked(config)
    config = CheckedConfig()
    config.rewards["hold"].weight = 1e9
    with pytest.raises(UsageError, match=r"behavior.rewards.hold.weight must be a finite"):
        Checked(config)
    config = CheckedConfig()
    config.rewards["hold"].params["speed"] = 2.0
    with pytest.raises(UsageError, match="'behavior.rewards.hold.params.speed' of Hold; valid"):
        Checked(config)
    config = CheckedConfig()
    config.rewards["hold"].cls = "nowhere:Hold"
    with pytest.raises(UsageError, match="behavior.rewards.hold.cls: unknown reward term class"):
        Checked(config)


class Stranger(devlearn.IntrinsicReward):
    """Another behaviour's term (as hand_to_mouth's ``MouthContact`` is to self-touch): it
    reads a fact this behaviour never computes."""

    def __call__(self, ctx: devlearn.StepContext) -> float:
        return float(ctx.facts["mouth_contact"])


def test_a_config_names_only_the_terms_its_behaviour_declares():
    # another behaviour's term passed the check and failed at step 0, after a run folder was
    # written; a private or abstract class or the core's adapter crashed with a TypeError
    # (issue #55, fault 3). The one check refuses each, naming the declared terms.
    hold = f"{Hold.__module__}:Hold"
    for cls in (
        f"{Stranger.__module__}:Stranger",
        "devlearn.api.rewards:BatchedFromPerEnv",
        "devlearn.api.rewards:BatchedIntrinsicReward",
        "devlearn_self_touch.rewards:_LifetimeNovelty",
    ):
        config = CheckedConfig()
        config.rewards["hold"].cls = cls
        expected = f"behavior.rewards.hold.cls: unknown reward term class '{cls}': a config "
        with pytest.raises(UsageError, match=re.escape(expected) + f".*; valid: {hold}$"):
            Checked(config)
        config.rewards = {"hold": RewardTermCfg(Hold), "more": RewardTermCfg(cls)}
        with pytest.raises(UsageError, match=r"behavior.rewards.more.cls: unknown reward term"):
            Checked(config)
    config = CheckedConfig()
    config.rewards["also"] = RewardTermCfg(Hold, 2.0)  # a declared class, twice: fine
    assert list(Checked(config).config.rewards) == ["hold", "also"]


def test_a_plain_dataclass_config_declares_nothing():
    # BehaviorConfig is optional: a plain dataclass works and has no check or legacy values.
    assert not isinstance(TinyConfig(), BehaviorConfig)
    assert TinyBehavior(TinyConfig(target=-1.0)).config.target == -1.0
    assert BehaviorConfig.LEGACY_DEFAULTS == {}
