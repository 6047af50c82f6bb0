"""Contacts as facts: contact forces in body frames (for the skin) and which regions hands touch."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import mujoco
import numpy as np

from devlearn.infant.regions import NUM_REGIONS
from devlearn.infant.skin import Skin

_EDGES = np.arange(4)


class ContactSides:
    """Each active contact seen from each of its bodies that has skin.

    Attributes:
        body: (Q,) body id on this side (a self-contact gives a row for each body).
        other_body: (Q,) body id on the other side.
        point: (Q, 3) contact point in ``body``'s frame.
        force: (Q, 3) force on ``body`` in its frame (N), or None when not asked for.
        cand, dist: (Q, K) candidate sensors near ``point`` and their distances.
    """

    __slots__ = ("body", "other_body", "point", "force", "cand", "dist")

    def __init__(
        self,
        body: np.ndarray,
        other_body: np.ndarray,
        point: np.ndarray,
        force: np.ndarray | None,
        cand: np.ndarray,
        dist: np.ndarray,
    ) -> None:
        self.body, self.other_body, self.point = body, other_body, point
        self.force, self.cand, self.dist = force, cand, dist


def contact_forces_world(model: mujoco.MjModel, data: mujoco.MjData, ids: np.ndarray) -> np.ndarray:
    """World-frame force that geom1 exerts on geom2, (len(ids), 3) float64.

    Vectorised equivalent of ``mj_contactForce`` followed by the rotation out of the contact
    frame (rows of ``contact.frame``: normal, then the two tangents). Pyramidal cones store
    2 (dim - 1) edge forces per contact: normal = their sum, tangent_i = (f_2i - f_2i+1) mu_i
    (MuJoCo's mju_decodePyramid). All our geoms have condim 3.
    """
    con = data.contact
    local = np.empty((len(ids), 1, 3))
    if model.opt.cone == mujoco.mjtCone.mjCONE_PYRAMIDAL:
        edges = data.efc_force.take(con.efc_address.take(ids)[:, None] + _EDGES)
        local[:, 0, 0] = edges.sum(axis=1)
        local[:, 0, 1:] = (edges[:, 0::2] - edges[:, 1::2]) * con.friction.take(ids, 0)[:, :2]
    else:  # elliptic cones: MuJoCo's own decoding, one call per contact
        wrench = np.zeros(6)
        for row, i in enumerate(ids):
            mujoco.mj_contactForce(model, data, int(i), wrench)
            local[row, 0] = wrench[:3]
    # Row vector times frame: f_world = f_local @ frame (the frame's rows are its axes).
    return np.matmul(local, con.frame.take(ids, 0).reshape(-1, 3, 3))[:, 0]


class ContactReader:
    """Reads the contacts of one model each step: the hot path of touch and hand contacts.

    Everything that does not change between steps is looked up once here; each step costs a
    fixed, small number of numpy calls whatever the number of contacts.

    Args:
        model: The compiled model.
        skin: Its skin.
        compiled: Use the compiled routine where the model allows it (see :attr:`compiled`);
            False: always the numpy reference (no numba).
    """

    def __init__(self, model: mujoco.MjModel, skin: Skin, compiled: bool = True) -> None:
        self.model = model
        self.skin = skin
        self.geom_body = model.geom_bodyid.astype(np.int64)
        self.geom_skin = skin.body_spacing[self.geom_body] > 0
        friction = model.geom_friction[:, 0]
        # With pyramidal cones, condim 3 and one sliding friction mu for every geom, a
        # contact's local force is edges @ P: normal = sum of the 4 edge forces, tangent_i =
        # (f_2i - f_2i+1) mu (see contact_forces_world).
        self.pyramid = None
        uniform = np.all(model.geom_condim == 3) and np.ptp(friction) == 0
        if model.opt.cone == mujoco.mjtCone.mjCONE_PYRAMIDAL and uniform:
            mu = float(friction[0])
            self.mu = mu
            self.pyramid = np.array([[1, mu, 0], [1, -mu, 0], [1, 0, mu], [1, 0, -mu]], float)
        self._acc = np.zeros((skin.num_sensors, 3))
        self._mark = np.zeros(skin.num_sensors, dtype=bool)
        # the compiled routine, imported (numba) on first use
        self._kernel: Callable[..., Any] | None = None
        self._views: tuple | None = None  # (data, data.xpos, data.xmat)
        # The kernel needs uniform pyramidal cones and candidate lists no longer than its
        # pairwise-sum block (kernels.MAX_CANDIDATES = 128; this skin's are 68).
        self.compiled = compiled and self.pyramid is not None and skin._cells.shape[1] <= 128
        """True when :meth:`touch_and_hands` runs as one compiled routine."""

    def touch_and_hands(
        self, data: mujoco.MjData, hand_of_body: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Sparse touch and hand contacts of this step in one compiled call (the hot path).

        Equal to :func:`sparse_touch_from_contacts` and :func:`hand_contacts` of :meth:`sides`
        (the numpy reference), which still serve models without uniform pyramidal cones.

        Args:
            data: The simulation state (after mj_step or mj_forward).
            hand_of_body: (nbody,) int, 0 left hand, 1 right hand, -1 not a hand.

        Returns:
            sensors (M,) int64 sorted, forces (M, 3) float32 (body frames, N), and
            (2, 68) bool regions each hand touches.
        """
        if not self.compiled:
            sides = self.sides(data, with_force=True)
            sensors, values = sparse_touch_from_contacts(self.skin, sides)
            return sensors, values, hand_contacts(self.skin, sides, hand_of_body)
        if self._kernel is None:
            from devlearn.infant.kernels import MAX_CANDIDATES, contact_touch

            assert self.skin._cells.shape[1] <= MAX_CANDIDATES
            self._kernel = contact_touch
        if self._views is None or self._views[0] is not data:
            # xpos and xmat have a fixed size: their views stay valid for this MjData
            self._views = (data, data.xpos, data.xmat)
        _, xpos, xmat = self._views
        con = data.contact
        skin = self.skin
        return self._kernel(
            con.geom, con.efc_address, con.pos, con.frame, data.efc_force, xpos,
            xmat, self.geom_body, self.geom_skin, self.mu, skin._params, skin._cells,
            skin._cell_count, skin._pos_padded, skin._inv_radius, skin.sensor_body,
            skin.sensor_pos, skin.sensor_region, hand_of_body, self._acc, self._mark,
            NUM_REGIONS,
        )  # fmt: skip

    def sides(self, data: mujoco.MjData, with_force: bool) -> ContactSides | None:
        """Active contacts, one row per side that has skin; None when there are none.

        Args:
            data: The simulation state (after mj_step or mj_forward).
            with_force: Also compute forces (the skin needs them, hand contacts do not).
        """
        if data.ncon == 0:
            return None
        con = data.contact
        geom = con.geom
        efc = con.efc_address
        ids = None
        if efc.min() < 0:  # gap or excluded contacts carry no force: drop them
            ids = np.flatnonzero(efc >= 0)
            geom = geom.take(ids, 0)
        flat = geom.T.ravel()  # [geom1 of each contact, then geom2]
        rows = np.flatnonzero(self.geom_skin.take(flat))
        if len(rows) == 0:
            return None
        m = len(geom)
        body = self.geom_body.take(flat.take(rows))
        other = self.geom_body.take(flat.take((rows + m) % (2 * m)))
        contact = rows % m if ids is None else ids.take(rows % m)
        both = np.empty((len(rows), 2, 3))  # [contact point, force] per row, world frame
        np.subtract(con.pos.take(contact, 0), data.xpos.take(body, 0), out=both[:, 0])
        force = None
        if with_force:
            if self.pyramid is not None:
                edges = data.efc_force.take(efc.take(contact)[:, None] + _EDGES)
                local = np.matmul(edges, self.pyramid)[:, None, :]
                frames = con.frame.take(contact, 0).reshape(-1, 3, 3)
                np.matmul(local, frames, out=both[:, 1:2])
            else:
                both[:, 1] = contact_forces_world(self.model, data, contact)
            both[: np.searchsorted(rows, m), 1] *= -1.0  # geom1's body feels the opposite
        rot = data.xmat.take(body, 0).reshape(-1, 3, 3)
        local = np.matmul(both, rot)  # row vectors: v^T R = (R^T v)^T, into the body frame
        point = local[:, 0]
        if with_force:
            force = local[:, 1]
        cand, dist = self.skin.candidates(body, point)
        return ContactSides(body, other, point, force, cand, dist)


def sparse_touch_from_contacts(
    skin: Skin, sides: ContactSides | None
) -> tuple[np.ndarray, np.ndarray]:
    """The sensors that feel a force, (M,) int64 sorted, and those forces, (M, 3) float32."""
    if sides is None:
        return np.zeros(0, dtype=np.int64), np.zeros((0, 3), dtype=np.float32)
    assert sides.force is not None, "ContactSides without forces (sides(with_force=False))"
    return skin.spread_sparse(sides.body, sides.point, sides.force, sides.cand, sides.dist)


def touch_from_contacts(skin: Skin, sides: ContactSides | None) -> np.ndarray:
    """Sensor forces, (num_sensors, 3) float32, body frames: the dense form of
    :func:`sparse_touch_from_contacts`."""
    return skin.dense(*sparse_touch_from_contacts(skin, sides))


def hand_contacts(skin: Skin, sides: ContactSides | None, hand_of_body: np.ndarray) -> np.ndarray:
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
    if sides is None:
        return out
    # Row q is the touched side (body, point); the toucher is other_body.
    hand = hand_of_body[sides.other_body]
    use = np.flatnonzero((hand >= 0) & (hand_of_body[sides.body] != hand))
    if len(use):
        sensor = skin.nearest(sides.body[use], sides.point[use], sides.cand[use], sides.dist[use])
        out[hand[use], skin.sensor_region[sensor]] = True
    return out
