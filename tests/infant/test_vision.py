"""The eyes: images, segmentation and which hands each eye sees; the third-person view."""

from __future__ import annotations

import mujoco
import numpy as np

from devlearn.infant.pictures import EYES_POSE


def _pose(infant, pose):
    infant.reset(np.random.default_rng(0))
    for joint, angle in pose.items():
        for name in (f"left_{joint}", f"right_{joint}", joint):
            if name in infant.actuator_names:
                infant.data.qpos[infant.model.joint(name).qposadr[0]] = angle
    mujoco.mj_forward(infant.model, infant.data)
    infant._cache.clear()


def test_eye_images(sitting, crib):
    for infant in (sitting, crib):
        infant.reset(np.random.default_rng(0))
        eyes = infant.eyes()
        assert eyes.shape == (2, 64, 64, 3) and eyes.dtype == np.uint8
        assert eyes.std() > 5  # something is in view
        assert np.abs(eyes[0].astype(int) - eyes[1]).mean() > 0.5  # two viewpoints


def test_hands_in_view_are_seen_by_both_eyes(sitting):
    _pose(sitting, EYES_POSE)
    seg = sitting.eyes_segmentation()
    assert seg.shape == (2, 64, 64) and seg.dtype == np.int32
    assert sitting.hand_visibility().all()
    labels = sitting.hand_labels
    assert np.array_equal(
        sitting.hand_visibility(),
        [[(seg[e] == labels[h]).any() for h in ("left", "right")] for e in range(2)],
    )
    assert (seg == 4).any()  # floor and toys


def test_hands_behind_are_not_seen(sitting):
    _pose(sitting, {"head_tilt": -0.3, "shoulder_flexion": -0.6, "elbow": 0.0})
    assert not sitting.hand_visibility().any()


def test_render_view(crib):
    frame = crib.render_view(160, 120)
    assert frame.shape == (120, 160, 3) and frame.dtype == np.uint8 and frame.std() > 5


def test_segmentation_matches_mujoco_segmentation_mode(sitting):
    """Our id-colour decoding agrees pixel for pixel with mujoco.Renderer's own."""
    rng = np.random.default_rng(4)
    eyes = sitting._eye_renderer()
    for _ in range(3):
        sitting.reset(rng, random_pose=True)
        ours = sitting.eyes_segmentation()
        renderer = eyes.renderer
        renderer.enable_segmentation_rendering()
        try:
            for e, camera in enumerate(eyes.cameras):
                renderer.update_scene(sitting.data, camera=camera)
                ids = renderer.render()
                geom = np.where(ids[..., 1] == mujoco.mjtObj.mjOBJ_GEOM, ids[..., 0], -1)
                reference = np.where(geom >= 0, eyes.labels[geom], 0)
                assert np.array_equal(ours[e], reference)
        finally:
            renderer.disable_segmentation_rendering()


_RENDER_SCRIPT = """
import hashlib, os, sys
import numpy as np
import devlearn
from devlearn import build_infant
infant = build_infant("sitting_babybench", senses=("proprioception", "eyes"))
infant.reset(np.random.default_rng(0), start="babybench")
rng, digest = np.random.default_rng(1), hashlib.sha256()
for _ in range(20):
    infant.step(rng.uniform(-1, 1, infant.action_dim))
    digest.update(infant.eyes().tobytes())
print(os.environ["LP_NUM_THREADS"], digest.hexdigest())
"""


def test_the_rasteriser_draws_in_the_calling_thread_and_the_eyes_see_the_same(tmp_path):
    """``import devlearn`` asks Mesa's llvmpipe (EGL without a GPU) for no rasteriser threads
    unless the user chose a number; the eye images are the same bytes either way."""
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k not in ("LP_NUM_THREADS", "MUJOCO_GL")}
    outputs = []
    for threads in (None, "2"):
        run_env = env if threads is None else {**env, "LP_NUM_THREADS": threads}
        done = subprocess.run(
            [sys.executable, "-c", _RENDER_SCRIPT], env=run_env, capture_output=True, text=True
        )
        assert done.returncode == 0, done.stderr[-2000:]
        outputs.append(done.stdout.split())
    (default_threads, default_images), (chosen_threads, chosen_images) = outputs
    assert default_threads == "0" and chosen_threads == "2"
    assert default_images == chosen_images
