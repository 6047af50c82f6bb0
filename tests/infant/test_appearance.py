"""Appearances: bare skin-tone hands with natural toy colours, or purple mittens (default)."""

from __future__ import annotations

import numpy as np
import pytest

from devlearn.infant import build_infant
from devlearn.infant.body_table import MITTEN_RGBA, SKIN_RGBA
from devlearn.infant.scenes import NATURAL_TOY_COLOURS, TOY_COLOURS

HAND_GEOMS = ("left_hand", "left_fingers", "right_hand", "right_fingers")


def _geom_colours(infant, prefix: str) -> dict[str, np.ndarray]:
    model = infant.model
    names = [model.geom(g).name for g in range(model.ngeom)]
    return {n: model.geom_rgba[g] for g, n in enumerate(names) if n.startswith(prefix)}


def _hand_colours(infant) -> list[np.ndarray]:
    model = infant.model
    out = []
    for body in HAND_GEOMS:
        b = model.body(body)
        out += [model.geom_rgba[g] for g in range(b.geomadr[0], b.geomadr[0] + b.geomnum[0])]
    return out


@pytest.fixture(scope="module")
def skin():
    with build_infant("sitting", appearance="skin") as infant:
        yield infant


def test_skin_hands_are_the_body_colour(skin):
    forearm = skin.model.body("left_lower_arm")
    assert np.allclose(skin.model.geom_rgba[forearm.geomadr[0]], SKIN_RGBA)
    colours = _hand_colours(skin)
    assert len(colours) >= 4
    for rgba in colours:
        assert np.allclose(rgba, SKIN_RGBA)
    toys = _geom_colours(skin, "toy_")
    assert np.allclose(np.stack([toys[f"toy_{i}"] for i in range(4)]), NATURAL_TOY_COLOURS)
    assert skin.describe()["appearance"] == "skin"


def test_mittens_stay_the_default(sitting):
    for rgba in _hand_colours(sitting):
        assert np.allclose(rgba, MITTEN_RGBA)
    toys = _geom_colours(sitting, "toy_")
    assert np.allclose(np.stack([toys[f"toy_{i}"] for i in range(4)]), TOY_COLOURS)
    assert sitting.appearance == "mittens"


def test_hands_render_in_their_colour(sitting, skin):
    # The same random start in both appearances (same physics, same draws): the hand's
    # pixels are skin (red well above blue) bare, bluish purple (blue above green) in mittens.
    for seed in range(20):
        for infant in (skin, sitting):
            infant.reset(np.random.default_rng(seed), random_pose=True)
        seg = skin.eyes_segmentation()
        hand = (seg == 1) | (seg == 2)
        if hand.sum() >= 20:
            break
    else:
        pytest.fail("no random start in 20 shows a hand")
    assert np.array_equal(seg, sitting.eyes_segmentation())
    bare = skin.eyes()[hand].mean(0)
    mitten = sitting.eyes()[hand].mean(0)
    assert bare[0] > bare[2] + 25 and bare[1] > bare[2]
    assert mitten[2] > mitten[1] + 25


def test_same_physics_either_way(sitting, skin):
    assert skin.action_dim == sitting.action_dim
    assert np.allclose(skin.model.body_mass, sitting.model.body_mass)


def test_unknown_appearance_names_the_valid_ones():
    with pytest.raises(ValueError, match="unknown appearance 'socks'; valid appearances: "):
        build_infant("sitting", appearance="socks")
