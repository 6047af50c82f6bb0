"""The body map, the behaviour's facts and observations, its curriculum and its evaluator."""

from __future__ import annotations

import dataclasses
import importlib.metadata as metadata
import json

import numpy as np
import pytest
from devlearn_self_touch import SelfTouch, SelfTouchConfig, SelfTouchEvaluator
from devlearn_self_touch.body_map import body_map, hand_touched_parts, sparse_body_map
from self_touch_fakes import FakeInfant, make_ctx

from devlearn import Behavior, Curriculum
from devlearn.testing import PluginRegistry, facts_of, observations_of


def test_entry_point_is_declared_and_registers_self_touch():
    eps = [ep for ep in metadata.entry_points(group="devlearn") if ep.name == "self_touch"]
    assert len(eps) == 1 and eps[0].value == "devlearn_self_touch.plugin"
    registry = PluginRegistry(disabled=())
    assert registry.behavior("self_touch") is SelfTouch
    assert registry.plugin_of("self_touch").distribution == "devlearn-self-touch"
    assert not [e for e in registry.errors if "self_touch" in e]


def test_body_map_is_mean_force_magnitude_per_region():
    sensor_region = np.array([0, 0, 1, 1, 1, 67])
    sizes = np.zeros(68, dtype=int)
    sizes[[0, 1, 67]] = [2, 3, 1]
    touch = np.array([[3, 4, 0], [0, 0, 0], [1, 0, 0], [0, 2, 0], [0, 0, 0], [0, 0, -6]], float)
    g = body_map(touch, sensor_region, sizes)
    assert g.shape == (68,) and g.dtype == np.float32
    assert g[0] == pytest.approx(5.0 / 2)
    assert g[1] == pytest.approx(3.0 / 3)
    assert g[67] == pytest.approx(6.0)
    assert g[2:67].sum() == 0.0
    sparse = sparse_body_map(np.array([0, 2, 3, 5]), touch[[0, 2, 3, 5]], sensor_region, sizes)
    assert np.array_equal(sparse, g)


def test_hand_parts_merge_sides(fake_regions):
    contacts = np.zeros((2, 68), bool)
    contacts[0, [5, 39]] = True  # left hand: left and right side of part 5
    contacts[1, 40] = True
    parts = hand_touched_parts(contacts, fake_regions.parts)
    assert parts.shape == (2, 34)
    assert parts[0].sum() == 1 and parts[0, 5] and parts[1, 6]


def test_facts_touched_sources():
    touch = np.zeros((204, 3), np.float32)
    touch[3 * 20 : 3 * 21, 2] = 0.5  # region 20: the mattress under the back, g = 0.5 N
    touch[3 * 30, 2] = 0.03  # region 30: a hand's light touch, g = 0.01 N
    contacts = np.zeros((2, 68), bool)
    contacts[0, 30] = True
    infant = FakeInfant(touch, contacts)
    facts = facts_of(SelfTouch(), infant)
    assert facts["body_map"][20] == pytest.approx(0.5)
    assert facts["body_map"][30] == pytest.approx(0.01)
    assert np.flatnonzero(facts["touched"]).tolist() == [30]  # default: hands, light touch counts
    assert facts["hand_parts"].shape == (2, 34) and facts["hand_parts"][0, 30]
    literal = facts_of(SelfTouch(SelfTouchConfig(touch_source="threshold")), infant)
    assert np.flatnonzero(literal["touched"]).tolist() == [20]  # the paper's rule: mattress
    either = facts_of(SelfTouch(SelfTouchConfig(touch_source="hands_or_threshold")), infant)
    assert np.flatnonzero(either["touched"]).tolist() == [20, 30]


def test_observations_have_fixed_shapes_and_are_scaled():
    behavior = SelfTouch()
    infant = FakeInfant()
    obs = observations_of(behavior, infant)
    assert set(obs) == {"body_map", "proprioception"}
    assert obs["body_map"].shape == (68,) and obs["body_map"].dtype == np.float32
    g = np.full(68, behavior.config.body_map_scale)
    from devlearn_self_touch.body_map import body_map_observation

    assert body_map_observation(g, behavior.config.body_map_scale) == pytest.approx(np.log(2))
    spec = behavior.network()
    assert set(spec.encoders) == {"body_map", "proprioception"}
    assert spec.encoders["body_map"].hidden_dims == (128, 256)
    assert spec.fusion_dims == (512,) and spec.trunk_dims == (256, 256)


def test_two_stage_curriculum_switches_at_its_step_count():
    curriculum = SelfTouch(SelfTouchConfig(fixed_pose_steps=1000)).curriculum()
    assert isinstance(curriculum, Curriculum)
    assert [s.name for s in curriculum.stages] == ["fixed_pose", "random_pose"]
    assert curriculum.stage.options == {"random_pose": False}
    assert not curriculum.update(999)
    assert curriculum.update(1000)
    assert curriculum.stage.options == {"random_pose": True}
    assert SelfTouch().curriculum().stages[0].steps == 4_000_000


@pytest.mark.parametrize(("variant", "random_pose"), [("fixed_only", False), ("random_only", True)])
def test_ablation_curricula_have_one_stage(variant, random_pose):
    curriculum = SelfTouch(SelfTouchConfig(curriculum=variant)).curriculum()
    assert len(curriculum.stages) == 1 and curriculum.stages[0].steps is None
    assert curriculum.stage.options == {"random_pose": random_pose}
    curriculum.update(10**9)
    assert curriculum.stage.options == {"random_pose": random_pose}


