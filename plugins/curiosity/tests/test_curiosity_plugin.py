"""The plugin is found by its entry point; both terms pass devlearn's conformance check."""

from __future__ import annotations

import pytest
from devlearn_curiosity import RND, ForwardModel, ForwardModelConfig, RNDConfig

from devlearn.testing import PluginRegistry, check_learned_reward

HAND_REGARD_SHAPES = {"left_eye": (16, 16, 3), "right_eye": (16, 16, 3), "proprioception": (9,)}


def test_entry_point_registers_both_terms():
    registry = PluginRegistry(disabled=())
    assert registry.learned_reward("rnd") is RND
    assert registry.learned_reward("forward_model") is ForwardModel
    info = registry.plugins["curiosity"]
    assert info.distribution == "devlearn-curiosity" and info.error is None
    assert info.learned_rewards == ["rnd", "forward_model"]


def test_rnd_conforms_and_measures_the_vector_observations():
    term = check_learned_reward(RND, HAND_REGARD_SHAPES)
    assert term.groups == ["proprioception"]  # the eyes are images: rsl-rl's RND takes 1-D
    assert not any(p.requires_grad for p in term.model.target.parameters())


def test_forward_model_conforms_and_predicts_the_eyes_by_default():
    term = check_learned_reward(ForwardModel, HAND_REGARD_SHAPES, action_dim=17)
    assert term.groups == ["left_eye", "right_eye"]
    trained = [n for n, p in term.model.named_parameters() if p.requires_grad]
    assert trained and all(n.startswith("predictor.") for n in trained)  # fixed features


def test_observation_groups_are_checked():
    with pytest.raises(ValueError, match="rnd works on 1-D observations"):
        RND(RNDConfig(observations=["left_eye"]), HAND_REGARD_SHAPES, 17)
    with pytest.raises(ValueError, match="unknown observation 'nose'; available: left_eye"):
        ForwardModel(ForwardModelConfig(observations=["nose"]), HAND_REGARD_SHAPES, 17)
    term = ForwardModel(ForwardModelConfig(observations=["proprioception"]), HAND_REGARD_SHAPES, 3)
    assert term.groups == ["proprioception"]
