"""Where the tactile sensors sit: points over every collision geom, left mirrored to right."""

from __future__ import annotations

from dataclasses import dataclass, replace

import mujoco
import numpy as np

from devlearn.infant.body_table import BODY_TABLE, BodySpec, GeomSpec, table_hash
from devlearn.infant.regions import NUM_PARTS, assign_parts

# Points on a hexagonal grid with neighbour distance s cover 2 / (sqrt(3) s^2) per unit area.
HEX_DENSITY = 2.0 / np.sqrt(3.0)
_GOLDEN = np.pi * (3.0 - np.sqrt(5.0))


def _fibonacci_cap(n: int, z_min: float) -> np.ndarray:
    """n near-uniform unit vectors with z in [z_min, 1] (equal-area spiral)."""
    i = np.arange(n) + 0.5
    z = 1.0 - i / n * (1.0 - z_min)
    rho = np.sqrt(np.clip(1.0 - z * z, 0.0, None))
    phi = i * _GOLDEN
    return np.stack([rho * np.cos(phi), rho * np.sin(phi), z], axis=1)


def _hex_rect(a: float, b: float, s: float) -> np.ndarray:
    """Hexagonal grid points inside the rectangle [-a, a] x [-b, b], (n, 2)."""
    rows = max(1, round(2 * b / (s * np.sqrt(3) / 2)))
    cols = max(1, round(2 * a / s))
    j, i = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    offset = np.where(j % 2 == 1, 0.25, -0.25) if cols > 1 else 0.0
    u = -a + (i + 0.5 + offset) * (2 * a / cols)
    v = -b + (j + 0.5) * (2 * b / rows)
    return np.stack([u.ravel(), v.ravel()], axis=1)


def surface_points(geom_type: int, size: np.ndarray, spacing: float) -> np.ndarray:
    """Sensor points on a geom's surface, in the geom's frame.

    Args:
        geom_type: mujoco.mjtGeom value (sphere, capsule or box).
        size: The geom's MuJoCo size vector.
        spacing: Distance between neighbouring sensors (metres).

    Returns:
        (n, 3) points, about area * 1.155 / spacing^2 of them.
    """
    s = spacing
    if geom_type == mujoco.mjtGeom.mjGEOM_SPHERE:
        r = size[0]
        return r * _fibonacci_cap(max(1, round(HEX_DENSITY * 4 * np.pi * r * r / s**2)), -1.0)
    if geom_type == mujoco.mjtGeom.mjGEOM_CAPSULE:
        r, h = size[0], size[1]
        around = max(3, round(2 * np.pi * r / s))
        # An even number of rings keeps none on z = 0, the midline of crosswise capsules.
        rows = 2 * max(1, round(h / (s * np.sqrt(3) / 2)))
        j, k = np.meshgrid(np.arange(rows), np.arange(around), indexing="ij")
        phi = (k + 0.5 * (j % 2)) * 2 * np.pi / around
        z = -h + (j + 0.5) * 2 * h / rows
        side = np.stack([r * np.cos(phi).ravel(), r * np.sin(phi).ravel(), z.ravel()], axis=1)
        cap = r * _fibonacci_cap(max(1, round(HEX_DENSITY * 2 * np.pi * r * r / s**2)), 0.0)
        top = cap + [0.0, 0.0, h]
        bottom = cap * [1.0, 1.0, -1.0] - [0.0, 0.0, h]
        return np.concatenate([side, top, bottom])
    if geom_type == mujoco.mjtGeom.mjGEOM_BOX:
        half = np.asarray(size[:3], dtype=float)
        faces = []
        for axis in range(3):
            u, v = [a for a in range(3) if a != axis]
            grid = _hex_rect(half[u], half[v], s)
            for sign in (1.0, -1.0):
                pts = np.zeros((len(grid), 3))
                pts[:, u], pts[:, v], pts[:, axis] = grid[:, 0], grid[:, 1], sign * half[axis]
                faces.append(pts)
        return np.concatenate(faces)
    raise ValueError(f"no skin for geom type {geom_type}; use sphere, capsule or box")


