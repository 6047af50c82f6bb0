"""The offline analyses of published policies (devlearn_hand_regard.analysis): the frame
recorder, the tables' figures, the gated attribution rule and the view prior's medians, each
checked by hand; one slow end-to-end run on a published policy."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest
from devlearn_hand_regard.analysis import attribution, gate, view_prior
from devlearn_hand_regard.detector import Blob, HandDetector

from devlearn import UsageError

ROOT = Path(__file__).resolve().parents[3]


class Eyes:
    """An infant whose eyes show frame i's number in every pixel at the i-th read."""

    def __init__(self) -> None:
        self.reads = 0
        self.scene = "fake"
        self.image = np.zeros((2, 4, 5, 3), np.uint8)

    def eyes(self) -> np.ndarray:
        self.reads += 1
        self.image[:] = self.reads
        return self.image  # the same array each time, as a renderer's buffer

    def proprioception(self) -> np.ndarray:
        return np.full(3, float(self.reads))

    def eyes_segmentation(self) -> np.ndarray:
        return np.full((2, 4, 5), self.reads, np.int32)


def test_the_recorder_keeps_a_copy_of_every_frame_it_passes_on():
    infant = Eyes()
    recorder = attribution.FrameRecorder(infant)
    seen = [recorder.eyes()[0, 0, 0, 0] for _ in range(3)]
    assert seen == [1, 2, 3] and recorder.scene == "fake"  # other attributes: the infant's
    data, segmentation = recorder.frames()
    assert data.eyes.shape == (3, 2, 4, 5, 3) and segmentation.shape == (3, 2, 4, 5)
    # copies: the renderer's buffer was overwritten, the recorded frames were not
    assert [int(data.eyes[t].max()) for t in range(3)] == [1, 2, 3]
    assert [int(segmentation[t].min()) for t in range(3)] == [1, 2, 3]
    assert data.proprioception[:, 0].tolist() == [1.0, 2.0, 3.0]
    assert data.actions.shape == (3, 0) and data.episode.tolist() == [0, 0, 0]


def _result(precision: list[float | None], recall: list[float | None], absent: list[float]):
    pairs = {
        name: {"precision_pixels": p, "recall_pixels": r, "credited_absent": a, "in_view": 0.5}
        for name, p, r, a in zip(attribution.PAIRS, precision, recall, absent)
    }
    return {
        "steps": 2012,
        "pair_mean": {"precision_pixels": 0.5, "recall_pixels": 0.42, "other": 1.0},
        "pairs": pairs,
        "credited_absent_max": max(absent),
        "any_hand": {"precision": 1.0},
    }


def test_a_table_row_shows_the_pair_mean_each_pair_and_the_worst_false_credit():
    result = attribution.brief(
        _result([1.0, 1.0, 0.0, None], [0.15, 0.7, None, None], [0.0, 0.956, 0.01, 0.0])
    )
    assert "other" not in result["pair_mean"] and set(result["pairs"]) == set(attribution.PAIRS)
    row = attribution.table_row("policy `i39/paper`", "position", result)
    assert row == (
        "| policy `i39/paper` | position | 2,012 | **0.50 / 0.42** | 1.00 / 0.15 | "
        "1.00 / 0.70 | 0.00 / - | - / - | 95.6% |"
    )
    assert row.count("|") == attribution.HEADER.splitlines()[0].count("|")
    assert gate.figures(_result([1.0] * 4, [0.5] * 4, [0.0, 0.12345, 0.0, 0.0])) == {
        "precision": 0.5,
        "recall": 0.42,
        "credited_absent_max": 0.1235,
    }


def _blob(x: float) -> Blob:
    mask = np.zeros((64, 64), bool)
    mask[30:34, int(x) - 2 : int(x) + 2] = True
    return Blob(centroid=(x, 32.0), area=16.0, mask=mask)


