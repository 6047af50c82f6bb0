"""The default recipe (bounded spread, shared memory), the paper preset, and old runs as trained."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from devlearn_self_touch import SelfTouch

import devlearn
from devlearn.api.errors import UsageError
from devlearn.testing import (
    Play,
    PluginRegistry,
    config_round_trip,
    load_saved_config,
    policy_network,
    run_config,
    saved_config,
)

ROOT = Path(__file__).resolve().parents[3]
RESULTS = ROOT / "results/self_touch"


def test_default_is_the_supported_recipe_and_a_short_run():
    cfg = run_config(SelfTouch)
    assert (cfg.behavior.max_std, cfg.behavior.lifetime_memory) == (1.0, "shared")
    from devlearn_self_touch.behavior import DEFAULT_STEPS

    # the README's few-minute run, long enough to show learning (issue #55), its stages halves
    assert cfg.total_steps == DEFAULT_STEPS == 1_024_000
    assert (cfg.behavior.fixed_pose_steps, cfg.behavior.random_pose_steps) == (512_000, 512_000)
    assert cfg.preset == ""


def test_paper_preset_gives_the_papers_values():
    cfg = run_config(SelfTouch, preset="paper")
    assert (cfg.behavior.max_std, cfg.total_steps, cfg.preset) == (0.0, 8_000_000, "paper")
    assert cfg.behavior.lifetime_memory == "shared"  # the paper's one agent
    assert (cfg.behavior.fixed_pose_steps, cfg.behavior.curriculum) == (4_000_000, "two_stage")
    # the command line still wins over the preset
    cfg = run_config(SelfTouch, ["behavior.max_std=2"], preset="paper", total_steps=4096)
    assert (cfg.behavior.max_std, cfg.total_steps) == (2.0, 4096)
    with pytest.raises(UsageError, match="unknown preset 'papr' for self_touch; valid: paper"):
        run_config(SelfTouch, preset="papr")
    with pytest.raises(UsageError, match="'preset' is set with --preset NAME"):
        run_config(SelfTouch, ["preset=paper"])


def test_a_new_config_loads_back_with_its_own_values():
    """LEGACY_DEFAULTS fill only what a saved config lacks."""
    cfg = config_round_trip(run_config(SelfTouch), SelfTouch)
    assert (cfg.behavior.max_std, cfg.behavior.lifetime_memory) == (1.0, "shared")


@pytest.mark.parametrize(
    "run, max_std",
    [("run", 0.0), ("max_std/run", 1.0), ("ablation/ablation_fixed_only", 0.0)],
)
def test_published_runs_load_as_trained(run, max_std):
    """Their configs predate lifetime_memory (and, but for max_std/, max_std): they keep the
    unbounded spread and per-environment memory they were trained with, also on --resume."""
    data = json.loads((RESULTS / run / "config.json").read_text())
    assert "lifetime_memory" not in data["behavior"]
    cfg = load_saved_config(RESULTS / run, PluginRegistry())
    assert (cfg.behavior.max_std, cfg.behavior.lifetime_memory) == (max_std, "per_env")


def test_the_old_runs_policy_is_rebuilt_with_its_unbounded_spread():
    """results/self_touch/run was trained with the paper's softplus spread (~1,000 by the end;
    its policy file is in git history since 2d704d9): a policy of its saved config, rebuilt
    after the default became 1.0, still has that spread."""
    registry = PluginRegistry()
    cfg = load_saved_config(json.loads((RESULTS / "run/config.json").read_text()), SelfTouch)
    assert (cfg.behavior.max_std, cfg.behavior.lifetime_memory) == (0.0, "per_env")
    behavior = registry.create("self_touch", cfg.behavior)
    env = Play(behavior, training=False)
    try:
        env.set_stage(behavior.evaluation().stage)
        [obs] = env.reset()
        saved = policy_network(cfg, behavior, obs, env.action_dim).state_dict()
        actor = policy_network(cfg, behavior, obs, env.action_dim, weights=saved)
    finally:
        env.close()
    assert actor.distribution.max_std == 0.0


def test_a_spread_bound_below_the_initial_spread_is_a_usage_error():
    """The core's NetworkSpec check answers at config time, naming the valid values."""
    with pytest.raises(UsageError, match="max_std must be 0 \\(unbounded\\) or above init_std=0.5"):
        run_config(SelfTouch, ["behavior.max_std=0.3"])


class MouthTouch(devlearn.IntrinsicReward):
    """Another behaviour's term (hand_to_mouth's ``MouthContact``): it reads a fact self-touch
    never computes."""

    def __call__(self, ctx: devlearn.StepContext) -> float:
        return float(ctx.facts["mouth_contact"])


@pytest.mark.parametrize(
    "cls",
    [
        "devlearn.api.rewards:BatchedFromPerEnv",
        "devlearn_self_touch.rewards:_LifetimeNovelty",
        f"{__name__}:MouthTouch",
    ],
)
def test_only_self_touchs_own_terms_may_be_named(cls):
    # issue #55, fault 3: each crashed with a TypeError (or at step 0) instead of a refusal
    expected = (
        f"behavior.rewards.diversity_milestones.cls: unknown reward term class '{cls}': a "
        "config names only the reward terms its behaviour declares; valid: "
        "devlearn_self_touch.activity:ActivityLevel, devlearn_self_touch.activity:ContactTime, "
        "devlearn_self_touch.activity:Effort, devlearn_self_touch.activity:TouchOnset, "
        "devlearn_self_touch.rewards:Balance, devlearn_self_touch.rewards:ContactNovelty, "
        "devlearn_self_touch.rewards:DiversityMilestones, devlearn_self_touch.rewards:TouchNovelty"
    )
    key = "behavior.rewards.diversity_milestones"
    with pytest.raises(UsageError) as refused:
        run_config(SelfTouch, [f"{key}.cls={cls}", f"{key}.params={{}}"])
    assert str(refused.value) == expected
    saved = saved_config(run_config(SelfTouch))
    saved["behavior"]["rewards"]["diversity_milestones"] = {"cls": cls, "weight": 1.0}
    with pytest.raises(UsageError, match=re.escape(expected)):
        load_saved_config(saved, SelfTouch)
