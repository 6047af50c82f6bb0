"""Hand contacts as facts: which regions each hand touches, credited fairly to both hands."""

from __future__ import annotations

import mujoco
import numpy as np

from devlearn.infant import contacts


def _reach(infant, hand: str, target: np.ndarray, point: np.ndarray) -> None:
    """Damped least-squares IK: move ``point`` (in the hand's fingers frame) onto ``target``."""
    model, data = infant.model, infant.data
    joints = [infant.actuator_names[i] for i in infant.actuator_groups[f"{hand}_arm"]]
    qadr = np.array([model.joint(j).qposadr[0] for j in joints])
    dofs = np.array([model.joint(j).dofadr[0] for j in joints])
    limits = np.array([model.joint(j).range for j in joints])
    body = model.body(f"{hand}_fingers").id
    jac = np.zeros((3, model.nv))
    for _ in range(200):
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        here = data.xpos[body] + data.xmat[body].reshape(3, 3) @ point
        error = target - here
        if np.linalg.norm(error) < 1e-4:
            break
        mujoco.mj_jac(model, data, jac, None, here, body)
        j = jac[:, dofs]
        step = j.T @ np.linalg.solve(j @ j.T + 1e-4 * np.eye(3), error)
        data.qpos[qadr] = np.clip(data.qpos[qadr] + step, limits[:, 0], limits[:, 1])
    assert np.linalg.norm(error) < 1e-3
    mujoco.mj_forward(model, data)
    infant._cache.clear()


def test_left_hand_on_the_right_cheek(crib):
    crib.reset(np.random.default_rng(0))
    skin, regions, model, data = crib.skin, crib.regions, crib.model, crib.data
    cheek = regions.index("right_cheek")
    idx = np.flatnonzero(skin.sensor_region == cheek)
    centre = skin.sensor_pos[idx].mean(axis=0)
    sensor = idx[np.argmin(np.linalg.norm(skin.sensor_pos[idx] - centre, axis=1))]
    head = model.body("head").id
    rot, origin = data.xmat[head].reshape(3, 3), data.xpos[head]
    on_cheek = origin + rot @ skin.sensor_pos[sensor]
    normal = rot @ (skin.sensor_pos[sensor] - model.geom("head").pos)
    normal /= np.linalg.norm(normal)
    pad = np.array([0.0075, 0.0, -0.019])  # middle of the mitten's inner face
    _reach(crib, "left", on_cheek - 0.003 * normal, pad)
    touched = crib.hand_contacts()
    assert touched.shape == (2, 68) and touched.dtype == bool
    assert touched[0, cheek]
    assert not touched[1, cheek]
    assert not touched[0, regions.sides == "left"][regions.parts[:34] == 1].any()  # left cheek
    assert np.abs(crib.touch()[idx]).sum() > 0  # the cheek feels it too
    crib.reset(np.random.default_rng(0))


def _sides(crib, pairs):
    """Synthetic contact rows: (touched body, toucher body, point in the touched body frame)."""
    model, skin = crib.model, crib.skin
    body = np.array([model.body(a).id for a, _, _ in pairs])
    other = np.array([model.body(b).id for _, b, _ in pairs])
    point = np.array([p for _, _, p in pairs], dtype=float)
    cand, dist = skin.candidates(body, point)
    return contacts.ContactSides(body, other, point, None, cand, dist)


def test_palm_to_palm_counts_for_both_hands(crib):
    regions = crib.regions
    palm = (0.01, 0.0, -0.025)  # centre of the palm face, hand body frame (mirror: same)
    sides = _sides(crib, [("right_hand", "left_hand", palm), ("left_hand", "right_hand", palm)])
    touched = contacts.hand_contacts(crib.skin, sides, crib.hand_of_body)
    assert touched[0, regions.index("right_palm")] and touched[1, regions.index("left_palm")]
    assert touched.sum() == 2


def test_own_hand_and_the_world_do_not_count(crib):
    sides = _sides(
        crib,
        [
            ("left_hand", "left_fingers", (0.01, 0.0, -0.045)),
            ("head", "mattress_placeholder", (0.0, 0.0, 0.0)),
        ][:1],
    )
    assert not contacts.hand_contacts(crib.skin, sides, crib.hand_of_body).any()
    # A body part touched by something that is not a hand (world body 0: mattress) counts nowhere.
    model, skin = crib.model, crib.skin
    body = np.array([model.body("head").id])
    point = np.array([[0.02, 0.0, 0.085 - 0.0735]])
    cand, dist = skin.candidates(body, point)
    world = contacts.ContactSides(body, np.array([0]), point, None, cand, dist)
    assert not contacts.hand_contacts(skin, world, crib.hand_of_body).any()
