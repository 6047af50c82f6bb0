"""The Behavior contract: a small core every behaviour writes, and optional capabilities in
groups, each declared with a default (never found by ``hasattr``)."""

from __future__ import annotations

import inspect
import re
from dataclasses import dataclass, field
from pathlib import Path

import pytest

import devlearn
from devlearn.api.behavior import (
    BEHAVIOR_CORE,
    BEHAVIOR_OPTIONAL,
    Behavior,
    BehaviorConfig,
    Evaluator,
)
from devlearn.api.errors import UsageError
from devlearn.api.rewards import RewardTermCfg
from devlearn.testing import TinyBehavior
from devlearn.testing.fake_infant import TinyConfig


def public_members(cls: type) -> set[str]:
    """Every public attribute and method ``cls`` declares (annotated or assigned)."""
    declared = set(vars(cls)) | set(vars(cls).get("__annotations__", {}))
    return {n for n in declared if not n.startswith("_")}


def test_every_public_member_is_core_or_in_one_optional_group():
    optional = [name for group in BEHAVIOR_OPTIONAL.values() for name in group]
    listed = [*BEHAVIOR_CORE, *optional]
    assert len(listed) == len(set(listed))  # once each
    assert set(listed) == public_members(Behavior)


def test_the_core_is_at_most_six_methods_two_of_them_abstract():
    methods = [n for n in BEHAVIOR_CORE if callable(getattr(Behavior, n, None))]
    assert len(methods) <= 6
    assert Behavior.__abstractmethods__ == {"observe", "network"}
    assert set(BEHAVIOR_CORE) - set(methods) == {"name", "scene", "config_class"}


def test_every_optional_member_has_a_default():
    behavior = TinyBehavior()
    for group, names in BEHAVIOR_OPTIONAL.items():
        for name in names:
            assert name not in Behavior.__abstractmethods__, (group, name)
            assert hasattr(Behavior, name), f"{group}: {name} has no default"
    # the evaluation extras' defaults say "as trained"
    assert Behavior.eval_start(behavior) is None and Behavior.eval_stage(behavior) is None
    assert Behavior.run_metrics(behavior) is None
    assert Evaluator().episode_record() is None and Evaluator.mergeable is False


def test_the_class_source_lists_the_core_first():
    """In ``Behavior`` and the class ``devlearn new`` writes, every core member comes before
    every optional one."""
    source = inspect.getsource(Behavior)
    template = (
        Path(devlearn.__file__).parent / "templates" / "plugin" / "behavior.py.tmpl"
    ).read_text()
    template = template[template.index("(devlearn.Behavior):") :]
    optional = {n for names in BEHAVIOR_OPTIONAL.values() for n in names}
    for text in (source, template):
        order = [
            m.group(1) or m.group(2)
            for m in re.finditer(r"^    (?:def (\w+)|(\w+)(?:: [^=\n]+)? =?)", text, re.MULTILINE)
        ]
        written = [n for n in order if n in optional or n in BEHAVIOR_CORE]
        last_core = max(i for i, n in enumerate(written) if n in BEHAVIOR_CORE)
        first_optional = min(i for i, n in enumerate(written) if n in optional)
        assert last_core < first_optional, written


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
