"""Where a run's hand detector comes from: calibrated by babbling (its colour, then which hand
is which), stored in a policy file, or found beside a checkpoint whose config names a path
from another machine."""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from devlearn import UsageError
from devlearn_hand_regard.config import HandRegardConfig
from devlearn_hand_regard.detector import FORMAT_VERSION, DetectorParams

if TYPE_CHECKING:
    from devlearn import Infant
    from devlearn_hand_regard.babbling import BabblingData

HELD_OUT_STEPS = 2000
"""Fresh babbling steps (seed ``babbling_seed + 1``, episodes of :data:`HELD_OUT_EPISODE`) on
which a run's calibration is scored against the renderer's segmentation
(``calibration["held_out"]`` in the detector file). In BabyBench's scene the hands are in view
in only a few percent of babbling frames, and one 1,000-step episode (seed 1) showed none."""
HELD_OUT_EPISODE = 500
"""Steps per held-out babbling episode."""
ATTRIBUTION_SEED_OFFSET = 2
"""The side attribution's extra babbling starts at seed ``babbling_seed + 2`` (``+ 1`` is the
held-out check's)."""
ATTRIBUTION_CHUNK = 10_000
"""The side attribution's extra babbling runs in recordings of this many steps (chunk ``i``
seeded ``babbling_seed + 2 + i``); only the posture and whether a hand was seen are kept of
each, so memory stays that of one 10,000-step recording (~250 MB of eye images)."""


def calibrate_by_babbling(
    cfg: HandRegardConfig, progress: bool = True, held_out_steps: int = HELD_OUT_STEPS
) -> DetectorParams:
    """Babble (``cfg.babbling_*``, in ``cfg.scene`` from ``cfg.start``) and calibrate the
    detector (``cfg.correlation_threshold``); ``progress`` prints a line every few seconds.
    With ``cfg.hand_attribution`` ``visibility``, learn the side attribution too
    (:func:`learn_side_attribution`, from this recording and more one-arm babbling).

    Then score the detector on ``held_out_steps`` of fresh babbling against the segmentation
    (never seen by the detector): per (eye, hand) pair its precision and recall (truth: at
    least 20 of the hand's pixels, eval's ``pixels``; and any pixel), stored in
    ``params.calibration["held_out"]`` and printed when ``progress``.
    """
    import sys

    from devlearn import build_infant
    from devlearn_hand_regard.calibration import calibrate
    from devlearn_hand_regard.detector import HandDetector
    from devlearn_hand_regard.segmentation_score import held_out, score

    infant = build_infant(cfg.scene, senses=("proprioception", "eyes"), appearance=cfg.appearance)
    try:
        data = calibration_babbling(cfg, infant, progress)
        if progress:
            print("babbling done; calibrating the hand detector", file=sys.stderr, flush=True)
        params = calibrate(
            data,
            threshold=cfg.correlation_threshold,
            per_hand_colours=cfg.babbling_arms == "alternate",
        )
        if cfg.hand_attribution == "visibility":
            learn_side_attribution(params, cfg, infant, data, progress)
        if cfg.hand_attribution == "contingency":  # issue #58: from this babbling
            params.contingency_model = fit_from_calibration(
                params, infant, data, other_arm_hangs=cfg.babbling_arms == "alternate"
            )
        del data
        if held_out_steps >= 2:
            test, segmentation = held_out(
                infant,
                held_out_steps,
                cfg.babbling_seed + 1,
                episode_steps=HELD_OUT_EPISODE,
                start=cfg.start,
                hold_steps=cfg.babbling_hold_steps,
            )
            detector = HandDetector(
                params, attribution=cfg.hand_attribution, pair_blobs=cfg.contingency_pairs
            )
            result = score(detector, test, segmentation)
            params.calibration["held_out"] = {
                "steps": held_out_steps,
                "episode_steps": HELD_OUT_EPISODE,
                "seed": cfg.babbling_seed + 1,
                "truth": "pixels: at least 20 of the hand's pixels (precision_pixels, "
                "recall_pixels); any pixel (precision, recall)",
                "attribution": cfg.hand_attribution,
                "pairs": result["pairs"],
                "pair_mean": result["pair_mean"],
            }
            if progress:
                print(_held_out_line(result, held_out_steps), file=sys.stderr, flush=True)
    finally:
        infant.close()
    return params


