"""Measure a babbling-calibrated detector against the renderer's segmentation.

``python -m devlearn_hand_regard.measure`` babbles (default 10,000 steps, seed 0) on the
infant of ``--appearance`` (mittens or skin) in ``--scene`` (default ``sitting_babybench``),
calibrates, then records test frames (seed 1): ``--test-episodes`` episodes of
``--test-episode-steps`` steps of the same held random babbling actions, each from ``--start``
(default ``babybench``, the training start; ``random``: random joints and toys), with the
segmentation. It prints JSON: per (eye, hand) pair the per-frame precision, recall and
accuracy of the detections (truth: any pixel of that hand), recall on clearly visible hands
(at least 20 pixels), per hand the pixel precision and recall of its mask, and which labels
the detected pixels carry (hand, other body, scene/toys, background). The segmentation is
used here only, never by the detector.

The detector tells the hands apart as ``--attribution`` says (default ``visibility``, issue
#39: learned after calibration from more one-arm babbling, seed + 2; a ``--detector`` file
without it learns it, babbling again as calibration did): ``score`` is that rule's,
``score_position`` the same detector attributing by position (the rule before issue #39) on
the same frames.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from devlearn import write_atomically, write_text_atomically
from devlearn_hand_regard.calibration import calibrate
from devlearn_hand_regard.config import HandRegardConfig
from devlearn_hand_regard.detector import ATTRIBUTIONS, DetectorParams, HandDetector
from devlearn_hand_regard.detector_store import calibration_babbling, learn_side_attribution
from devlearn_hand_regard.segmentation_score import held_out, score

if TYPE_CHECKING:
    from devlearn_hand_regard.babbling import BabblingData


def detection_picture(
    detector: HandDetector,
    data: BabblingData,
    segmentation: np.ndarray,
    path: str | Path,
    frames: int = 6,
    scale: int = 2,
) -> Path:
    """Draw ``frames`` left-eye test frames that show a hand, spread over the recording.

    Top row: the eye image; bottom row: the same with the detected left hand tinted green,
    the detected right hand blue and the true hands' pixels (segmentation) outlined red.
    """
    import cv2

    shown = np.flatnonzero(np.isin(segmentation[:, 0], (1, 2)).sum(axis=(1, 2)) >= 20)
    pick = shown[np.linspace(0, len(shown) - 1, min(frames, len(shown))).astype(int)]
    top, bottom = [], []
    for t in pick:
        image = data.eyes[t, 0]
        _, masks = detector.detect(data.eyes[t], data.proprioception[t])
        tinted = image.astype(np.float32)
        for hand, colour in ((0, (0, 220, 0)), (1, (0, 80, 255))):
            tinted[masks[0, hand]] = 0.4 * tinted[masks[0, hand]] + 0.6 * np.array(colour)
        big = cv2.resize(tinted.astype(np.uint8), None, fx=scale, fy=scale, interpolation=0)
        truth: np.ndarray = np.isin(segmentation[t, 0], (1, 2)).astype(np.uint8)
        truth = cv2.resize(truth, None, fx=scale, fy=scale, interpolation=0)
        contours, _ = cv2.findContours(truth, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
        cv2.drawContours(big, contours, -1, (255, 0, 0), 1)
        top.append(cv2.resize(image, None, fx=scale, fy=scale, interpolation=0))
        bottom.append(big)
    picture = np.concatenate([np.concatenate(top, 1), np.concatenate(bottom, 1)], 0)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    ok, encoded = cv2.imencode(path.suffix or ".png", cv2.cvtColor(picture, cv2.COLOR_RGB2BGR))
    if not ok:
        raise ValueError(f"OpenCV cannot write a '{path.suffix}' picture")
    write_atomically(path, lambda f: f.write(encoded.tobytes()))
    return path


def main(argv: list[str] | None = None) -> dict:
    """Command line: see the module docstring and ``--help``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--babbling-steps", type=int, default=10_000)
    parser.add_argument("--seed", type=int, default=0, help="babbling seed of the calibration")
    parser.add_argument(
        "--appearance",
        default="mittens",
        help="infant appearance: two_colour_mittens, mittens or skin",
    )
    parser.add_argument("--test-episodes", type=int, default=4, help="test episodes")
    parser.add_argument("--test-episode-steps", type=int, default=500, help="steps per episode")
    parser.add_argument("--test-seed", type=int, default=1)
    parser.add_argument(
        "--scene", default="sitting_babybench", help="sitting_babybench (default) or sitting"
    )
    parser.add_argument(
        "--start",
        default="babybench",
        choices=("babybench", "rest", "random"),
        help="how babbling and test episodes start (default babybench)",
    )
    parser.add_argument("--hold-steps", type=int, default=25, help="babbling action hold")
    parser.add_argument(
        "--arms",
        default="alternate",
        choices=("alternate", "both"),
        help="calibration babbling: one arm per episode (default) or both arms",
    )
    parser.add_argument(
        "--attribution",
        default="visibility",
        choices=ATTRIBUTIONS,
        help="how the detector tells the hands apart (default visibility, issue #39)",
    )
    parser.add_argument(
        "--attribution-share",
        type=float,
        default=HandRegardConfig.attribution_babbling_share,
        help="one-arm babbling for the visibility attribution, share of --babbling-steps",
    )
    parser.add_argument("--detector", help="score this detector JSON instead of calibrating")
    parser.add_argument("--save", help="write the calibrated detector JSON here")
    parser.add_argument("--out", help="write the JSON result here too")
    parser.add_argument("--picture", help="draw test frames with detections and truth (PNG)")
    args = parser.parse_args(argv)
    from devlearn import build_infant

    infant = build_infant(args.scene, senses=("proprioception", "eyes"), appearance=args.appearance)
    result: dict = {
        "appearance": args.appearance,
        "scene": args.scene,
        "hold_steps": args.hold_steps,
        "arms": args.arms,
        "attribution": args.attribution,
        "argv": list(sys.argv[1:] if argv is None else argv),
        "test_frames": {
            "episodes": args.test_episodes,
            "episode_steps": args.test_episode_steps,
            "start": args.start,
            "seed": args.test_seed,
        },
    }
    cfg = HandRegardConfig(
        scene=args.scene,
        appearance=args.appearance,
        start="rest" if args.start == "random" else args.start,
        babbling_steps=args.babbling_steps,
        babbling_seed=args.seed,
        babbling_hold_steps=args.hold_steps,
        babbling_arms=args.arms,
        hand_attribution=args.attribution,
        attribution_babbling_share=args.attribution_share,
    )
    try:
        start = time.perf_counter()
        data = None
        if args.detector:
            params = DetectorParams.load(args.detector)
        else:
            data = calibration_babbling(cfg, infant, progress=True)
            result["babbling_s"] = round(time.perf_counter() - start, 1)
            start = time.perf_counter()
            params = calibrate(data, per_hand_colours=args.arms == "alternate")
            result["calibration_s"] = round(time.perf_counter() - start, 1)
        if args.attribution == "visibility" and not params.visibility_model:
            start = time.perf_counter()
            learn_side_attribution(params, cfg, infant, data, progress=True)
            result["side_attribution_s"] = round(time.perf_counter() - start, 1)
        del data
        if args.save:
            path = params.save(args.save)
            result["detector_bytes"] = path.stat().st_size
        result["calibration"] = params.calibration
        result["hsv_ranges"] = params.hsv_ranges
        result["area"] = [
            round(params.min_area),
            round(params.expected_area),
            round(params.max_area),
        ]
        test, segmentation = held_out(
            infant,
            args.test_episodes * args.test_episode_steps,
            args.test_seed,
            episode_steps=args.test_episode_steps,
            random_pose=args.start == "random",
            start="rest" if args.start == "random" else args.start,
            hold_steps=args.hold_steps,
        )
        detector = HandDetector(params, attribution=args.attribution)
        start = time.perf_counter()
        result["score"] = score(detector, test, segmentation)
        result["detect_ms_per_step"] = round(1000 * (time.perf_counter() - start) / len(test), 2)
        if args.attribution != "position":
            result["score_position"] = score(HandDetector(params), test, segmentation)
        means_only = score(HandDetector(params), test, segmentation, posture=False)
        result["score_mean_positions"] = {k: means_only[k] for k in ("pairs", "pair_mean")}
        if args.picture:
            detection_picture(detector, test, segmentation, args.picture)
    finally:
        infant.close()
    text = json.dumps(result, indent=1)
    print(text)
    if args.out:
        write_text_atomically(Path(args.out), text + "\n")
    return result


if __name__ == "__main__":
    main()