def test_config_rejects_unknown_choices_and_documents_every_field():
    with pytest.raises(ValueError, match="unknown curriculum 'three'.*two_stage"):
        SelfTouchConfig(curriculum="three")
    with pytest.raises(ValueError, match="touch_source"):
        SelfTouchConfig(touch_source="eyes")
    config = SelfTouchConfig()
    config.curriculum = "fixed"  # as ``--set`` does, after construction
    with pytest.raises(ValueError, match="fixed_only"):
        SelfTouch(config)
    source = __import__("inspect").getsource(SelfTouchConfig)
    for f in dataclasses.fields(SelfTouchConfig):
        after = source.split(f"    {f.name}:", 1)[1].split("\n", 2)[1]
        assert after.strip().startswith('"""'), f"field {f.name} has no docstring"


def test_behavior_contract():
    behavior = SelfTouch()
    assert isinstance(behavior, Behavior)
    assert behavior.scene == "crib" and "touch" in behavior.episode().senses
    assert [t.name for t in behavior.reward_terms()] == [
        "touch_novelty",
        "contact_novelty",
        "diversity_milestones",
        "balance",
    ]
    assert behavior.evaluation().stage == {"random_pose": True}
    from devlearn_self_touch.behavior import DEFAULT_STEPS

    assert behavior.about.train_defaults == {"total_steps": DEFAULT_STEPS}  # issue #55
    import pickle

    assert pickle.loads(pickle.dumps(behavior)).config == behavior.config


def test_evaluator_episode_and_summary(tmp_path):
    ev = SelfTouchEvaluator(training=False, settle_steps=0)  # scripted steps are all step 0
    ev.record(make_ctx(hand_parts=[(0, 1), (0, 2), (1, 2)], hand_contacts=[(0, 1), (1, 36)]))
    ev.record(make_ctx(hand_parts=[(0, 1)], hand_contacts=[(0, 1)], last_step=True))
    first = ev.end_episode()
    assert first == {
        "coverage_left": 2.0,
        "coverage_right": 1.0,
        "coverage_total": 2.0,
        "score": 3 / 68,
        "balance": 1.0,
    }
    ev.record(make_ctx(hand_parts=[(1, 3), (1, 4), (1, 5)]))
    assert ev.end_episode()["coverage_right"] == 3.0
    summary = ev.summary()
    assert summary["episodes"] == 2 and summary["parts"] == 34
    assert summary["coverage_left"] == 2 and summary["coverage_right"] == 4
    assert summary["coverage_total"] == 5 and summary["balance"] == 2
    assert summary["score"] == pytest.approx(6 / 68)
    assert summary["part_touch_steps"]["left"]["part_01"] == 2
    json.dumps(summary)
    paths = ev.write_artifacts(tmp_path)
    assert all(p.exists() for p in paths) and paths[0].suffix == ".png"
    counts = json.loads(paths[1].read_text())
    assert counts["left"]["region_01"] == 2 and counts["right"]["region_36"] == 1


def test_training_evaluator_keeps_no_history():
    ev = SelfTouchEvaluator(training=True)
    ev.record(make_ctx(hand_parts=[(0, 1)]))
    assert ev.end_episode()["coverage_left"] == 1.0
    assert ev.end_episode()["coverage_left"] == 0.0
    assert ev.episodes == []


def test_likeness_measures_of_a_scripted_episode():
    """Touches are contact onsets after the settle period: a contact held from it is none."""
    from types import SimpleNamespace

    categories = np.array(["arm"] * 68, dtype=object)
    categories[[0, 40, 60]] = ["face", "torso", "foot"]
    stub = SimpleNamespace(
        regions=SimpleNamespace(categories=categories, part_names=[f"p{i}" for i in range(34)],
                                names=[f"r{i}" for i in range(68)]),
        physics_timestep=0.005,
    )  # fmt: skip
    script = {0: [(0, 5)], 1: [(0, 5)], 2: [(0, 5), (1, 40)], 4: [(0, 0)], 5: [(0, 0), (0, 60)]}
    ev = SelfTouchEvaluator(training=False, settle_steps=2)
    for step in range(12):
        ctx = make_ctx(hand_contacts=script.get(step, []), step=step)
        ctx.infant = stub
        ev.record(ctx)
    ev.end_episode()
    likeness = ev.summary()["likeness"]
    minutes = 10 * 0.005 / 60  # 10 counted steps
    assert likeness["touches"] == 3  # right on 40, left on 0, left on 60; not left on 5
    assert likeness["touches_per_minute"] == pytest.approx(3 / minutes)
    assert likeness["distinct_regions_per_minute"] == pytest.approx(4 / minutes)  # 5, 40, 0, 60
    assert likeness["contact_time_share"] == pytest.approx(0.3)  # steps 2, 4 and 5 of 10
    assert likeness["mean_seconds_between_touches"] == pytest.approx((0.010 + 0.005) / 2)
    assert likeness["touch_share_by_area"] == pytest.approx(
        {"face": 1 / 3, "torso": 1 / 3, "arm": 0.0, "leg": 0.0, "foot": 1 / 3}
    )
