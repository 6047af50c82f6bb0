"""The tactile skin: sensor table, a per-body neighbour grid, and force spreading (the hot path)."""

from __future__ import annotations

import mujoco
import numpy as np

from devlearn.infant.regions import NUM_REGIONS
from devlearn.infant.skin_layout import skin_layout

_FAR = 1e3  # position of the padding "sensor": never within range of anything


class Skin:
    """Tactile sensors of the infant in one compiled model.

    Each sensor reports the 3-D force on its body, in the body's frame (facts sec. 2). A contact
    force is spread over the sensors of the touched body within 2 * spacing of the contact
    point, with weights max(0, 1 - d / (2 spacing)) normalised to sum to 1, so force is
    conserved; with no sensor in range the nearest sensor takes it all.

    Attributes:
        num_sensors: N.
        sensor_body: (N,) int64 MuJoCo body id of each sensor.
        sensor_pos: (N, 3) float64 position in its body's frame (metres).
        sensor_region: (N,) int64 body-map region in [0, 68).
        region_sizes: (68,) int64 sensors per region.
        body_spacing: (nbody,) float64 sensor spacing per body (0: no skin).
    """

    def __init__(self, model: mujoco.MjModel) -> None:
        layout = skin_layout(model)
        ids = {
            name: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
            for name in set(layout.body)
        }
        self.sensor_body = np.array([ids[name] for name in layout.body], dtype=np.int64)
        self.sensor_pos = layout.pos.copy()
        self.sensor_region = layout.region.copy()
        self.num_sensors = len(self.sensor_pos)
        self.region_sizes = np.bincount(self.sensor_region, minlength=NUM_REGIONS)
        self.body_spacing = np.zeros(model.nbody)
        for name, spacing in layout.spacing.items():
            self.body_spacing[ids[name]] = spacing
        self._build_grid(model.nbody)

    def _build_grid(self, nbody: int) -> None:
        """Per body, a grid of cells 2 * spacing wide; each cell lists the sensors in it and its
        26 neighbours, so every sensor within range of a point is in the point's cell list."""
        self._lo = np.zeros((nbody, 3))
        self._dims = np.ones((nbody, 3), dtype=np.int64)
        self._cell_size = np.ones(nbody)
        self._offset = np.zeros(nbody, dtype=np.int64)
        offsets = np.stack(np.meshgrid(*[np.arange(-1, 2)] * 3, indexing="ij"), -1).reshape(-1, 3)
        lists: list[tuple[np.ndarray, np.ndarray]] = []  # (global cell, sensor) pairs
        total = 0
        for b in range(nbody):
            idx = np.flatnonzero(self.sensor_body == b)
            if len(idx) == 0:
                continue
            h = 2.0 * self.body_spacing[b]
            pts = self.sensor_pos[idx]
            lo = pts.min(0) - h
            dims = np.floor((pts.max(0) - lo) / h).astype(np.int64) + 2
            self._lo[b], self._dims[b], self._cell_size[b], self._offset[b] = lo, dims, h, total
            cells = np.floor((pts - lo) / h).astype(np.int64)
            near = cells[:, None, :] + offsets[None]  # (n, 27, 3)
            ok = np.all((near >= 0) & (near < dims), axis=2)
            flat = total + (near[..., 0] * dims[1] + near[..., 1]) * dims[2] + near[..., 2]
            lists.append((flat[ok], np.broadcast_to(idx[:, None], ok.shape)[ok]))
            total += int(np.prod(dims))
        cell = np.concatenate([c for c, _ in lists])
        sensor = np.concatenate([s for _, s in lists])
        order = np.lexsort((sensor, cell))
        cell, sensor = cell[order], sensor[order]
        counts = np.bincount(cell, minlength=total)
        width = int(counts.max())
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        slot = np.arange(len(cell)) - starts[cell]
        self._cells = np.full((total, width), self.num_sensors, dtype=np.int64)
        self._cells[cell, slot] = sensor
        self._pos_padded = np.vstack([self.sensor_pos, np.full((1, 3), _FAR)])

    def _candidates(self, bodies: np.ndarray, points: np.ndarray):
        """Candidate sensors (Q, K) of each query and their distances (Q, K)."""
        h = self._cell_size[bodies]
        cells = np.floor((points - self._lo[bodies]) / h[:, None]).astype(np.int64)
        cells = np.clip(cells, 0, self._dims[bodies] - 1)
        dims = self._dims[bodies]
        flat = (
            self._offset[bodies]
            + (cells[:, 0] * dims[:, 1] + cells[:, 1]) * dims[:, 2]
            + cells[:, 2]
        )
        cand = self._cells[flat]
        diff = self._pos_padded[cand] - points[:, None, :]
        return cand, np.sqrt(np.einsum("qki,qki->qk", diff, diff)), h

    def nearest(self, bodies: np.ndarray, points: np.ndarray) -> np.ndarray:
        """Index of the nearest sensor of each body to each point.

        Args:
            bodies: (Q,) body ids (bodies with skin).
            points: (Q, 3) points in those bodies' frames.

        Returns:
            (Q,) int64 sensor indices.
        """
        cand, dist, _ = self._candidates(bodies, points)
        best = cand[np.arange(len(cand)), np.argmin(dist, axis=1)]
        for q in np.flatnonzero(best == self.num_sensors):  # far outside the grid: rare
            idx = np.flatnonzero(self.sensor_body == bodies[q])
            best[q] = idx[np.argmin(np.linalg.norm(self.sensor_pos[idx] - points[q], axis=1))]
        return best

    def spread(self, bodies: np.ndarray, points: np.ndarray, forces: np.ndarray) -> np.ndarray:
        """Spread contact forces over the skin.

        Args:
            bodies: (Q,) body id receiving each force (bodies with skin).
            points: (Q, 3) contact points in that body's frame.
            forces: (Q, 3) forces on that body, in its frame (N).

        Returns:
            (num_sensors, 3) float32 summed sensor forces.
        """
        out = np.zeros(3 * self.num_sensors)
        if len(bodies) == 0:
            return out.reshape(-1, 3).astype(np.float32)
        cand, dist, h = self._candidates(bodies, points)
        weight = np.maximum(0.0, 1.0 - dist / h[:, None])
        total = weight.sum(axis=1)
        empty = total <= 0.0
        if np.any(empty):  # nothing in range: all of it to the nearest sensor
            rows = np.flatnonzero(empty)
            weight[rows] = 0.0
            nearest = self.nearest(bodies[rows], points[rows])
            cand[rows, 0], weight[rows, 0], total[rows] = nearest, 1.0, 1.0
        weight /= total[:, None]
        hit = weight > 0.0
        index = (cand[hit][:, None] * 3 + np.arange(3)).ravel()
        values = (weight[hit][:, None] * forces[np.nonzero(hit)[0]]).ravel()
        out[: 3 * self.num_sensors] = np.bincount(index, values, minlength=3 * self.num_sensors)
        return out.reshape(-1, 3).astype(np.float32)
