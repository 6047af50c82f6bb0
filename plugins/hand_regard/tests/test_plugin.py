"""The plugin is found through its entry point and passes devlearn's conformance checks."""

from __future__ import annotations

import pytest
from devlearn_hand_regard import HandRegard

from devlearn.testing import (
    PluginRegistry,
    check_behavior,
    check_behavior_class,
    check_curriculum,
    check_gymnasium,
    check_reward_terms,
)

try:
    from devlearn import build_infant  # noqa: F401

    HAS_INFANT = True
except ImportError:  # the body is built in parallel; until it lands these tests skip
    HAS_INFANT = False


def test_entry_point_registers_hand_regard():
    registry = PluginRegistry(disabled=())
    assert registry.behavior("hand_regard") is HandRegard
    info = registry.plugin_of("hand_regard")
    assert info.distribution == "devlearn-hand-regard"
    assert info.error is None


def test_class_terms_and_curriculum_conform():
    check_behavior_class(HandRegard)
    behavior = HandRegard()
    terms = behavior.reward_terms()
    check_reward_terms(terms)
    assert [t.name for t in terms] == [
        "hand_count",
        "motion",
        "living_penalty",
        "bilateral_balance",
    ]
    check_curriculum(behavior.curriculum())


def test_zero_weight_switches_a_term_off():
    from devlearn_hand_regard import HandRegardConfig

    config = HandRegardConfig()
    config.rewards["bilateral_balance"].weight = 0.0
    terms = HandRegard(config).reward_terms()
    assert "bilateral_balance" not in [t.name for t in terms]


@pytest.mark.slow
@pytest.mark.skipif(not HAS_INFANT, reason="devlearn.infant has not landed")
@pytest.mark.filterwarnings("ignore:hand_regard. no calibrated hand detector")
def test_conformance_with_the_real_infant():
    # Without prepare() the detector is uncalibrated (sees nothing): conformance is about
    # shapes and contracts; test_calibration covers the calibrated detector on real renders.
    shapes = check_behavior(HandRegard, steps=10)
    assert shapes["hands_seen"] == (16,) and shapes["proprioception"] == (102,)


@pytest.mark.skipif(not HAS_INFANT, reason="devlearn.infant has not landed")
@pytest.mark.parametrize("policy", ["proprio", "cnn"])
def test_gymnasium_conformance(detector_file, policy):
    # a calibrated detector given, as a run shares one (no babbling); cnn: the eye images
    # as uint8 observation groups
    settings = {"behavior.detector_file": str(detector_file), "behavior.policy": policy}
    check_gymnasium(HandRegard, settings, vector_steps=1)
