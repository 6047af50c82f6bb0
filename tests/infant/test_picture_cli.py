"""``devlearn picture``: its options, its module's ``run`` and the pictures."""

from __future__ import annotations

import gc

import cv2
import numpy as np
import pytest

from devlearn.cli import build_parser, picture


@pytest.fixture(autouse=True)
def no_leftover_renderers():
    """Renderers that earlier tests dropped without closing are freed now, not mid-render: a
    garbage-collected renderer frees its OpenGL context whenever the collector runs, which
    in a full run could land inside this test's render (it passed alone, failed in order)."""
    gc.collect()
    yield


def _parse(argv):
    return build_parser().parse_args(argv)


@pytest.mark.parametrize(
    "what, shape",
    [("eyes", (256, 865, 3)), ("body-map", (900, 1100, 3)), ("growth", (520, 5 * 250 + 4 * 4, 3))],
)
def test_picture_writes_png(tmp_path, capsys, what, shape):
    out = tmp_path / f"{what}.png"
    args = _parse(["picture", what, "--out", str(out)])
    assert picture.run(args, registry=None) == 0
    image = cv2.imread(str(out))
    assert image.shape == shape and image.std() > 10
    assert str(out) in capsys.readouterr().out


def test_unknown_picture_is_rejected():
    with pytest.raises(SystemExit):
        _parse(["picture", "nose", "--out", "x.png"])


def test_body_map_is_the_same_picture_every_time():
    from devlearn.infant.pictures import body_map_picture

    first = body_map_picture(width=120, height=240)
    again = body_map_picture(width=120, height=240)
    assert np.array_equal(first, again)  # mjv_initGeom left uninitialised fields: every differed


def test_the_growth_picture_shows_the_infant_growing():
    from devlearn.infant.pictures import growth_picture

    image = growth_picture()
    assert image.shape == (520, 1266, 3)
    crowns = []
    for k in range(5):  # each panel: the highest row of the body (not white, grey or text)
        panel = image[60:, k * 254 : k * 254 + 250].astype(int)
        coloured = (panel.max(axis=2) - panel.min(axis=2)) > 20  # skin, not the grey lines
        crowns.append(int(np.flatnonzero(coloured.any(axis=1))[0]))
    assert all(a > b for a, b in zip(crowns, crowns[1:])), crowns  # taller at every age
    again = growth_picture(ages=(0.0, 24.0), width=80, height=160)
    assert np.array_equal(again, growth_picture(ages=(0.0, 24.0), width=80, height=160))
