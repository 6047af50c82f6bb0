"""The infant's compiled hot path (numba): touch as one routine (contact decoding, sensor search
and force spread) and the proprioception gather.

Imported on first use only (``ContactReader.touch_and_hands``, ``Proprioception.__call__``):
whatever only builds or describes an infant (``devlearn info``) never loads numba. Each routine
computes exactly what its numpy reference does (the equivalence tests compare them bit for bit);
``build_infant(..., compiled=False)`` runs the references instead."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numba
import numpy as np
from llvmlite import ir
from numba.core import types
from numba.extending import intrinsic

# Every loop below repeats, operation for operation, what the numpy reference path
# (ContactReader.sides, Skin.candidates / nearest / spread_sparse, contacts.hand_contacts)
# computes, in the same order where the order changes a float: sums over a candidate row follow
# numpy's pairwise summation, sensor sums follow np.bincount's order of occurrence. The
# equivalence test (tests/infant/test_touch_kernel.py) compares the two on recorded contacts.
# The reference's 2-D product (edges @ pyramid) and its stacked (Q, 2, 3) @ (Q, 3, 3) product go
# through BLAS, which on FMA hardware accumulates with fused multiply-adds (OpenBLAS's
# Haswell-and-later kernels); those two are repeated here with fma, in BLAS's k order. The
# (Q, 1, 3) @ (Q, 3, 3) product is numpy's own loop: plain multiply, then add.

# cache: compiled once per machine, not per process
_JIT: dict[str, Any] = {"cache": True, "nogil": True}


@intrinsic
def _fma(typingctx: Any, a: Any, b: Any, c: Any) -> tuple[Any, Callable[..., Any]]:
    """a * b + c with one rounding (LLVM's llvm.fma: fused even where the CPU lacks FMA)."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        double = ir.DoubleType()
        fnty = ir.FunctionType(double, [double, double, double])
        fn = builder.module.declare_intrinsic("llvm.fma", [double], fnty)
        return builder.call(fn, args)

    return sig, codegen


MAX_CANDIDATES = 128
"""Longest candidate list the kernel sums (numpy's pairwise block; longer ones recurse)."""


@numba.njit(**_JIT)
def _pairwise_sum(a: np.ndarray, n: int) -> float:
    """numpy's pairwise sum of ``a[:n]``, n <= 128 (what ``ndarray.sum`` does on a row)."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[i]
        return res
    r0, r1, r2, r3, r4, r5, r6, r7 = a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7]
    i = 8
    while i < n - (n % 8):
        r0 += a[i]
        r1 += a[i + 1]
        r2 += a[i + 2]
        r3 += a[i + 3]
        r4 += a[i + 4]
        r5 += a[i + 5]
        r6 += a[i + 6]
        r7 += a[i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[i]
        i += 1
    return res


@numba.njit(**_JIT)
def _nearest(
    q: int, body: np.ndarray, point: np.ndarray, cand: np.ndarray, dist: np.ndarray, k_max: int,
    num_sensors: int, sensor_body: np.ndarray, sensor_pos: np.ndarray,
) -> int:  # fmt: skip
    """Skin.nearest for row q: nearest candidate, else the nearest sensor of the body."""
    best_k = 0
    for k in range(1, k_max):
        if dist[q, k] < dist[q, best_k]:
            best_k = k
    best = cand[q, best_k]
    if best != num_sensors:
        return best
    best_d = np.inf
    for s in range(num_sensors):  # no sensor near the point: rare
        if sensor_body[s] == body[q]:
            d0 = sensor_pos[s, 0] - point[q, 0]
            d1 = sensor_pos[s, 1] - point[q, 1]
            d2 = sensor_pos[s, 2] - point[q, 2]
            d = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
            if d < best_d:
                best_d, best = d, s
    return best


@numba.njit(**_JIT)
def contact_touch(
    con_geom: np.ndarray, con_efc: np.ndarray, con_pos: np.ndarray, con_frame: np.ndarray,
    efc_force: np.ndarray, xpos: np.ndarray, xmat: np.ndarray,
    geom_body: np.ndarray, geom_skin: np.ndarray, mu: float, params: np.ndarray,
    cells: np.ndarray, cell_count: np.ndarray, pos_padded: np.ndarray, inv_radius: np.ndarray,
    sensor_body: np.ndarray, sensor_pos: np.ndarray, sensor_region: np.ndarray,
    hand_of_body: np.ndarray, acc: np.ndarray, mark: np.ndarray, num_regions: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """Sparse touch and hand contacts of one step, from MuJoCo's contact list.

    Args:
        con_geom (C, 2) int, con_efc (C,) int, con_pos (C, 3), con_frame (C, 9): the contacts.
        efc_force (nefc,), xpos (nbody, 3), xmat (nbody, 9): constraint forces, body poses.
        geom_body, geom_skin (ngeom,): body of each geom, whether that body has skin.
        mu: The one sliding friction of every geom (pyramidal cone, condim 3).
        params, cells, cell_count, pos_padded, inv_radius: the skin's neighbour grid.
        sensor_body, sensor_pos, sensor_region: the sensor table (N sensors).
        hand_of_body (nbody,): 0 left hand, 1 right hand, -1 not a hand.
        acc, mark: (N, 3) float64 and (N,) bool scratch, all zero; left all zero.
        num_regions: 68.

    Returns:
        sensors (M,) int64 sorted, forces (M, 3) float32, hand_contacts (2, num_regions) bool.
    """
    num_sensors = sensor_pos.shape[0]
    hands = np.zeros((2, num_regions), dtype=np.bool_)
    ncon = con_geom.shape[0]
    ids = np.empty(ncon, dtype=np.int64)
    m = 0
    for c in range(ncon):  # gap or excluded contacts carry no force: drop them
        if con_efc[c] >= 0:
            ids[m] = c
            m += 1
    if m == 0:
        return np.zeros(0, np.int64), np.zeros((0, 3), np.float32), hands
    # Sides: geom1 of every kept contact, then geom2 (the reference's order), skin only.
    nq = 0
    side_row = np.empty(2 * m, dtype=np.int64)
    for r in range(2 * m):
        if geom_skin[con_geom[ids[r % m], r // m]]:
            side_row[nq] = r
            nq += 1
    if nq == 0:
        return np.zeros(0, np.int64), np.zeros((0, 3), np.float32), hands
    body = np.empty(nq, dtype=np.int64)
    other = np.empty(nq, dtype=np.int64)
    point = np.empty((nq, 3))
    force = np.empty((nq, 3))
    world = np.empty(3)
    fworld = np.empty(3)
    local = np.empty(3)
    for q in range(nq):
        r = side_row[q]
        c = ids[r % m]
        g = r // m
        b = geom_body[con_geom[c, g]]
        body[q] = b
        other[q] = geom_body[con_geom[c, 1 - g]]
        for i in range(3):
            world[i] = con_pos[c, i] - xpos[b, i]
        a = con_efc[c]
        e0, e1, e2, e3 = efc_force[a], efc_force[a + 1], efc_force[a + 2], efc_force[a + 3]
        # edges @ [[1, mu, 0], [1, -mu, 0], [1, 0, mu], [1, 0, -mu]] (mju_decodePyramid), as
        # BLAS accumulates it over the 4 edges (products by 0 and 1 are exact and left out)
        local[0] = ((e0 + e1) + e2) + e3
        # (an @intrinsic: numba passes its typing context; the stubs ask for it)
        local[1] = _fma(e1, -mu, e0 * mu)  # type: ignore[call-arg]
        local[2] = _fma(e3, -mu, e2 * mu)
        for j in range(3):  # f_world = f_local @ frame (rows: normal, tangents); numpy's loop
            fworld[j] = (local[0] * con_frame[c, j] + local[1] * con_frame[c, 3 + j]) + local[
                2
            ] * con_frame[c, 6 + j]
        if g == 0:  # geom1's body feels the opposite force
            for j in range(3):
                fworld[j] = -fworld[j]
        for j in range(3):  # row vectors times R, into the body frame; BLAS (fma) order
            r0, r1, r2 = xmat[b, j], xmat[b, 3 + j], xmat[b, 6 + j]
            point[q, j] = _fma(world[2], r2, _fma(world[1], r1, world[0] * r0))
            force[q, j] = _fma(fworld[2], r2, _fma(fworld[1], r1, fworld[0] * r0))
    # Candidates: the grid cell of each point lists every sensor that may be in range.
    flat = np.empty(nq, dtype=np.int64)
    k_max = 1
    for q in range(nq):
        p = params[body[q]]
        total = 0.0
        for i in range(3):
            cell = (point[q, i] - p[i]) * p[3]
            cell = min(max(cell, 0.0), p[4 + i])
            total += np.floor(cell) * p[7 + i]
        flat[q] = np.int64(total + p[10])
        k_max = max(k_max, cell_count[flat[q]])
    cand = np.empty((nq, k_max), dtype=np.int64)
    dist = np.empty((nq, k_max))
    for q in range(nq):
        for k in range(k_max):
            s = cells[flat[q], k]
            cand[q, k] = s
            d0 = pos_padded[s, 0] - point[q, 0]
            d1 = pos_padded[s, 1] - point[q, 1]
            d2 = pos_padded[s, 2] - point[q, 2]
            dist[q, k] = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    # Hand contacts: the touched side's region nearest to the contact, per touching hand.
    for q in range(nq):
        hand = hand_of_body[other[q]]
        if hand >= 0 and hand_of_body[body[q]] != hand:
            s = _nearest(q, body, point, cand, dist, k_max, num_sensors, sensor_body, sensor_pos)
            hands[hand, sensor_region[s]] = True
    # Spread: weights max(0, 1 - d / r), normalised; nothing in range: the nearest takes it all.
    weight = np.empty(k_max)
    touched = np.empty(nq * k_max, dtype=np.int64)
    count = 0
    for q in range(nq):
        inv_r = inv_radius[body[q]]
        for k in range(k_max):
            weight[k] = max(1.0 - dist[q, k] * inv_r, 0.0)
        total = _pairwise_sum(weight, k_max)
        if total <= 0.0:
            best = _nearest(q, body, point, cand, dist, k_max, num_sensors, sensor_body, sensor_pos)
            cand[q, 0] = best
            weight[:] = 0.0
            weight[0] = 1.0
            total = 1.0
        for k in range(k_max):
            w = weight[k] / total
            if w != 0.0:
                s = cand[q, k]
                if not mark[s]:
                    mark[s] = True
                    touched[count] = s
                    count += 1
                for j in range(3):
                    acc[s, j] += w * force[q, j]
    listed = np.sort(touched[:count])
    sensors = np.empty(len(listed), dtype=np.int64)
    values = np.empty((len(listed), 3), dtype=np.float32)
    for i in range(len(listed)):
        s = listed[i]
        sensors[i] = s
        for j in range(3):
            values[i, j] = np.float32(acc[s, j])
            acc[s, j] = 0.0
        mark[s] = False
    return sensors, values, hands


@numba.njit(inline="always")
def _min(a: float, b: float) -> float:
    """np.minimum of two floats (NaN if either is NaN)."""
    return a if (a < b or a != a) else b


@numba.njit(inline="always")
def _max(a: float, b: float) -> float:
    """np.maximum of two floats (NaN if either is NaN)."""
    return a if (a > b or a != a) else b


@numba.njit(**_JIT)
def gather(
    qpos: np.ndarray, qvel: np.ndarray, qfrc_actuator: np.ndarray, qfrc_passive: np.ndarray,
    qfrc_constraint: np.ndarray, ctrl: np.ndarray, qpos_index: np.ndarray, dof: np.ndarray,
    lo: np.ndarray, hi: np.ndarray, limit_zone: float, out: np.ndarray,
) -> None:  # fmt: skip
    """``Proprioception.reference`` (:mod:`devlearn.infant.senses`) into ``out`` (6 J,) float32,
    element by element: the same float64 operations in the same order (no fast-math), each
    rounded once to float32. ``limit_zone`` is the caller's ``LIMIT_ZONE`` (passed, not imported,
    so that senses, which imports this module lazily, is not imported back)."""
    n = dof.shape[0]
    for i in range(n):
        q = qpos[qpos_index[i]]
        d = dof[i]
        to_limit = _min(q - lo[i], hi[i] - q)
        limit = _min(_max(1.0 - to_limit / limit_zone, 0.0), 1.0)
        motor = qfrc_actuator[d]
        out[i] = q
        out[n + i] = qvel[d]
        out[2 * n + i] = (motor + qfrc_passive[d]) + qfrc_constraint[d]
        out[3 * n + i] = limit
        out[4 * n + i] = ctrl[i]
        out[5 * n + i] = motor
