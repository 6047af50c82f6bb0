"""Contacts as facts: contact forces in body frames (for the skin) and which regions hands touch."""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from devlearn.infant.regions import NUM_REGIONS
from devlearn.infant.skin import Skin


@dataclass(frozen=True)
class ContactSides:
    """Each active contact seen from each of its bodies that has skin.

    Attributes:
        contact: (Q,) index into data.contact.
        body: (Q,) body id on this side.
        other_body: (Q,) body id on the other side.
        point: (Q, 3) contact point in ``body``'s frame.
        force: (Q, 3) force on ``body`` in its frame (N); None when not computed.
    """

    contact: np.ndarray
    body: np.ndarray
    other_body: np.ndarray
    point: np.ndarray
    force: np.ndarray | None


def contact_forces_world(model: mujoco.MjModel, data: mujoco.MjData, ids: np.ndarray):
    """World-frame force that geom1 exerts on geom2, for the given contacts.

    Vectorised equivalent of ``mj_contactForce`` followed by the rotation out of the contact
    frame (rows of ``contact.frame`` are the normal and the two tangents). Pyramidal cones
    store 2 (dim - 1) edge forces per contact: normal = their sum, tangent_i =
    (f_2i - f_2i+1) * mu_i (MuJoCo's mju_decodePyramid).

    Returns:
        (len(ids), 3) float64.
    """
    con = data.contact
    addr = con.efc_address[ids]
    dim = con.dim[ids]
    local = np.zeros((len(ids), 3))
    if model.opt.cone == mujoco.mjtCone.mjCONE_PYRAMIDAL and np.all(dim == 3):
        edges = data.efc_force[addr[:, None] + np.arange(4)]
        mu = con.friction[ids, :2]
        local[:, 0] = edges.sum(axis=1)
        local[:, 1] = (edges[:, 0] - edges[:, 1]) * mu[:, 0]
        local[:, 2] = (edges[:, 2] - edges[:, 3]) * mu[:, 1]
    else:  # other cones or condims: MuJoCo's own decoding, one call per contact
        wrench = np.zeros(6)
        for row, i in enumerate(ids):
            mujoco.mj_contactForce(model, data, int(i), wrench)
            local[row] = wrench[:3]
    frames = con.frame[ids].reshape(-1, 3, 3)
    return np.einsum("nij,ni->nj", frames, local)


def contact_sides(
    model: mujoco.MjModel, data: mujoco.MjData, skin_body: np.ndarray, with_force: bool
) -> ContactSides:
    """Active contacts, one row per side that has skin (a self-contact gives two rows).

    Args:
        skin_body: (nbody,) bool, bodies with tactile sensors.
        with_force: Also compute forces (the skin needs them, hand contacts do not).
    """
    n = data.ncon
    con = data.contact
    if n:
        ids = np.flatnonzero((con.exclude == 0) & (con.efc_address >= 0))
    else:
        ids = np.zeros(0, dtype=np.int64)
    geom = con.geom[ids] if len(ids) else np.zeros((0, 2), dtype=np.int64)
    b1, b2 = model.geom_bodyid[geom[:, 0]], model.geom_bodyid[geom[:, 1]]
    on1, on2 = skin_body[b1], skin_body[b2]
    contact = np.concatenate([ids[on1], ids[on2]])
    body = np.concatenate([b1[on1], b2[on2]])
    other = np.concatenate([b2[on1], b1[on2]])
    rot = data.xmat[body].reshape(-1, 3, 3)
    rel = con.pos[contact] - data.xpos[body]
    point = np.einsum("qi,qij->qj", rel, rot)  # R^T (p - x)
    force = None
    if with_force:
        world = contact_forces_world(model, data, ids)
        sign = np.concatenate([-np.ones(on1.sum()), np.ones(on2.sum())])
        rows = np.concatenate([np.flatnonzero(on1), np.flatnonzero(on2)])
        force = np.einsum("qi,qij->qj", world[rows] * sign[:, None], rot)
    return ContactSides(contact, body, other, point, force)


def touch_from_contacts(skin: Skin, sides: ContactSides) -> np.ndarray:
    """Sensor forces, (num_sensors, 3) float32, body frames."""
    return skin.spread(sides.body, sides.point, sides.force)


def hand_contacts(skin: Skin, sides: ContactSides, hand_of_body: np.ndarray) -> np.ndarray:
    """Which regions each hand touches.

    A hand is its hand (palm) body or its fingers body. For every contact between a hand and
    a body part with skin, the touched part's region is the region of its sensor nearest to the
    contact point. Both hands are credited fairly: a palm-to-palm contact counts for each hand.
    A hand touching its own hand or fingers is not self-touch and is ignored; contacts with the
    mattress, floor or toys never appear (they have no skin).

    Args:
        skin: The skin.
        sides: Contact sides (forces not needed).
        hand_of_body: (nbody,) int, 0 left hand, 1 right hand, -1 not a hand.

    Returns:
        (2, 68) bool: [hand (left, right), region].
    """
    out = np.zeros((2, NUM_REGIONS), dtype=bool)
    # Row q is the touched side (body, point); the toucher is other_body.
    hand = hand_of_body[sides.other_body]
    use = (hand >= 0) & (hand_of_body[sides.body] != hand)
    if np.any(use):
        sensor = skin.nearest(sides.body[use], sides.point[use])
        out[hand[use], skin.sensor_region[sensor]] = True
    return out
