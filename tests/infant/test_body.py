"""The body: actuators, mirror symmetry, size, contact settings, scenes, reset and step."""

from __future__ import annotations

import numpy as np
import pytest

from devlearn.infant import ACTUATOR_GROUPS, build_infant
from devlearn.infant.body_table import BODY_TABLE, SKIN_RGBA

PAIRED = [spec.name for spec in BODY_TABLE if spec.paired]


def test_action_dims_and_groups(crib, sitting):
    assert crib.action_dim == 30 and sitting.action_dim == 17
    sizes = {"crib": (8, 8, 3, 3, 8), "sitting": (7, 7, 3, 0, 0)}
    for infant in (crib, sitting):
        groups = infant.actuator_groups
        assert tuple(len(groups[g]) for g in ACTUATOR_GROUPS) == sizes[infant.scene]
        every = np.sort(np.concatenate([groups[g] for g in ACTUATOR_GROUPS]))
        assert np.array_equal(every, np.arange(infant.action_dim))
        assert infant.model.nu == infant.action_dim == len(infant.actuator_names)
    names = [crib.actuator_names[i] for i in crib.actuator_groups["left_arm"]]
    assert {"left_shoulder_flexion", "left_elbow", "left_wrist_flexion", "left_fingers"} <= set(
        names
    )


def test_max_torques_from_facts(crib):
    gear = {n: crib.model.actuator(n).gear[0] for n in crib.actuator_names}
    expected = {
        "trunk_bend": 10.58,
        "trunk_twist": 3.63,
        "head_tilt": 3.3,
        "left_elbow": 3.6,
        "right_shoulder_abduction": 4.0,
        "left_wrist_rotation": 0.7,
        "right_fingers": 0.69,
        "left_hip_flexion": 8.0,
        "right_knee": 10.0,
    }
    for name, torque in expected.items():
        assert gear[name] == pytest.approx(torque)
    assert np.all(crib.model.actuator_ctrlrange == [-1.0, 1.0])


def test_left_and_right_mirror_exactly(sitting):
    model = sitting.model
    for part in PAIRED:
        left, right = model.body(f"left_{part}"), model.body(f"right_{part}")
        assert left.mass[0] == pytest.approx(right.mass[0])
        assert np.allclose(left.inertia, right.inertia)
        assert np.allclose(left.pos * [1, -1, 1], right.pos)
        geoms = zip(
            range(left.geomadr[0], left.geomadr[0] + left.geomnum[0]),
            range(right.geomadr[0], right.geomadr[0] + right.geomnum[0]),
        )
        for gl, gr in geoms:
            assert np.allclose(model.geom_size[gl], model.geom_size[gr])
            assert np.allclose(model.geom_pos[gl] * [1, -1, 1], model.geom_pos[gr])
    for name in sitting.actuator_names:
        if name.startswith("left_"):
            twin = "right_" + name.removeprefix("left_")
            assert np.allclose(model.joint(name).range, model.joint(twin).range)
            assert np.allclose(model.joint(name).axis * [-1, 1, -1], model.joint(twin).axis)
    # The symmetric rest pose puts mirrored bodies at mirrored places in the world.
    for part in PAIRED:
        left = sitting.data.xpos[model.body(f"left_{part}").id]
        right = sitting.data.xpos[model.body(f"right_{part}").id]
        assert np.allclose(left * [1, -1, 1], right, atol=1e-9)


def test_infant_is_78_cm_and_about_10_kg(crib):
    # Lying straight along world x at the rest pose: crown minus sole.
    data, model = crib.data, crib.model
    crown = data.geom_xpos[model.geom("head").id][0] + model.geom("head").size[0]
    sole = data.geom_xpos[model.geom("left_foot").id][0] - model.geom("left_foot").size[2]
    assert crown - sole == pytest.approx(0.778, abs=0.01)
    assert 9.0 < model.body_mass.sum() < 12.0


def test_contact_settings(crib):
    model = crib.model
    body_geoms = [g for g in range(model.ngeom) if model.geom_bodyid[g] > 0]
    for g in body_geoms:
        name = model.geom(g).name
        if name.endswith("eye"):
            assert model.geom_contype[g] == 0 and model.geom_conaffinity[g] == 0
            continue
        assert model.geom_condim[g] == 3
        assert np.allclose(model.geom_friction[g], [1.0, 0.005, 0.0002])
    hip = model.body("hip").id
    assert model.body_weldid[hip] == 0  # welded to the mattress: no free joint
    assert model.nq == model.nv == 30


def test_sitting_holds_trunk_and_legs(sitting):
    joints = {sitting.model.joint(j).name for j in range(sitting.model.njnt)}
    assert not any(k in j for j in joints for k in ("trunk", "hip_", "knee", "ankle", "finger"))
    assert sitting.model.body_weldid[sitting.model.body("left_lower_leg").id] == 0


def test_toys_are_not_skin_coloured(sitting):
    model = sitting.model
    toys = [g for g in range(model.ngeom) if model.geom(g).name.startswith("toy_")]
    assert len(toys) >= 3
    for g in toys:
        assert np.linalg.norm(model.geom_rgba[g][:3] - SKIN_RGBA[:3]) > 0.4


def test_timing_and_describe(crib):
    assert crib.physics_timestep == crib.control_timestep == crib.model.opt.timestep == 0.005
    info = crib.describe()
    assert info["touch_sensors"] == crib.skin.num_sensors
    assert (info["skin_regions"], info["regions_per_side"], info["action_dim"]) == (68, 34, 30)
    assert info["episode_steps"] == 1000


def test_reset_random_pose_is_seeded_and_within_ranges(crib):
    crib.reset(np.random.default_rng(5), random_pose=True)
    first = crib.data.qpos.copy()
    crib.reset(np.random.default_rng(5), random_pose=True)
    assert np.array_equal(first, crib.data.qpos)
    ranges = crib.model.jnt_range
    assert np.all((first >= ranges[:, 0]) & (first <= ranges[:, 1]))
    crib.reset(np.random.default_rng(6), random_pose=True)
    assert not np.allclose(first, crib.data.qpos)
    crib.reset(np.random.default_rng(0))


def test_step_clips_and_validates(crib):
    crib.step(np.full(30, 5.0))
    assert np.all(crib.data.ctrl == 1.0)
    # torque = max_torque * action on the actuator's joint
    dof = crib.model.joint(crib.actuator_names[0]).dofadr[0]
    assert crib.data.qfrc_actuator[dof] == pytest.approx(crib.model.actuator_gear[0, 0])
    with pytest.raises(ValueError, match="expected"):
        crib.step(np.zeros(17))
    with pytest.raises(ValueError, match="NaN"):
        crib.step(np.full(30, np.nan))
    crib.reset(np.random.default_rng(0))


def test_unknown_scene_and_sense():
    with pytest.raises(ValueError, match="valid scenes: crib, sitting"):
        build_infant("pool")
    with pytest.raises(ValueError, match="valid senses"):
        build_infant("crib", senses=("smell",))


def test_sitting_random_actions_stay_finite(sitting):
    rng = np.random.default_rng(1)
    sitting.reset(rng, random_pose=True)
    for _ in range(1500):
        sitting.step(rng.uniform(-1, 1, sitting.action_dim))
    assert np.all(np.isfinite(sitting.data.qpos))
    assert [w.number for w in sitting.data.warning] == [0] * len(sitting.data.warning)
