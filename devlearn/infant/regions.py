"""The 68-region body map (paper sec. II-A): 34 parts per side, and the rules that place sensors."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# Per side: face 5, torso 7, arm 9, leg 9, foot 4 (paper sec. II-A). Order fixes region indices.
CATEGORIES: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("face", ("forehead", "cheek", "mouth", "ear", "back_of_head")),
    ("torso", ("chest", "upper_back", "flank", "belly", "lower_back", "pelvis", "buttock")),
    (
        "arm",
        (
            "shoulder",
            "upper_arm_inner",
            "upper_arm_outer",
            "forearm_inner",
            "forearm_outer",
            "palm",
            "back_of_hand",
            "fingers_inner",
            "fingers_outer",
        ),
    ),
    (
        "leg",
        (
            "thigh_front",
            "thigh_back",
            "thigh_inner",
            "thigh_outer",
            "knee",
            "shin",
            "calf",
            "lower_leg_inner",
            "lower_leg_outer",
        ),
    ),
    ("foot", ("sole", "heel", "top_of_foot", "toes")),
)
PART_NAMES: tuple[str, ...] = tuple(p for _, parts in CATEGORIES for p in parts)
PART_CATEGORY: tuple[str, ...] = tuple(c for c, parts in CATEGORIES for _ in parts)
NUM_PARTS = len(PART_NAMES)  # 34
NUM_REGIONS = 2 * NUM_PARTS  # 68: left parts 0..33, right parts 34..67
_P = {name: i for i, name in enumerate(PART_NAMES)}


@dataclass(frozen=True)
class RegionTable:
    """The 68 skin regions: index j = side * 34 + part (side 0 left, 1 right).

    Attributes:
        names: (68,) str, "left_cheek" ... "right_toes".
        sides: (68,) str, "left" or "right".
        parts: (68,) int in [0, 34), the side-free part of each region.
        part_names: (34,) str, side-free part names ("cheek").
        categories: (68,) str, face / torso / arm / leg / foot.
    """

    names: np.ndarray
    sides: np.ndarray
    parts: np.ndarray
    part_names: np.ndarray
    categories: np.ndarray

    def index(self, name: str) -> int:
        """Region index of a full name ("left_cheek"); raises with the valid names."""
        hits = np.flatnonzero(self.names == name)
        if len(hits) == 0:
            raise KeyError(f"unknown region '{name}'; valid: {', '.join(self.names)}")
        return int(hits[0])


def region_table() -> RegionTable:
    """Build the region table (cheap, immutable)."""
    sides = np.repeat(np.array(["left", "right"]), NUM_PARTS)
    parts = np.tile(np.arange(NUM_PARTS), 2)
    names = np.array([f"{s}_{PART_NAMES[p]}" for s, p in zip(sides, parts)])
    categories = np.array([PART_CATEGORY[p] for p in parts])
    return RegionTable(names, sides, parts, np.array(PART_NAMES), categories)


def assign_parts(
    body: str, geom: str, p_body: np.ndarray, p_geom: np.ndarray, geom_size: np.ndarray
) -> np.ndarray:
    """Side-free part of each sensor of one geom, from its position (left side, y >= 0).

    The body frames are those of the standing pose (x forward, y left, z up); on the left side
    +y is lateral (outer), and midline bodies are split at y = 0 by the caller.

    Args:
        body: Side-free body name ("upper_arm").
        geom: Side-free geom name ("ribs").
        p_body: (n, 3) sensor positions in the body frame.
        p_geom: (n, 3) the same in the geom frame (capsule axis = z).
        geom_size: The geom's MuJoCo size (capsule: radius, half-length).

    Returns:
        (n,) int part indices in [0, 34).
    """
    x, y, z = p_body.T
    n = len(p_body)
    out = np.full(n, -1, dtype=np.int64)

    def pick(*pairs: tuple[np.ndarray, str]) -> np.ndarray:
        for mask, part in pairs:
            free = (out < 0) & mask
            out[free] = _P[part]
        return out

    if body == "head":
        u = p_geom / np.linalg.norm(p_geom, axis=1, keepdims=True)
        pick(
            (u[:, 1] > 0.7, "ear"),
            (u[:, 0] < -0.1, "back_of_head"),
            (u[:, 2] > 0.3, "forehead"),
            ((u[:, 2] < -0.15) & (u[:, 1] < 0.45), "mouth"),
            (np.ones(n, bool), "cheek"),
        )
    elif body == "hip":
        pick((x >= 0, "pelvis"), (x < 0, "buttock"))
    elif body in ("lower_body", "upper_body"):
        # The capsules run along y: the sides of their end caps are the flanks.
        end_cap = (np.abs(p_geom[:, 2]) > geom_size[1]) & (np.abs(x) < 0.5 * geom_size[0])
        front, back = (
            ("chest", "upper_back") if geom in ("ribs", "shoulders") else ("belly", "lower_back")
        )
        pick((end_cap & (geom != "shoulders"), "flank"), (x >= 0, front), (x < 0, back))
    elif body == "upper_arm":
        pick((z > -0.01, "shoulder"), (y < 0, "upper_arm_inner"), (y >= 0, "upper_arm_outer"))
    elif body == "lower_arm":
        pick((x >= 0, "forearm_inner"), (x < 0, "forearm_outer"))
    elif body == "hand":
        pick((x > 0, "palm"), (x <= 0, "back_of_hand"))
    elif body == "fingers":
        pick((x > 0, "fingers_inner"), (x <= 0, "fingers_outer"))
    elif body in ("upper_leg", "lower_leg"):
        names = ("thigh_front", "thigh_back", "thigh_inner", "thigh_outer")
        if body == "lower_leg":
            names = ("shin", "calf", "lower_leg_inner", "lower_leg_outer")
            pick((z > -0.015, "knee"))
        pick(
            (x >= np.abs(y), names[0]),
            (-x >= np.abs(y), names[1]),
            (y < 0, names[2]),
            (y >= 0, names[3]),
        )
    elif body == "foot":
        pick((x < -0.01, "heel"), (z < -0.0445, "sole"), (np.ones(n, bool), "top_of_foot"))
    elif body == "toes":
        pick((np.ones(n, bool), "toes"))
    if np.any(out < 0):
        raise ValueError(f"no body-map part for some sensors of {body}/{geom}")
    return out