def signed_distance(geom_type: int, size: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Signed distance of points (n, 3) in a geom's frame to its surface (negative inside)."""
    if geom_type == mujoco.mjtGeom.mjGEOM_SPHERE:
        return np.linalg.norm(p, axis=1) - size[0]
    if geom_type == mujoco.mjtGeom.mjGEOM_CAPSULE:
        z = np.clip(p[:, 2], -size[1], size[1])
        return np.linalg.norm(p - np.stack([0 * z, 0 * z, z], axis=1), axis=1) - size[0]
    if geom_type == mujoco.mjtGeom.mjGEOM_BOX:
        q = np.abs(p) - size[:3]
        outside = np.linalg.norm(np.maximum(q, 0.0), axis=1)
        return outside + np.minimum(q.max(axis=1), 0.0)
    raise ValueError(f"no signed distance for geom type {geom_type}")


@dataclass(frozen=True)
class SkinLayout:
    """Sensor points of the whole body, independent of the scene.

    Attributes:
        body: (N,) str, name of each sensor's body ("left_hand").
        pos: (N, 3) float64 positions in the body's frame.
        region: (N,) int64 body-map region in [0, 68).
        spacing: body name -> sensor spacing (metres).
        geom: (N,) str, side-free name of the geom each sensor lies on ("ribs").
    """

    body: np.ndarray
    pos: np.ndarray
    region: np.ndarray
    spacing: dict[str, float]
    geom: np.ndarray


def _geom_frame(model: mujoco.MjModel, g: int) -> tuple[np.ndarray, np.ndarray]:
    mat = np.zeros(9)
    mujoco.mju_quat2Mat(mat, model.geom_quat[g])
    return mat.reshape(3, 3), model.geom_pos[g].copy()


def _half_body(
    model: mujoco.MjModel, body: str, side_free: str, spacing: float, midline: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sensors of one left or midline body (midline: the y > 0 half only): positions, parts
    and geom names."""
    bid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, body)
    geoms = [
        g
        for g in range(model.body_geomadr[bid], model.body_geomadr[bid] + model.body_geomnum[bid])
        if model.geom_contype[g]
    ]
    frames = {g: _geom_frame(model, g) for g in geoms}
    positions, parts, names = [], [], []
    for g in geoms:
        rot, pos = frames[g]
        local = surface_points(model.geom_type[g], model.geom_size[g], spacing)
        p = local @ rot.T + pos
        keep = np.ones(len(p), dtype=bool)
        for other in geoms:  # points buried inside another geom of the same body are off
            if other != g:
                orot, opos = frames[other]
                keep &= (
                    signed_distance(
                        model.geom_type[other], model.geom_size[other], (p - opos) @ orot
                    )
                    > -1e-6
                )
        if midline:
            keep &= p[:, 1] > 1e-6
        gname = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g).removeprefix("left_")
        positions.append(p[keep])
        parts.append(assign_parts(side_free, gname, p[keep], local[keep], model.geom_size[g]))
        names.append(np.full(int(keep.sum()), gname, dtype=object))
    return np.concatenate(positions), np.concatenate(parts), np.concatenate(names)


_CACHE: dict[str, SkinLayout] = {}


def _compute_layout(model: mujoco.MjModel) -> SkinLayout:
    names, positions, regions, geoms, spacing = [], [], [], [], {}
    for spec in BODY_TABLE:
        if spec.spacing is None:
            continue
        body = f"left_{spec.name}" if spec.paired else spec.name
        pos, parts, on = _half_body(model, body, spec.name, spec.spacing, not spec.paired)
        mirrored = pos * [1.0, -1.0, 1.0]
        halves: tuple[tuple[str, np.ndarray, np.ndarray, np.ndarray], ...]
        if spec.paired:
            halves = (
                (body, pos, parts, on),
                (f"right_{spec.name}", mirrored, parts + NUM_PARTS, on),
            )
        else:
            both = np.concatenate([parts, parts + NUM_PARTS])
            halves = ((body, np.concatenate([pos, mirrored]), both, np.concatenate([on, on])),)
        for name, p, r, g in halves:
            names.append(np.full(len(p), name, dtype=object))
            positions.append(p)
            regions.append(r)
            geoms.append(g)
            spacing[name] = spec.spacing
    return SkinLayout(
        np.concatenate(names),
        np.concatenate(positions),
        np.concatenate(regions).astype(np.int64),
        spacing,
        np.concatenate(geoms),
    )


def skin_layout(model: mujoco.MjModel) -> SkinLayout:
    """The skin of the infant in ``model``, computed once per process per body table.

    Only body-frame geometry is used, which every scene shares. Bodies are listed in
    BODY_TABLE order: midline bodies (left half, then the mirrored right half), paired bodies
    left then right.
    """
    key = table_hash()
    if key not in _CACHE:
        _CACHE[key] = _compute_layout(model)
    return _CACHE[key]


def _default_layout() -> SkinLayout:
    """The default body's skin, from a bare model of it if no scene has been built yet."""
    if table_hash() not in _CACHE:
        from dm_control import mjcf

        from devlearn.infant.body import add_infant

        root = mjcf.RootElement(model="infant_skin")
        add_infant(
            root,
            root_pos=(0.0, 0.0, 0.0),
            root_quat=(1.0, 0.0, 0.0, 0.0),
            actuated_groups=set(),
            held={},
            vestibular=False,
        )
        skin_layout(mjcf.Physics.from_mjcf_model(root).model.ptr)
    return _CACHE[table_hash()]


def _stretch(points: np.ndarray, before: GeomSpec, after: GeomSpec) -> np.ndarray:
    """Move points on a geom's surface onto the same geom resized, (n, 3) body frame.

    Along a capsule's axis a point keeps its fraction of the way, across it its direction, at
    the new radius (on an end cap: from the cap's new centre); on a sphere or box each offset
    from the centre scales with the radius or with each half size. A point on the surface
    before is on the surface after.
    """
    if before.kind == "capsule":
        assert before.fromto is not None and after.fromto is not None
        a0, b0 = np.array(before.fromto[:3]), np.array(before.fromto[3:])
        a1, b1 = np.array(after.fromto[:3]), np.array(after.fromto[3:])
        axis = b0 - a0
        t = np.clip((points - a0) @ axis / (axis @ axis), 0.0, 1.0)[:, None]
        radial = points - (a0 + t * axis)
        return a1 + t * (b1 - a1) + radial * (after.size[0] / before.size[0])
    scale = np.array(after.size) / np.array(before.size)
    if before.kind == "sphere":
        scale = np.repeat(scale[:1], 3)
    return np.array(after.pos) + (points - np.array(before.pos)) * scale


def grown_layout(table: tuple[BodySpec, ...]) -> SkinLayout:
    """The default body's skin moved onto a grown body (:mod:`devlearn.infant.growth`).

    Every sensor stays on its geom (:func:`_stretch`), in its region, so the 68 regions hold
    the same number of sensors at every age; each body's spacing is the grown one (the
    default's times the square root of its skin's growth in area). Where the growth changes a
    body's proportions, a few sensors can end up inside a neighbouring geom of the same body
    (at birth, 14 of the upper trunk's 126, under the shorter trunk's overlapping
    capsules); they still feel contacts near them, through the force spreading.

    Args:
        table: The grown body's table: the default's parts and geoms, resized.
    """
    base = _default_layout()
    pos = base.pos.copy()
    grown = {spec.name: spec for spec in table}
    spacing = {}
    for spec in BODY_TABLE:
        for side in ("left_", "right_") if spec.paired else ("",):
            body = side + spec.name
            on_body = base.body == body
            if not on_body.any():
                continue
            spacing[body] = float(grown[spec.name].spacing or 0.0)
            mirror = np.array([1.0, -1.0 if side == "right_" else 1.0, 1.0])
            for before, after in zip(spec.geoms, grown[spec.name].geoms):
                rows = np.flatnonzero(on_body & (base.geom == before.name))
                pos[rows] = _stretch(pos[rows] * mirror, before, after) * mirror
    return replace(base, pos=pos, spacing=spacing)
