"""The tactile skin: sensor table, a per-body neighbour grid, and force spreading (the hot path)."""

from __future__ import annotations

import mujoco
import numpy as np

from devlearn.infant.regions import NUM_REGIONS
from devlearn.infant.skin_layout import SkinLayout, skin_layout

_FAR = 1e3  # position of the padding "sensor": never within range of anything
_SUBDIV = 2  # grid cells per sensing radius (2 * spacing)
_XYZ = np.arange(3)


class Skin:
    """Tactile sensors of the infant in one compiled model.

    Each sensor reports the 3-D force on its body, in the body's frame (facts sec. 2). A contact
    force is spread over the sensors of the touched body within r = 2 * spacing of the contact
    point, with weights max(0, 1 - d / r) normalised to sum to 1, so force is conserved; with
    no sensor in range the nearest sensor takes it all.

    Attributes:
        num_sensors: N.
        sensor_body: (N,) int64 MuJoCo body id of each sensor.
        sensor_pos: (N, 3) float64 position in its body's frame (metres).
        sensor_region: (N,) int64 body-map region in [0, 68).
        region_sizes: (68,) int64 sensors per region.
        body_spacing: (nbody,) float64 sensor spacing per body (0: no skin).
    """

    def __init__(self, model: mujoco.MjModel, layout: SkinLayout | None = None) -> None:
        """``layout``: where the sensors sit (default: the default body's, from ``model``; a
        grown body's is :func:`~devlearn.infant.skin_layout.grown_layout`)."""
        layout = skin_layout(model) if layout is None else layout
        ids = {n: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n) for n in set(layout.body)}
        self.sensor_body = np.array([ids[name] for name in layout.body], dtype=np.int64)
        self.sensor_pos = layout.pos.copy()
        self.sensor_region = layout.region.copy()
        self.num_sensors = len(self.sensor_pos)
        self.region_sizes = np.bincount(self.sensor_region, minlength=NUM_REGIONS)
        self.body_spacing = np.zeros(model.nbody)
        for name, spacing in layout.spacing.items():
            self.body_spacing[ids[name]] = spacing
        self.radius = 2.0 * self.body_spacing
        self._build_grid(model.nbody)

    def _build_grid(self, nbody: int) -> None:
        """Per body, a grid of cells radius / 2 wide; each cell lists every sensor within one
        radius of the cell's box, so a point's cell list holds all sensors in its range."""
        self._lo = np.zeros((nbody, 3))
        self._dims = np.ones((nbody, 3), dtype=np.int64)
        self._strides = np.zeros((nbody, 3), dtype=np.int64)
        self._inv_cell = np.ones(nbody)
        self._offset = np.zeros(nbody, dtype=np.int64)
        reach = np.arange(-_SUBDIV, _SUBDIV + 1)
        offsets = np.stack(np.meshgrid(reach, reach, reach, indexing="ij"), -1).reshape(-1, 3)
        cells_list, sensors_list = [], []
        total = 0
        for b in range(nbody):
            idx = np.flatnonzero(self.sensor_body == b)
            if len(idx) == 0:
                continue
            r = self.radius[b]
            cell = r / _SUBDIV
            pts = self.sensor_pos[idx]
            lo = pts.min(0) - r
            dims = np.floor((pts.max(0) + r - lo) / cell).astype(np.int64) + 1
            strides = np.array([dims[1] * dims[2], dims[2], 1])
            self._lo[b], self._dims[b], self._strides[b] = lo, dims, strides
            self._inv_cell[b], self._offset[b] = 1.0 / cell, total
            near = np.floor((pts - lo) / cell).astype(np.int64)[:, None, :] + offsets  # (n,k,3)
            box_lo = lo + near * cell
            gap = np.maximum(0.0, np.maximum(box_lo - pts[:, None], pts[:, None] - box_lo - cell))
            ok = np.all((near >= 0) & (near < dims), axis=2) & (np.linalg.norm(gap, axis=2) <= r)
            cells_list.append(total + (near @ strides)[ok])
            sensors_list.append(np.broadcast_to(idx[:, None], ok.shape)[ok])
            total += int(np.prod(dims))
        cell_of, sensor = np.concatenate(cells_list), np.concatenate(sensors_list)
        order = np.lexsort((sensor, cell_of))
        cell_of, sensor = cell_of[order], sensor[order]
        counts = np.bincount(cell_of, minlength=total)
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        self._cells = np.full((total, max(1, int(counts.max()))), self.num_sensors, np.int32)
        self._cells[cell_of, np.arange(len(cell_of)) - starts[cell_of]] = sensor
        self._pos_padded = np.vstack([self.sensor_pos, np.full((1, 3), _FAR)])
        self._params = np.concatenate(
            [
                self._lo,
                self._inv_cell[:, None],
                self._dims - 1,
                self._strides,
                self._offset[:, None],
            ],
            axis=1,
        ).astype(np.float64)
        self._cell_count = np.maximum(counts, 1)
        self._inv_radius = np.divide(1.0, self.radius, out=np.zeros(nbody), where=self.radius > 0)

    def candidates(self, bodies: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Sensors that may be in range of each point, and their distances.

        Args:
            bodies: (Q,) body ids (bodies with skin).
            points: (Q, 3) points in those bodies' frames.

        Returns:
            (Q, K) int64 sensor indices (padding = num_sensors, far away) and (Q, K) distances.
        """
        # Few, fused numpy calls (np.take, ufuncs with out=): this runs every step and the
        # arrays are tiny, so call overhead is the cost.
        par = self._params.take(bodies, 0)  # lo (3), 1 / cell, dims - 1 (3), strides (3), offset
        cells = points - par[:, 0:3]
        cells *= par[:, 3:4]
        np.maximum(cells, 0.0, out=cells)
        np.minimum(cells, par[:, 4:7], out=cells)
        np.floor(cells, out=cells)
        flat = (np.einsum("qi,qi->q", cells, par[:, 7:10]) + par[:, 10]).astype(np.int64)
        cand = self._cells.take(flat, 0)[:, : self._cell_count.take(flat).max()]
        diff = self._pos_padded.take(cand, 0)
        diff -= points[:, None, :]
        dist = np.einsum("qki,qki->qk", diff, diff)
        return cand, np.sqrt(dist, out=dist)

    def nearest(
        self,
        bodies: np.ndarray,
        points: np.ndarray,
        cand: np.ndarray | None = None,
        dist: np.ndarray | None = None,
    ) -> np.ndarray:
        """Index of the nearest sensor of each body to each point, (Q,) int64.

        ``cand``/``dist`` from :meth:`candidates` may be passed to avoid recomputing them.
        """
        if cand is None or dist is None:
            cand, dist = self.candidates(bodies, points)
        best = cand[np.arange(len(cand)), np.argmin(dist, axis=1)]
        for q in np.flatnonzero(best == self.num_sensors):  # no sensor near the point: rare
            idx = np.flatnonzero(self.sensor_body == bodies[q])
            best[q] = idx[np.argmin(np.linalg.norm(self.sensor_pos[idx] - points[q], axis=1))]
        return best

    def spread_sparse(
        self,
        bodies: np.ndarray,
        points: np.ndarray,
        forces: np.ndarray,
        cand: np.ndarray | None = None,
        dist: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Spread contact forces over the skin: the sensors that receive force.

        Args:
            bodies: (Q,) body id receiving each force (bodies with skin).
            points: (Q, 3) contact points in that body's frame.
            forces: (Q, 3) forces on that body, in its frame (N).
            cand, dist: Optional output of :meth:`candidates` for these points.

        Returns:
            sensors: (M,) int64, sorted and unique, the sensors within range of some contact.
            values: (M, 3) float32, their summed forces (body frames, N); the other sensors
            feel none (:meth:`dense` gives the whole (num_sensors, 3) vector).
        """
        if len(bodies) == 0:
            return np.zeros(0, dtype=np.int64), np.zeros((0, 3), dtype=np.float32)
        if cand is None or dist is None:
            cand, dist = self.candidates(bodies, points)
        weight = 1.0 - dist * self._inv_radius.take(bodies)[:, None]
        np.maximum(weight, 0.0, out=weight)
        total = weight.sum(axis=1)
        if total.min() <= 0.0:  # nothing in range: all of it to the nearest sensor
            rows = np.flatnonzero(total <= 0.0)
            nearest = self.nearest(bodies[rows], points[rows], cand[rows], dist[rows])
            cand, weight = cand.copy(), weight.copy()
            cand[rows, 0], weight[rows], total[rows] = nearest, 0.0, 1.0
            weight[rows, 0] = 1.0
        weight /= total[:, None]
        keep = np.flatnonzero(weight.ravel())  # in range (drops the padding sensor too)
        flat = cand.ravel().take(keep)
        sensors, slot = np.unique(flat, return_inverse=True)
        values = weight.ravel().take(keep)[:, None] * np.repeat(forces, cand.shape[1], 0)[keep]
        index = (slot[:, None] * 3 + _XYZ).ravel()
        out = np.bincount(index, values.ravel(), minlength=3 * len(sensors))
        return sensors, out.reshape(-1, 3).astype(np.float32)

    def dense(self, sensors: np.ndarray, values: np.ndarray) -> np.ndarray:
        """The forces of :meth:`spread_sparse` on every sensor, (num_sensors, 3) float32 (zero
        on the sensors it did not name)."""
        out = np.zeros((self.num_sensors, 3), dtype=np.float32)
        out[sensors] = values
        return out
