"""A body that grows (issue #41): WHO length and mass, changing proportions, the same skin."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from devlearn.infant import build_infant
from devlearn.infant.growth import REFERENCE_AGE, grown_body

AGES = (0, 6, 12, 18, 24)

# WHO Child Growth Standards (2006), boys, birth to 2 years, median (M) of the length-for-age
# and weight-for-age tables: written here again so that a wrong table in the code fails.
WHO_LENGTH_M = {0: 0.498842, 6: 0.676236, 12: 0.757488, 18: 0.822587, 24: 0.878161}
WHO_WEIGHT_KG = {0: 3.3464, 6: 7.9340, 12: 9.6479, 18: 10.9385, 24: 12.1515}


@pytest.fixture(scope="module")
def infants():
    built = {age: build_infant("crib", senses=("touch",), age_months=age) for age in AGES}
    built[None] = build_infant("crib", senses=("touch",))
    yield built
    for infant in built.values():
        infant.close()


def _extent(model: mujoco.MjModel, data: mujoco.MjData, g: int, up: np.ndarray) -> np.ndarray:
    """Lowest and highest point of geom ``g`` along the unit vector ``up`` (world)."""
    centre, rot, size = data.geom_xpos[g] @ up, data.geom_xmat[g].reshape(3, 3), model.geom_size[g]
    along = rot.T @ up  # ``up`` in the geom's frame
    kind = model.geom_type[g]
    if kind == mujoco.mjtGeom.mjGEOM_SPHERE:
        half = size[0]
    elif kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
        half = size[0] + size[1] * abs(along[2])
    else:
        half = float(np.abs(size[:3] * along).sum())
    return np.array([centre - half, centre + half])


def body_length(infant) -> float:
    """Crown-heel length measured in the compiled model: every joint at 0 (lying straight),
    from the top of the head to the lowest point of the soles, along the body's long axis."""
    model = infant.model
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    hip = model.body("hip").id
    up = data.xmat[hip].reshape(3, 3)[:, 2]  # the body's head-ward axis, lying in the crib
    infant_geoms = [
        g for g in range(model.ngeom) if model.geom_bodyid[g] != 0 and model.geom_contype[g]
    ]
    ends = np.array([_extent(model, data, g, up) for g in infant_geoms])
    return float(ends[:, 1].max() - ends[:, 0].min())


def body_mass(infant) -> float:
    return float(infant.model.body_mass.sum())


@pytest.mark.parametrize("age", AGES)
def test_length_and_mass_within_3_percent_of_the_who_medians(infants, age):
    infant = infants[age]
    assert body_length(infant) == pytest.approx(WHO_LENGTH_M[age], rel=0.03)
    assert body_mass(infant) == pytest.approx(WHO_WEIGHT_KG[age], rel=0.03)


def test_the_default_body_is_unchanged(infants):
    default = infants[None]
    assert default.age_months is None and default.describe()["age_months"] is None
    assert body_length(default) == pytest.approx(0.7785, abs=1e-9)  # MIMo v1's 77.8 cm
    assert body_mass(default) == pytest.approx(10.96075, abs=1e-5)  # density 1000
    assert default.model.actuator("left_elbow").gear[0] == 3.6


def test_proportions_change_the_head_share_falls(infants):
    def head_share(infant):
        return 2 * infant.model.geom("head").size[0] / body_length(infant)

    shares = [head_share(infants[age]) for age in AGES]
    assert all(a > b for a, b in zip(shares, shares[1:])), shares
    assert shares[0] - shares[-1] > 0.03  # about 22% of a newborn's length, 17% at 24 months


def test_at_the_reference_age_the_shape_is_the_default_bodys(infants):
    default = infants[None].model
    grown = build_infant("crib", senses=("touch",), age_months=REFERENCE_AGE).model
    np.testing.assert_allclose(grown.geom_size, default.geom_size, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(grown.body_pos, default.body_pos, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(grown.actuator_gear, default.actuator_gear, rtol=1e-9)
    # its mass is WHO's at that age (10.06 kg), below the plump default's 10.96 kg
    assert grown.body_mass.sum() == pytest.approx(10.056, abs=1e-3)


def test_torques_grow_with_the_body(infants):
    gears = np.array([infants[age].model.actuator_gear[:, 0] for age in AGES])
    assert np.all(np.diff(gears, axis=0) > 0)  # every motor stronger at every later age
    assert [infants[a].actuator_names for a in AGES] == [infants[None].actuator_names] * 5
    stiffness = np.array([infants[age].model.jnt_stiffness for age in AGES])
    assert np.all(np.diff(stiffness[:, 1:], axis=0) > 0)  # the passive springs with them


def test_the_skin_keeps_its_sensors_and_grows(infants):
    default = infants[None].skin
    for age in AGES:
        skin = infants[age].skin
        assert skin.num_sensors == default.num_sensors
        np.testing.assert_array_equal(skin.sensor_region, default.sensor_region)
        np.testing.assert_array_equal(skin.region_sizes, default.region_sizes)
        assert infants[age].touch().shape == (default.num_sensors, 3)

    def region_extent(skin):  # (68,) RMS distance of a region's sensors from their centre
        out = np.zeros(68)
        for r in range(68):
            pts = skin.sensor_pos[skin.sensor_region == r]
            out[r] = np.sqrt(((pts - pts.mean(0)) ** 2).sum(1).mean())
        return out

    extents = np.array([region_extent(infants[age].skin) for age in AGES])
    assert np.all(np.diff(extents, axis=0) > 0)  # every region larger at every later age
    spacing = np.array([infants[age].skin.body_spacing for age in AGES])
    has_skin = spacing[0] > 0
    assert np.all(np.diff(spacing[:, has_skin], axis=0) > 0)
    # the head's sensors spread over a head whose circumference grew 34.5 -> 48.3 cm (WHO)
    head = infants[0].model.body("head").id
    ratio = infants[24].skin.body_spacing[head] / infants[0].skin.body_spacing[head]
    assert ratio == pytest.approx(48.2515 / 34.4618, rel=1e-6)


@pytest.mark.parametrize("age", (-1, 24.5, float("nan"), "six"))
def test_an_age_outside_0_to_24_is_a_one_line_error(age):
    with pytest.raises(ValueError, match=r"between 0 and 24 months") as err:
        grown_body(age)  # type: ignore[arg-type]
    assert "\n" not in str(err.value)
    with pytest.raises(ValueError, match=r"infant.age_months must be between 0 and 24"):
        build_infant("crib", senses=("touch",), age_months=age)  # type: ignore[arg-type]


@pytest.mark.parametrize("age", (0, 24))
def test_a_grown_body_moves_and_feels(infants, age):
    infant = infants[age]
    rng = np.random.default_rng(7)
    infant.reset(rng, random_pose=True)
    felt = 0.0
    for _ in range(300):
        infant.step(rng.uniform(-1.0, 1.0, infant.action_dim))
        felt += float(np.abs(infant.touch()).sum())
    assert np.all(np.isfinite(infant.data.qpos)) and np.abs(infant.data.qvel).max() < 100.0
    assert all(w.number == 0 for w in infant.data.warning)
    assert felt > 0.0
