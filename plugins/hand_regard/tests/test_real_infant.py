"""Real renders: babbling calibration against the segmentation, and a tiny training run."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

try:
    from devlearn import build_infant
except ImportError:  # the body is built in parallel; until it lands these tests skip
    build_infant = None

from devlearn_hand_regard.babbling import babble
from devlearn_hand_regard.calibration import calibrate
from devlearn_hand_regard.detector import HandDetector
from devlearn_hand_regard.segmentation_score import LABELS, held_out, score

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(build_infant is None, reason="devlearn.infant has not landed"),
]
CALIBRATION_STEPS = 1500
"""The paper babbles 10,000 steps; 1,500 keep this test ~30 s. Measured with these seeds
(README, calibration table): hue box 136..140, 300 held-out steps: detected pixels 99.9% hand,
0.1% scene; any hand in an eye precision 1.0, recall 0.92; pair-averaged precision 0.90,
recall 0.88. (1,000 steps is too short: a skin-coloured box joins the mitten's.)"""
HELD_OUT_STEPS = 300


@pytest.fixture(scope="module")
def real():
    """A calibration from real babbling, and its score on fresh babbling (segmentation)."""
    # The scene and babbling of runs before issue #29 (head free, hands raised at rest, actions
    # held 8 steps), where these figures were measured; BabyBench's scene: the README's table.
    with build_infant("sitting", senses=("proprioception", "eyes")) as infant:
        params = calibrate(babble(CALIBRATION_STEPS, seed=0, infant=infant, start="rest"))
        data, segmentation = held_out(infant, HELD_OUT_STEPS, seed=1, start="rest", hold_steps=8)
        yield params, score(HandDetector(params), data, segmentation)


def test_babbling_finds_arm_correlated_tracks(real):
    params = real[0]
    report = params.calibration
    assert report["hand_tracks"] >= 5 and min(report["rho_hand_tracks"]) > 0.6
    # since issue #29 the posture model is kept only if it predicts hand tracks of babbling
    # episodes it was not fitted on (within a quarter of the image); 1,500 steps may not pass
    model = params.position_model
    assert not model or model["validation_error_px"] <= 0.25 * params.image_size[1]


def test_no_toy_colour_is_hand_coloured(real):
    from devlearn.testing import TOY_COLOURS

    detector = HandDetector(real[0])
    for rgba in TOY_COLOURS:  # flat, shaded and lit toy faces
        for light in (0.5, 0.75, 1.0):
            patch = np.full((4, 4, 3), np.array(rgba[:3]) * 255 * light, np.uint8)
            assert not detector.colour_mask(patch).any(), (rgba, light)


def test_detector_agrees_with_the_segmentation(real):
    result = real[1]
    pixels = result["pixels"]
    assert set(pixels) == set(LABELS)
    # Detected pixels are the hands (measured 0.999), never the toys or the floor.
    assert pixels["left_hand"] + pixels["right_hand"] > 0.9
    assert pixels["scene"] < 0.02 and pixels["background"] < 0.02
    # Any hand in an eye (measured precision 1.0, recall 0.92).
    assert result["any_hand"]["precision"] > 0.9 and result["any_hand"]["recall"] > 0.75
    # Which hand (posture model; measured pair-averaged precision 0.90, recall 0.88).
    assert result["pair_mean"]["precision"] > 0.7 and result["pair_mean"]["recall"] > 0.65


def short_infant(scene, **kwargs):
    """The real infant with 200-step episodes (the eval below runs one whole episode)."""
    infant = build_infant(scene, **kwargs)
    infant.episode_steps = 200
    return infant


def test_tiny_training_run_and_eval(tmp_path, real):
    from devlearn.testing import PluginRegistry, evaluate_policy

    out = tmp_path / "run"
    out.mkdir()
    real[0].save(out / "hand_detector.json")  # prepare() reuses it: no 10,000-step babbling
    # Two PPO iterations of 2 envs x 16 steps: one per one-arm stage.
    cmd = [
        sys.executable,
        "-m",
        "devlearn.cli",
        "run",
        "hand_regard",
        "--steps",
        "64",
        "--envs",
        "2",
        "--workers",
        "0",
        "--seed",
        "1",
        "--out",
        str(out),
        "--set",
        "ppo.num_steps_per_env=16",
        "--set",
        "env.action_repeat=1",  # a decision every physics step: stages of 32 and 16 steps
        "--set",
        "behavior.left_arm_steps=32",
        "--set",
        "behavior.right_arm_steps=16",
    ]
    subprocess.run(cmd, check=True, timeout=600)
    rows = [json.loads(line) for line in (out / "metrics.jsonl").read_text().splitlines()]
    # Episodes last 1,000 steps, so none ends here (per-term sums appear at episode ends).
    assert rows[-1]["step"] >= 64 and np.isfinite(rows[-1]["mean_step_reward"])
    assert [r["stage"] for r in rows] == ["left_arm", "right_arm"]
    config = json.loads((out / "config.json").read_text())
    assert config["behavior"]["detector_file"].endswith("hand_detector.json")
    # `devlearn eval`'s code path in process, on one short (200-step) episode.
    evaluation = tmp_path / "eval"
    video = evaluation / "episode.mp4"
    summary = evaluate_policy(
        "hand_regard",
        out / "checkpoint_latest.pt",
        1,
        PluginRegistry(),
        out_dir=evaluation,
        infant_factory=short_infant,
        video=video,
    )
    assert json.loads((evaluation / "eval.json").read_text())["steps"] == 200
    assert summary["episodes"] == 1 and summary["steps"] == 200
    assert set(summary["visibility"]) == {
        "left_eye_left_hand",
        "right_eye_left_hand",
        "left_eye_right_hand",
        "right_eye_right_hand",
    }
    assert 0.0 <= summary["average"] <= 1.0 and "detector_agreement" in summary
    assert set(summary["detector_pixels"]) == {"left_hand", "right_hand"}  # pixel agreement
    assert (evaluation / "hand_regard_visibility.png").stat().st_size > 0
    import imageio.v2 as imageio

    frame = imageio.get_reader(video).get_data(0)  # left eye | right eye | third person
    assert frame.shape == (256, 896, 3) and frame[:, :512].std() > 5
