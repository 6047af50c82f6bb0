"""The compiled touch routine gives exactly the numbers of the numpy reference path."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from devlearn.infant import contacts
from devlearn.infant.regions import NUM_REGIONS


def reference(infant, data):
    """Today's numpy path: sides, then sparse spread, dense spread and hand contacts."""
    reader = infant._contacts
    sides = reader.sides(data, with_force=True)
    sensors, values = contacts.sparse_touch_from_contacts(infant.skin, sides)
    dense = contacts.touch_from_contacts(infant.skin, sides)
    hands = contacts.hand_contacts(infant.skin, reader.sides(data, False), infant.hand_of_body)
    return sensors, values, dense, hands


def assert_same(infant, data):
    sensors, values, hands = infant._contacts.touch_and_hands(data, infant.hand_of_body)
    ref_sensors, ref_values, ref_dense, ref_hands = reference(infant, data)
    assert sensors.dtype == np.int64 and values.dtype == np.float32
    np.testing.assert_array_equal(sensors, ref_sensors)
    assert values.tobytes() == ref_values.tobytes()  # bit for bit
    dense = np.zeros((infant.skin.num_sensors, 3), np.float32)
    dense[sensors] = values
    assert dense.tobytes() == ref_dense.tobytes()
    np.testing.assert_array_equal(hands, ref_hands)
    return len(sensors), int(hands.sum())


def test_recorded_trajectory_matches_the_reference(crib):
    """Random actions from random poses: every step's sparse and dense touch and hand contacts."""
    assert crib._contacts.compiled
    rng = np.random.default_rng(7)
    touched = hand_steps = 0
    for step in range(600):
        if step % 150 == 0:
            crib.reset(rng, random_pose=True)
        crib.step(rng.uniform(-1, 1, crib.action_dim))
        felt, hands = assert_same(crib, crib.data)
        touched += felt > 0
        hand_steps += hands > 0
    assert touched > 400  # the mattress is almost always felt
    # and the infant's own accessors give the same as the reference
    ref_sensors, ref_values, ref_dense, ref_hands = reference(crib, crib.data)
    np.testing.assert_array_equal(crib.touch_sparse()[0], ref_sensors)
    assert crib.touch().tobytes() == ref_dense.tobytes()
    np.testing.assert_array_equal(crib.hand_contacts(), ref_hands)


def _fake_contacts(crib, rng, ncon: int, spread: float):
    """A synthetic contact list between random body geoms (some without skin), as MjData."""
    model, data = crib.model, crib.data
    skin_geoms = np.flatnonzero(crib._contacts.geom_skin)
    bare = np.flatnonzero(~crib._contacts.geom_skin)
    hands = np.flatnonzero(crib.hand_of_body[model.geom_bodyid] >= 0)
    pool = np.concatenate([skin_geoms, bare, hands, hands])
    geom = rng.choice(pool, (ncon, 2)).astype(np.int32)
    efc = (4 * np.arange(ncon)).astype(np.int32)
    efc[rng.random(ncon) < 0.1] = -1  # excluded contacts carry no force
    body = model.geom_bodyid[geom[:, 0]]
    pos = data.xpos[body] + rng.uniform(-spread, spread, (ncon, 3))
    frame = np.zeros((ncon, 9))
    for c in range(ncon):
        frame[c] = np.linalg.qr(rng.normal(size=(3, 3)))[0].ravel()
    contact = SimpleNamespace(geom=geom, efc_address=efc, pos=pos, frame=frame)
    forces = rng.exponential(2.0, 4 * ncon)
    return SimpleNamespace(
        ncon=ncon, contact=contact, efc_force=forces, xpos=data.xpos, xmat=data.xmat
    )


@pytest.mark.parametrize(("ncon", "spread"), [(2, 0.01), (40, 0.05), (300, 0.2)])
def test_synthetic_contacts_sparse_to_dense_match(crib, ncon, spread):
    """Few contacts and very many, near the skin and far from it (nearest-sensor fallback)."""
    crib.reset(np.random.default_rng(0), random_pose=True)
    rng = np.random.default_rng(ncon)
    felt = 0
    for _ in range(20):
        felt += assert_same(crib, _fake_contacts(crib, rng, ncon, spread))[0]
    assert felt > 0


def test_no_contacts_and_no_skin_contacts(crib):
    crib.reset(np.random.default_rng(0))
    empty = _fake_contacts(crib, np.random.default_rng(0), 0, 0.01)
    sensors, values, hands = crib._contacts.touch_and_hands(empty, crib.hand_of_body)
    assert sensors.shape == (0,) and values.shape == (0, 3)
    assert hands.shape == (2, NUM_REGIONS) and not hands.any()
