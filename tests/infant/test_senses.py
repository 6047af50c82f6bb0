"""Proprioception, vestibular sense, caching and senses that are switched off."""

from __future__ import annotations

import numpy as np
import pytest

from devlearn.infant import SenseNotEnabledError, build_infant
from devlearn.infant.senses import LIMIT_ZONE


def test_proprioception_layout(crib, sitting):
    assert crib.proprioception().shape == (180,) and sitting.proprioception().shape == (102,)
    crib.reset(np.random.default_rng(0))
    action = np.linspace(-1, 1, 30)
    crib.step(action)
    p = crib.proprioception().reshape(6, 30)
    assert p.dtype == np.float32
    qpos = [crib.model.joint(name).qposadr[0] for name in crib.actuator_names]
    assert np.allclose(p[0], crib.data.qpos[qpos])  # in actuator order
    assert np.allclose(p[4], action)
    gear = crib.model.actuator_gear[:, 0]
    assert np.allclose(p[5], gear * action, rtol=1e-5)  # torque = max_torque * action
    crib.reset(np.random.default_rng(0))


def test_limit_proximity(crib):
    crib.reset(np.random.default_rng(0))
    lo, hi = crib.model.jnt_range[0]
    for q, expected in (
        (0.5 * (lo + hi), 0.0),
        (lo + LIMIT_ZONE / 2, 0.5),
        (hi, 1.0),
        (hi - 2 * LIMIT_ZONE, 0.0),
    ):
        crib.data.qpos[0] = q
        crib._cache.clear()
        assert crib.proprioception()[3 * 30] == pytest.approx(expected, abs=1e-5)
    crib.reset(np.random.default_rng(0))


def test_vestibular_feels_gravity(sitting):
    sitting.reset(np.random.default_rng(0))
    for _ in range(200):
        sitting.step(np.zeros(sitting.action_dim))
    v = sitting.vestibular()
    assert v.shape == (6,) and v.dtype == np.float32
    assert np.linalg.norm(v[:3]) == pytest.approx(9.81, abs=0.3)
    assert np.linalg.norm(v[3:]) < 0.2


def test_senses_are_cached_until_the_next_step(crib):
    crib.reset(np.random.default_rng(0))
    first = crib.touch()
    assert crib.touch() is first and not first.flags.writeable
    crib.step(np.zeros(30))
    assert crib.touch() is not first


def test_sparse_touch_is_the_dense_touch_without_its_zeros(crib):
    rng = np.random.default_rng(3)
    crib.reset(rng, random_pose=True)
    felt = 0
    for _ in range(300):
        crib.step(rng.uniform(-1, 1, 30))
        sensors, forces = crib.touch_sparse()
        dense = crib.touch()
        assert np.all(np.diff(sensors) > 0) and not forces.flags.writeable
        assert np.array_equal(np.flatnonzero(dense.any(axis=1)), sensors[forces.any(axis=1)])
        np.testing.assert_allclose(dense[sensors], forces, rtol=1e-6, atol=1e-6)
        felt += len(sensors)
    assert felt > 300  # lying on the mattress: contacts on most steps


def test_senses_not_enabled_raise_clearly():
    infant = build_infant("crib", senses=("proprioception",))
    for sense in ("touch", "vestibular", "eyes"):
        with pytest.raises(SenseNotEnabledError, match=f"sense '{sense}' is not enabled"):
            getattr(infant, sense)()
    assert infant.hand_contacts().shape == (2, 68)  # facts need no sense
    infant.close()


def test_compiled_proprioception_is_the_numpy_reference_bit_for_bit(crib):
    """The compiled gather against the numpy vector on recorded random-pose steps, joints
    near their limits included (where the limit proximity is strictly between 0 and 1)."""
    rng = np.random.default_rng(5)
    proprio, partial_limits = crib._proprio, 0
    for step in range(400):
        if step % 100 == 0:
            crib.reset(rng, random_pose=True)
        crib.step(rng.uniform(-1, 1, crib.action_dim))
        got, want = proprio(crib.data), proprio.reference(crib.data)
        assert got.dtype == want.dtype == np.float32
        assert got.tobytes() == want.tobytes(), step
        limit = got[90:120]
        partial_limits += int(np.sum((limit > 0) & (limit < 1)))
    assert partial_limits > 0
    crib.reset(np.random.default_rng(0))


def test_an_uncompiled_infant_senses_the_same_numbers(crib):
    """``build_infant(compiled=False)`` (what ``devlearn info`` builds) reads touch and
    proprioception through the numpy references: the same numbers as the compiled infant."""
    plain = build_infant("crib", senses=("touch", "proprioception"), compiled=False)
    try:
        assert not plain._contacts.compiled and not plain._proprio.compiled
        rng_a, rng_b = np.random.default_rng(3), np.random.default_rng(3)
        crib.reset(rng_a, random_pose=True)
        plain.reset(rng_b, random_pose=True)
        for _ in range(50):
            action = rng_a.uniform(-1, 1, crib.action_dim)
            crib.step(action)
            plain.step(action)
            assert plain.proprioception().tobytes() == crib.proprioception().tobytes()
            assert plain.touch().tobytes() == crib.touch().tobytes()
        assert np.abs(plain.touch()).sum() > 0  # the mattress is felt: something was compared
    finally:
        plain.close()
        crib.reset(np.random.default_rng(0))


def test_leaving_a_with_block_closes_the_infant():
    """``with build_infant(...) as infant:`` frees its renderers when the block ends, by an
    error too."""
    with pytest.raises(KeyError):
        with build_infant("sitting", senses=("eyes",)) as infant:
            assert infant.eyes().shape == (2, 64, 64, 3)
            assert infant._gl["eyes"] is not None
            raise KeyError("leaving by an error")
    assert infant._gl["eyes"] is None
