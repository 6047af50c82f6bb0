"""Self-touch facts and observations of a worker's environments at once (one compiled pass each).

:func:`batch_touch_facts` gives, for every infant, exactly (bit for bit) the facts of
:func:`~devlearn_self_touch.behavior.touch_facts` (that infant alone), and
:func:`batch_touch_observations` the observations of
:func:`~devlearn_self_touch.behavior.touch_observations`;
``plugins/self_touch/tests/test_batched_facts.py`` compares them on recorded steps. The body
map's sums repeat numpy's float operations in numpy's order (see :func:`_touch_row`); the rest
is boolean or done by the same numpy calls over the batch.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numba
import numpy as np

from devlearn_self_touch.body_map import HANDS, NUM_PARTS, NUM_REGIONS


@numba.njit(cache=True, nogil=True)
def _touch_row(
    sensors: np.ndarray, forces: np.ndarray, sensor_region: np.ndarray,
    region_sizes: np.ndarray, hands: np.ndarray, region_parts: np.ndarray, g: np.ndarray,
    contacts: np.ndarray, parts: np.ndarray,
) -> None:  # fmt: skip
    """One infant's facts into its rows: ``g`` (68,) float32 the body map of
    :func:`~devlearn_self_touch.body_map.sparse_body_map`, ``contacts`` (2, 68) a copy of
    ``hands`` and ``parts`` (2, 34) bool :func:`~devlearn_self_touch.body_map.hand_touched_parts`.

    sparse_body_map takes |f| with ``np.einsum("ij,ij->i", f, f)``, whose two-lane SIMD loop
    (numpy's baseline build; einsum is not dispatched per CPU) adds the products as
    (f0² + f2²) + f1²; np.bincount then sums the magnitudes per region in sensor order, from 0.
    """
    sums = np.zeros(g.shape[0])
    for k in range(sensors.shape[0]):
        f0 = np.float64(forces[k, 0])
        f1 = np.float64(forces[k, 1])
        f2 = np.float64(forces[k, 2])
        sums[sensor_region[sensors[k]]] += np.sqrt((f0 * f0 + f2 * f2) + f1 * f1)
    for j in range(g.shape[0]):
        g[j] = np.float32(sums[j] / max(np.float64(region_sizes[j]), 1.0))
    parts[:] = False
    for h in range(hands.shape[0]):
        for j in range(hands.shape[1]):
            contacts[h, j] = hands[h, j]
            if hands[h, j]:
                parts[h, region_parts[j]] = True


def batch_touch_facts(
    infants: Sequence[Any], touch_source: str, touch_threshold: float
) -> list[dict[str, np.ndarray]]:
    """:func:`~devlearn_self_touch.behavior.touch_facts` of every infant; each fact is a row of
    one (num_envs, ...) array.

    Args:
        infants: (num_envs,) infants after this step's physics (touch sense enabled).
        touch_source: :attr:`SelfTouchConfig.touch_source`.
        touch_threshold: :attr:`SelfTouchConfig.touch_threshold`.
    Returns:
        Per infant ``body_map`` (68,) float32, ``hand_contacts`` (2, 68) bool, ``hand_parts``
        (2, 34) bool and ``touched`` (68,) bool.
    """
    n = len(infants)
    g = np.empty((n, NUM_REGIONS), dtype=np.float32)
    contacts = np.empty((n, len(HANDS), NUM_REGIONS), dtype=bool)
    parts = np.empty((n, len(HANDS), NUM_PARTS), dtype=bool)
    for i, infant in enumerate(infants):
        skin, (sensors, forces) = infant.skin, infant.touch_sparse()
        hands = np.asarray(infant.hand_contacts(), dtype=bool)
        region_parts = np.asarray(infant.regions.parts)
        _touch_row(sensors, forces, skin.sensor_region, skin.region_sizes, hands, region_parts,
                   g[i], contacts[i], parts[i])  # fmt: skip
    if touch_source == "hands":
        touched = contacts.any(axis=1)
    else:
        above = g > touch_threshold  # float32 against the Python float, as touch_facts() compares
        touched = above if touch_source == "threshold" else contacts.any(axis=1) | above
    # touched is (n, 68) bool; numpy's stubs also allow a scalar for any(axis=1) and ">"
    return [
        {"body_map": g[i], "hand_contacts": contacts[i], "hand_parts": parts[i], "touched": t}
        for i, t in enumerate(touched)  # type: ignore[arg-type]
    ]


def batch_touch_observations(
    infants: Sequence[Any], facts: Sequence[dict[str, np.ndarray]], body_map_scale: float
) -> dict[str, np.ndarray]:
    """:func:`~devlearn_self_touch.behavior.touch_observations` of every infant, stacked.

    Returns:
        ``body_map`` (num_envs, 68) float32 log1p(g / scale) and ``proprioception``
        (num_envs, P) float32.
    """
    g = _rows([f["body_map"] for f in facts])
    return {
        "body_map": np.log1p(g.astype(np.float64) / float(body_map_scale)).astype(np.float32),
        "proprioception": _rows([np.asarray(i.proprioception(), np.float32) for i in infants]),
    }


def _rows(arrays: list[np.ndarray]) -> np.ndarray:
    """Stack equal-shaped arrays, (n, *shape); one array becomes a (1, *shape) view of it."""
    if len(arrays) == 1:
        return arrays[0][None]
    out = np.empty((len(arrays), *arrays[0].shape), dtype=arrays[0].dtype)
    for i, array in enumerate(arrays):
        out[i] = array
    return out