def calibration_babbling(
    cfg: HandRegardConfig,
    infant: Infant,
    progress: bool = False,
    steps: int | None = None,
    seed: int | None = None,
    arms: str | None = None,
) -> BabblingData:
    """The motor babbling that calibration records (``cfg.babbling_*``, from ``cfg.start``):
    the same frames for the same config (seeded). ``steps``, ``seed`` and ``arms`` replace the
    config's for more babbling of the same kind (:func:`learn_side_attribution`)."""
    from devlearn_hand_regard.babbling import babble

    return babble(
        cfg.babbling_steps if steps is None else steps,
        seed=cfg.babbling_seed if seed is None else seed,
        hold_steps=cfg.babbling_hold_steps,
        head_hold_steps=cfg.babbling_head_hold_steps,
        head_scale=cfg.babbling_head_scale,
        infant=infant,
        start=cfg.start,
        progress=progress,
        arms=cfg.babbling_arms if arms is None else arms,
    )


def learn_side_attribution(
    params: DetectorParams,
    cfg: HandRegardConfig,
    infant: Infant,
    recording: BabblingData | None = None,
    progress: bool = False,
) -> DetectorParams:
    """Learn each hand's visibility from its arm's posture (``params.visibility_model``, the
    ``visibility`` attribution, :mod:`devlearn_hand_regard.attribution`), in place.

    The frames: the calibration's recording (``recording``; None: babbled again, seeded as
    calibration babbles, for a detector file calibrated under ``cfg``), when it babbled one
    arm at a time, and ``cfg.attribution_babbling_share`` x ``cfg.babbling_steps`` more
    steps of one-arm babbling (:data:`ATTRIBUTION_CHUNK` steps per seed, from
    ``babbling_seed + 2``). Labels: whether the calibrated
    colour detector finds a hand blob in each eye, and which arm moved. No segmentation is
    read. When babbling saw too little of a hand the model stays empty (the detector then
    attributes by position, with a warning) and ``params.calibration["side_attribution"]``
    says so.
    """
    import sys

    from devlearn_hand_regard.attribution import fit_visibility_model, visibility_labels
    from devlearn_hand_regard.detector import HandDetector

    colour = HandDetector(params)  # blobs only: their colour says "a hand"

    def seen(data: BabblingData) -> np.ndarray:
        return np.array([[bool(colour.blobs(eye)) for eye in frame] for frame in data.eyes])

    recordings = []
    if cfg.babbling_arms == "alternate":
        if recording is None:
            recording = calibration_babbling(cfg, infant, progress)
        recordings.append((recording, seen(recording)))
    steps = round(cfg.attribution_babbling_share * cfg.babbling_steps)
    if progress and steps >= 2:
        print(
            f"babbling {steps:,} more steps, one arm at a time, to learn which hand is which",
            file=sys.stderr,
            flush=True,
        )
    for chunk, start in enumerate(range(0, steps if steps >= 2 else 0, ATTRIBUTION_CHUNK)):
        extra = calibration_babbling(
            cfg,
            infant,
            progress,
            steps=max(min(ATTRIBUTION_CHUNK, steps - start), 2),
            seed=cfg.babbling_seed + ATTRIBUTION_SEED_OFFSET + chunk,
            arms="alternate",
        )
        hands_seen = seen(extra)
        extra.eyes = np.zeros((len(extra), 0), np.uint8)  # keep the posture, free the images
        recordings.append((extra, hands_seen))
    params.visibility_model = fit_visibility_model(recordings)
    model = params.visibility_model
    params.calibration["side_attribution"] = {
        "rule": "visibility" if model else "position (too few hand frames to learn from)",
        "babbling_steps": [len(data) for data, _ in recordings],
        "seen_frames": [  # per hand: frames where its arm babbled alone and a hand was seen
            sum(
                int(visibility_labels(d, s)[0][:, :, hand].any(axis=1).sum()) for d, s in recordings
            )
            for hand in range(2)
        ],
    }
    if progress:
        print(
            "which hand is which: learned from each arm's posture"
            if model
            else "which hand is which: too few hand frames; by position",
            file=sys.stderr,
            flush=True,
        )
    return params