def test_the_gate_passes_a_confident_eye_to_the_visibility_rule_and_handles_the_others(
    synthetic_params,
):
    with warnings.catch_warnings():  # the synthetic calibration may lack a visibility model
        warnings.simplefilter("ignore")
        plain = HandDetector(synthetic_params, attribution="visibility")
        gated = {f: gate.GatedDetector(synthetic_params, 0.2, f) for f in gate.FALLBACKS}
    blobs = [_blob(12.0), _blob(50.0)]
    confident = np.array([0.9, 0.05])  # the left hand likely in view: above the gate
    expected = plain.attribute_by_visibility(blobs, 0, confident)
    for detector in gated.values():
        assert detector.attribute_by_visibility(blobs, 0, confident) == expected
    unsure = np.array([0.1, 0.15])  # neither hand predicted in view: below the gate
    assert gated["none"].attribute_by_visibility(blobs, 0, unsure) == [[], []]
    by_position = plain.attribute(blobs, 0, 64, None)
    assert gated["position"].attribute_by_visibility(blobs, 0, unsure) == [
        [blob] if blob is not None else [] for blob in by_position
    ]
    assert gated["none"].attribute_by_visibility([], 0, unsure) == [[], []]
    with pytest.raises(ValueError, match="unknown fallback 'both'; valid: position, none"):
        gate.GatedDetector(synthetic_params, 0.2, "both")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert len(gate.rules(synthetic_params)) == 2 + len(gate.TAUS) * len(gate.FALLBACKS)


def test_the_view_prior_medians_per_eye():
    prior = np.array(
        [  # (frames, eye, hand)
            [[0.9, 0.1], [0.2, 0.8]],
            [[0.7, 0.3], [0.4, 0.6]],
            [[0.1, 0.5], [0.6, 0.5]],
        ]
    )
    left_eye, right_eye = view_prior.prior_medians(prior)
    assert left_eye == pytest.approx(
        {"left_median": 0.7, "right_median": 0.3, "right_larger_share": 1 / 3}
    )
    assert right_eye == pytest.approx(
        {"left_median": 0.4, "right_median": 0.6, "right_larger_share": 2 / 3}
    )
    with pytest.raises(ValueError, match="expected \\(frames, 2 eyes, 2 hands\\)"):
        view_prior.prior_medians(prior[:, 0])


def test_a_policy_file_without_a_detector_is_refused():
    path = ROOT / "results" / "self_touch" / "i30" / "curriculum" / "two_stage" / "policy.pt"
    if not path.is_file():
        pytest.skip("no published policy in this checkout")
    with pytest.raises(UsageError, match="holds no hand detector; give a policy file made by"):
        attribution.policy_detector(path)


PUBLISHED = ROOT / "results" / "hand_regard" / "i39" / "reach_t4" / "policy.pt"
SIDES = ROOT / "results" / "hand_regard" / "detector" / "babybench_mittens_sides_detector.json"


@pytest.mark.slow
def test_the_attribution_command_scores_a_published_policy_on_its_own_frames(tmp_path):
    if not PUBLISHED.is_file():
        pytest.skip("no published policy in this checkout")
    assert attribution.policy_detector(PUBLISHED).visibility_model  # issue #39's detector
    argv = ["--detector", str(SIDES), "--policies", str(PUBLISHED), "--episodes", "1"]
    out = attribution.main([*argv, "--out", str(tmp_path)])
    entry = out["policies"]["i39/reach_t4"]
    assert set(entry) == {"position", "visibility", "published_pixels"}
    assert entry["visibility"]["steps"] == entry["position"]["steps"] > 0
    assert set(entry["published_pixels"]) == set(attribution.PAIRS)
    assert json.loads((tmp_path / "attribution.json").read_text())["policies"] == json.loads(
        json.dumps(out["policies"])
    )
    rows = (tmp_path / "attribution.md").read_text().splitlines()
    assert rows[0] == attribution.HEADER.splitlines()[0] and len(rows) == 4
    assert rows[2].startswith("| policy `i39/reach_t4`, 1 eval episodes | position |")
