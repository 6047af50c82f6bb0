"""The skin: sensor counts, placement, mirroring, and force spreading that conserves force."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from dm_control import mjcf

from devlearn.infant import build_infant, contacts
from devlearn.infant.scenes import build_scene_model
from devlearn.infant.skin import Skin
from devlearn.infant.skin_layout import signed_distance

# Sensors per body from the facts file (sec. 2), per side where paired.
FACTS = {
    "hip": 119,
    "lower_body": 116,
    "upper_body": 162,
    "head": 404,
    "upper_arm": 54,
    "lower_arm": 47,
    "hand": 172,
    "fingers": 1944,
    "upper_leg": 82,
    "lower_leg": 35,
    "foot": 79,
    "toes": 48,
}


def _names(infant):
    return np.array([infant.model.body(b).name for b in infant.skin.sensor_body])


def test_sensor_counts_match_the_facts(crib):
    skin = crib.skin
    assert 4500 <= skin.num_sensors <= 7000
    names, counts = np.unique(_names(crib), return_counts=True)
    assert len(names) == 4 + 2 * 8
    for name, count in zip(names, counts):
        fact = FACTS[name.removeprefix("left_").removeprefix("right_")]
        assert fact / 1.5 <= count <= fact * 1.5, (name, count, fact)


def _geom_distances(infant):
    """Per skin body: (its geoms, its sensors) signed distances of the sensors to each geom."""
    model, skin = infant.model, infant.skin
    for b in np.unique(skin.sensor_body):
        pts = skin.sensor_pos[skin.sensor_body == b]
        geoms = [
            g
            for g in range(model.body_geomadr[b], model.body_geomadr[b] + model.body_geomnum[b])
            if model.geom_contype[g]
        ]
        dists = []
        for g in geoms:
            rot = np.zeros(9)
            mujoco.mju_quat2Mat(rot, model.geom_quat[g])
            local = (pts - model.geom_pos[g]) @ rot.reshape(3, 3)
            dists.append(signed_distance(model.geom_type[g], model.geom_size[g], local))
        yield model.body(b).name, np.array(dists)


def test_sensors_lie_on_their_body_surface_and_none_is_buried(crib):
    for _, dists in _geom_distances(crib):
        assert np.all(np.abs(dists).min(axis=0) < 1e-6)  # on some geom's surface
        assert np.all(dists > -1e-6)  # inside none


@pytest.mark.parametrize("age", (0, 24))
def test_a_grown_bodys_sensors_lie_on_its_grown_surface(age):
    """The default's sensors, moved onto the body at an age (issue #41), are on its surface
    (a few of the trunk's may be inside a neighbouring trunk capsule that grew over them)."""
    infant = build_infant("crib", senses=("touch",), age_months=age)
    for name, dists in _geom_distances(infant):
        assert np.all(np.abs(dists).min(axis=0) < 1e-9), name
    infant.close()


def test_skin_is_mirrored(crib):
    skin, names = crib.skin, _names(crib)
    for left in {n for n in names if n.startswith("left_")}:
        right = "right_" + left.removeprefix("left_")
        assert np.allclose(
            skin.sensor_pos[names == left] * [1, -1, 1], skin.sensor_pos[names == right]
        )
    sizes = skin.region_sizes
    assert np.array_equal(sizes[:34], sizes[34:])


@pytest.mark.parametrize("body", ["left_lower_arm", "head", "right_fingers", "upper_body"])
def test_spread_conserves_force_locally(crib, body):
    skin = crib.skin
    b = crib.model.body(body).id
    idx = np.flatnonzero(skin.sensor_body == b)
    rng = np.random.default_rng(0)
    for _ in range(5):
        point = skin.sensor_pos[rng.choice(idx)] + rng.normal(0, 0.2 * skin.body_spacing[b], 3)
        force = rng.normal(0, 3.0, 3)
        touch = skin.dense(*skin.spread_sparse(np.array([b]), point[None], force[None]))
        assert touch.dtype == np.float32 and touch.shape == (skin.num_sensors, 3)
        assert np.allclose(touch.sum(axis=0), force, rtol=1e-5, atol=1e-5)
        hit = np.flatnonzero(np.any(touch != 0, axis=1))
        assert np.all(skin.sensor_body[hit] == b)
        assert np.all(np.linalg.norm(skin.sensor_pos[hit] - point, axis=1) <= skin.radius[b])
        assert len(hit) > 1


def test_spread_far_from_sensors_goes_to_the_nearest(crib):
    skin = crib.skin
    b = crib.model.body("head").id
    point = np.array([[0.02, 0.0, 0.085 + 0.0735 + 0.05]])  # 5 cm above the crown
    touch = skin.dense(*skin.spread_sparse(np.array([b]), point, np.array([[0.0, 0.0, -2.0]])))
    hit = np.flatnonzero(np.any(touch != 0, axis=1))
    nearest = np.argmin(
        np.where(skin.sensor_body == b, np.linalg.norm(skin.sensor_pos - point, axis=1), np.inf)
    )
    assert list(hit) == [nearest] and touch[nearest, 2] == pytest.approx(-2.0)


def test_touch_agrees_with_mj_contact_force(crib):
    """Per body, the sensors' forces (back in the world frame) add up to the contact forces."""
    rng = np.random.default_rng(3)
    crib.reset(rng, random_pose=True)
    model, data = crib.model, crib.data
    for _ in range(3000):  # until the body touches itself as well as the mattress
        crib.step(rng.uniform(-1, 1, crib.action_dim))
        bodies = model.geom_bodyid[data.contact.geom]
        if data.ncon >= 5 and np.any(np.all(bodies > 0, axis=1)):
            break
    assert np.any(np.all(bodies > 0, axis=1))
    touch = crib.touch().astype(np.float64)
    expected = np.zeros((model.nbody, 3))
    wrench = np.zeros(6)
    for i in range(data.ncon):
        con = data.contact[i]
        mujoco.mj_contactForce(model, data, i, wrench)
        world = con.frame.reshape(3, 3).T @ wrench[:3]  # geom1 on geom2
        expected[model.geom_bodyid[con.geom2]] += world
        expected[model.geom_bodyid[con.geom1]] -= world
    for b in np.unique(crib.skin.sensor_body):
        sensors = touch[crib.skin.sensor_body == b]
        felt = data.xmat[b].reshape(3, 3) @ sensors.sum(axis=0)
        assert np.allclose(felt, expected[b], atol=1e-3 + 1e-4 * np.abs(expected[b]).max())
    crib.reset(np.random.default_rng(0))


def test_box_resting_on_the_shin_weighs_on_it():
    """A 0.2 kg box on the (held) left shin of the sitting infant: the shin's sensors feel
    exactly its weight, m g, straight down."""
    root, _ = build_scene_model("sitting", vestibular=False)
    physics = mjcf.Physics.from_mjcf_model(root)
    model, data = physics.model.ptr, physics.data.ptr
    mujoco.mj_forward(model, data)
    shin = model.geom("left_lower_leg").id
    top = data.geom_xpos[shin] + [0.0, 0.0, model.geom_size[shin, 0] + 0.011]
    box = root.worldbody.add("body", name="box", pos=top)
    box.add("freejoint")
    box.add("geom", type="box", size=(0.015, 0.015, 0.01), mass=0.2, contype=2, conaffinity=1)
    physics = mjcf.Physics.from_mjcf_model(root)
    model, data = physics.model.ptr, physics.data.ptr
    for _ in range(600):
        mujoco.mj_step(model, data)
    skin = Skin(model)
    sides = contacts.ContactReader(model, skin).sides(data, with_force=True)
    touch = contacts.touch_from_contacts(skin, sides).astype(np.float64)
    b = model.body("left_lower_leg").id
    others = {model.geom_bodyid[g] for g in data.contact.geom[data.contact.geom[:, 1] > 0].ravel()}
    assert model.body("left_hand").id not in others  # only the box touches the shin
    felt = data.xmat[b].reshape(3, 3) @ touch[skin.sensor_body == b].sum(axis=0)
    assert np.linalg.norm(data.qvel[-6:-3]) < 1e-3  # the box has come to rest
    assert np.allclose(felt, [0.0, 0.0, -0.2 * 9.81], atol=0.01)
