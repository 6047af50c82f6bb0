"""The three visibility criteria on a scripted scene: an eye, a hand and a toy."""

from __future__ import annotations

import mujoco  # noqa: E402
import numpy as np
import pytest
from devlearn_hand_regard.visibility import axis_angles, pixel_counts, visible  # noqa: E402

import devlearn  # noqa: F401  (sets MUJOCO_GL before mujoco loads)

# The eye at the origin looks along +x (its frame's -z); a 4 cm ball is the hand, a 10 cm box
# the toy. Lying on the camera frame's x axis (image "right") puts the hand at 20 degrees.
SCENE = """
<mujoco>
  <visual><global offwidth="64" offheight="64"/></visual>
  <worldbody>
    <light pos="0 0 2" dir="0 0 -1"/>
    <camera name="eye" pos="0 0 0" xyaxes="0 -1 0 0 0 1" fovy="60"/>
    <body name="hand" mocap="true" pos="0.5 0 0">
      <geom name="mitten" type="sphere" size="0.04"/>
    </body>
    <body name="toy" mocap="true" pos="0 5 0"><geom type="box" size="0.05 0.05 0.05"/></body>
  </worldbody>
</mujoco>
"""


@pytest.fixture(scope="module")
def scene():
    model = mujoco.MjModel.from_xml_string(SCENE)
    renderer = mujoco.Renderer(model, 64, 64)
    renderer.enable_segmentation_rendering()
    yield model, mujoco.MjData(model), renderer
    renderer.close()


def criteria(scene, hand, toy=(0.0, 5.0, 0.0)):
    model, data, renderer = scene
    data.mocap_pos[0], data.mocap_pos[1] = hand, toy
    mujoco.mj_forward(model, data)
    renderer.update_scene(data, camera="eye")
    seg = renderer.render()  # (64, 64, 2): object id, object type
    mitten = model.geom("mitten").id
    labels = np.where((seg[..., 0] == mitten) & (seg[..., 1] == mujoco.mjtObj.mjOBJ_GEOM), 1, 0)
    pixels = pixel_counts(labels[None], (1,))
    camera, hand_body = np.array([model.camera("eye").id]), np.array([model.body("hand").id])
    angles = axis_angles(data, camera, hand_body)
    verdicts = visible(angles, pixels)
    return {k: bool(v[0, 0]) for k, v in verdicts.items()}, float(angles[0, 0]), int(pixels[0, 0])


def test_hand_on_the_axis_is_seen_by_every_criterion(scene):
    seen, angle, pixels = criteria(scene, (0.5, 0.0, 0.0))
    assert angle == pytest.approx(0.0, abs=1e-6) and pixels >= 20
    assert seen == {"pixels": True, "cone": True, "any_pixel": True}


def test_hand_at_20_degrees_is_in_the_image_but_outside_the_cone(scene):
    a = np.radians(20)
    seen, angle, pixels = criteria(scene, (0.5 * np.cos(a), -0.5 * np.sin(a), 0.0))
    assert angle == pytest.approx(20.0, abs=1e-6) and pixels >= 20  # 60 degree eye: in view
    assert seen == {"cone": False, "pixels": True, "any_pixel": True}


def test_hand_hidden_behind_a_toy(scene):
    seen, angle, pixels = criteria(scene, (0.5, 0.0, 0.0), toy=(0.25, 0.0, 0.0))
    assert pixels == 0
    # The cone is geometry only (as BabyBench's counter); the pixel criteria see the occlusion.
    assert seen == {"cone": True, "pixels": False, "any_pixel": False}


def test_few_pixels_count_for_any_pixel_only():
    verdicts = visible(np.array([[40.0, 10.0]]), np.array([[3, 0]]))
    assert verdicts["any_pixel"].tolist() == [[True, False]]
    assert verdicts["pixels"].tolist() == [[False, False]]
    assert verdicts["cone"].tolist() == [[False, True]]


# BabyBench's counter: the eye *body's* -z axis. An eye body at the origin whose camera looks
# along +x (camera xyaxes in the body as in our infant and MIMo): the body's -z points down.
EYE_BODY = """
<mujoco>
  <worldbody>
    <body name="eye" pos="0 0 0">
      <camera name="cam" pos="0 0 0" xyaxes="0 -1 0 0 0 1" fovy="60"/>
    </body>
    <body name="hand" mocap="true" pos="0.5 0 0"><geom type="sphere" size="0.04"/></body>
  </worldbody>
</mujoco>
"""


@pytest.mark.parametrize(
    ("hand", "cone", "babybench"),
    [
        ((0.5, 0.0, 0.0), True, False),  # on the optical axis: in view, BabyBench misses it
        ((0.0, 0.0, -0.5), False, True),  # straight below the eye, out of view: BabyBench counts
        ((0.05, 0.0, -0.5), False, True),  # 5.7 degrees off the body's -z
        ((0.2, 0.0, -0.5), False, False),  # 21.8 degrees off
    ],
)
def test_babybench_counts_the_eye_body_minus_z_axis(hand, cone, babybench):
    from devlearn_hand_regard.visibility import babybench_angles

    model = mujoco.MjModel.from_xml_string(EYE_BODY)
    data = mujoco.MjData(model)
    data.mocap_pos[0] = hand
    mujoco.mj_forward(model, data)
    eye, hand_id = np.array([model.body("eye").id]), np.array([model.body("hand").id])
    verdicts = visible(
        axis_angles(data, np.array([model.camera("cam").id]), hand_id),
        np.zeros((1, 1)),
        babybench=babybench_angles(data, eye, hand_id),
    )
    assert bool(verdicts["cone"][0, 0]) == cone
    assert bool(verdicts["babybench"][0, 0]) == babybench
    assert list(verdicts) == ["pixels", "babybench", "cone", "any_pixel"]