def as_artifact(params: DetectorParams) -> dict[str, Any]:
    """The detector's parameters as a policy file stores them (plain lists, no tuples)."""
    return json.loads(json.dumps({"format_version": FORMAT_VERSION, **asdict(params)}))


def find_file(name: str, folder: Path) -> Path:
    """The detector file a checkpoint's config names: at ``name`` (relative: in ``folder``),
    else by its file name in ``folder`` or the folder above it (a relocated run folder).

    Raises:
        UsageError: None of those exists.
    """
    given = Path(name)
    candidates = [given] if given.is_absolute() else [folder / given]
    candidates += [folder / given.name, folder.parent / given.name]
    for path in candidates:
        if path.is_file():
            return path
    raise UsageError(
        f"hand_regard: the checkpoint's detector file {name} is missing, and no "
        f"{given.name} is in {folder} or {folder.parent}; put it beside the checkpoint "
        "or make a self-contained policy file with `devlearn slim`"
    )


def _held_out_line(result: dict, steps: int) -> str:
    """One line on the held-out score (``measure.score``'s result)."""
    mean = result["pair_mean"]
    shown = [
        f"{name} {mean[key]:.2f}" if mean[key] is not None else f"{name} n/a"
        for name, key in (("precision", "precision_pixels"), ("recall", "recall_pixels"))
    ]
    in_view = max(p["in_view"] for p in result["pairs"].values())
    return (
        f"hand detector on {steps:,} fresh babbling steps, against >= 20 hand pixels: "
        f"{', '.join(shown)} (mean over the eye-hand pairs; a hand in view in at most "
        f"{100 * in_view:.1f}% of frames per pair)"
    )


def fit_from_calibration(
    params: Any, infant: Any, data: Any, other_arm_hangs: bool
) -> dict[str, Any]:
    """A fresh run's contingency model, from its own calibration babbling (issue #58: a run
    with ``hand_attribution=contingency`` and no detector file fits it after babbling).

    Args:
        params: The calibrated :class:`~devlearn_hand_regard.detector.DetectorParams`
            (its colour step finds the blobs).
        infant: The infant that babbled (its model gives the body schema).
        data: Its :class:`~devlearn_hand_regard.babbling.BabblingData`.
        other_arm_hangs: The babbling moved one arm at a time, the other limp.
    Returns:
        :func:`fit_contingency_model`'s dict.
    Raises:
        ValueError: Too few labelled blobs (the message says to babble longer).
    """
    from devlearn_hand_regard.babbling import posture_joints
    from devlearn_hand_regard.blob_table import tabulate
    from devlearn_hand_regard.contingency import fit_contingency_model
    from devlearn_hand_regard.contingency_body import body_schema
    from devlearn_hand_regard.detector import HandDetector

    names = list(infant.actuator_names)
    table = tabulate(
        HandDetector(params),
        data.eyes,
        data.proprioception,
        data.episode,
        moving_arm=data.moving_arm,
        other_arm_hangs=other_arm_hangs,
    )
    joints = posture_joints(names, infant.actuator_groups)
    return fit_contingency_model(
        [table], joints, body_schema(infant.model, names, int(data.eyes.shape[3]))
    )
