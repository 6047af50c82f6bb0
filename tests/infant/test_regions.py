"""The 68-region body map: the table, and every sensor in exactly one region."""

from __future__ import annotations

import collections

import numpy as np

from devlearn.infant import NUM_PARTS, region_table


def test_region_table_shape_and_categories():
    regions = region_table()
    assert regions.names.shape == regions.sides.shape == regions.parts.shape == (68,)
    assert len(set(regions.names)) == 68 and len(regions.part_names) == NUM_PARTS == 34
    assert np.all((regions.parts >= 0) & (regions.parts < 34))
    for side in ("left", "right"):
        mine = regions.sides == side
        assert mine.sum() == 34
        assert sorted(regions.parts[mine]) == list(range(34))
        counts = collections.Counter(regions.categories[mine])
        assert counts == {"face": 5, "torso": 7, "arm": 9, "leg": 9, "foot": 4}  # paper II-A
    for j in range(68):
        assert regions.names[j] == f"{regions.sides[j]}_{regions.part_names[regions.parts[j]]}"
    assert regions.index("right_cheek") == 34 + list(regions.part_names).index("cheek")


def test_part_names_that_plugins_rely_on():
    names = list(region_table().part_names)
    assert "mouth" in names and "cheek" in names
    hand_like = [n for n in names if any(k in n for k in ("hand", "palm", "finger"))]
    assert hand_like == ["palm", "back_of_hand", "fingers_inner", "fingers_outer"]


def test_every_sensor_in_exactly_one_region(crib):
    skin, regions = crib.skin, crib.regions
    assert skin.sensor_region.shape == (skin.num_sensors,)
    assert np.all((skin.sensor_region >= 0) & (skin.sensor_region < 68))
    assert skin.region_sizes.shape == (68,) and skin.region_sizes.sum() == skin.num_sensors
    assert np.all(skin.region_sizes > 0)
    bodies = np.array([crib.model.body(b).name for b in skin.sensor_body])
    sides = regions.sides[skin.sensor_region]
    paired = np.array([b.startswith(("left_", "right_")) for b in bodies])
    assert all(b.startswith(s) for b, s in zip(bodies[paired], sides[paired]))
    # Midline bodies split at y = 0 of the body frame: +y is the infant's left.
    y = skin.sensor_pos[~paired, 1]
    assert np.all((y > 0) == (sides[~paired] == "left"))


def test_regions_follow_anatomy(crib):
    skin, regions = crib.skin, crib.regions
    part = regions.part_names[regions.parts[skin.sensor_region]]
    bodies = np.array([crib.model.body(b).name for b in skin.sensor_body])
    expect = {
        "head": {"forehead", "cheek", "mouth", "ear", "back_of_head"},
        "left_hand": {"palm", "back_of_hand"},
        "right_toes": {"toes"},
        "left_fingers": {"fingers_inner", "fingers_outer"},
        "hip": {"pelvis", "buttock"},
    }
    for body, parts in expect.items():
        assert set(part[bodies == body]) == parts
    palm = skin.sensor_pos[part == "palm"]
    assert np.all(palm[:, 0] > 0)  # palms face forward (+x) in the anatomical pose
