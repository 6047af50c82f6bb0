"""The body map of paper sec. II-A2: mean contact force per anatomical region, g_t in R^68."""

from __future__ import annotations

import numpy as np

NUM_REGIONS = 68
"""G = 68 anatomical regions, 34 body parts per side (paper sec. II-A2)."""
NUM_PARTS = 34
"""Side-free body parts; a hand's coverage is counted out of these (BabyBench scoring)."""
HANDS = ("left", "right")
"""Row order of ``Infant.hand_contacts()``: (2 hands, 68)."""


def body_map(touch: np.ndarray, sensor_region: np.ndarray, region_sizes: np.ndarray) -> np.ndarray:
    """Mean force magnitude per region: g_j = (1/|S_j|) sum_{i in S_j} |o_i| (sec. II-A2).

    Args:
        touch: (num_sensors, 3) contact force per sensor (N).
        sensor_region: (num_sensors,) int region index in [0, 68) of every sensor.
        region_sizes: (68,) number of sensors per region (|S_j|).

    Returns:
        (68,) float32 mean force magnitude per region; 0 for a region without sensors.
    """
    touch = np.asarray(touch).reshape(-1, 3)
    sensors = np.flatnonzero(touch.any(axis=1))
    return sparse_body_map(sensors, touch[sensors], sensor_region, region_sizes)


def sparse_body_map(
    sensors: np.ndarray, forces: np.ndarray, sensor_region: np.ndarray, region_sizes: np.ndarray
) -> np.ndarray:
    """:func:`body_map` from the sensors that feel a force (``Infant.touch_sparse()``).

    Args:
        sensors: (M,) int indices of the sensors with a force; every other sensor reads 0.
        forces: (M, 3) their forces (N).
        sensor_region, region_sizes: as in :func:`body_map`.

    Returns:
        (68,) float32, equal to ``body_map`` of the dense vector.
    """
    f = np.asarray(forces, dtype=np.float64).reshape(-1, 3)
    magnitude = np.sqrt(np.einsum("ij,ij->i", f, f))
    regions = np.asarray(sensor_region).take(np.asarray(sensors, dtype=np.int64))
    sums = np.bincount(regions, weights=magnitude, minlength=NUM_REGIONS)
    sizes = np.asarray(region_sizes, dtype=np.float64)
    return (sums / np.maximum(sizes, 1.0)).astype(np.float32)


def body_map_observation(g: np.ndarray, scale: float) -> np.ndarray:
    """Scale the body map for the policy: log1p(g / scale), so that inputs are O(1).

    The raw g_j spans four orders of magnitude (a light hand touch ~0.3 N per sensor, a kick
    into the mattress ~30 N, a random initial pose pushed out of the mattress thousands);
    log1p keeps them all readable without saturating.

    Args:
        g: (68,) body map (N per sensor).
        scale: Force per sensor that maps to log(2) ~ 0.69.

    Returns:
        (68,) float32.
    """
    return np.log1p(np.asarray(g, dtype=np.float64) / float(scale)).astype(np.float32)


def hand_touched_parts(hand_contacts: np.ndarray, region_parts: np.ndarray) -> np.ndarray:
    """Side-free parts each hand touches: part p is touched by hand h if either side's is.

    Args:
        hand_contacts: (2, 68) bool, hand (left, right) touches region j (palm or fingers).
        region_parts: (68,) int part index in [0, 34) of every region.

    Returns:
        (2, 34) bool.
    """
    parts = np.zeros((len(HANDS), NUM_PARTS), dtype=bool)
    for h in range(len(HANDS)):
        parts[h, region_parts[np.asarray(hand_contacts[h], dtype=bool)]] = True
    return parts
