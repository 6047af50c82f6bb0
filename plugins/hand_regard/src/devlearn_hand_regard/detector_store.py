"""Where a run's hand detector comes from: calibrated by babbling, stored in a policy file, or
found beside a checkpoint whose config names a path from another machine."""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path
from typing import Any

from devlearn import UsageError
from devlearn_hand_regard.config import HandRegardConfig
from devlearn_hand_regard.detector import FORMAT_VERSION, DetectorParams

HELD_OUT_STEPS = 2000
"""Fresh babbling steps (seed ``babbling_seed + 1``, episodes of :data:`HELD_OUT_EPISODE`) on
which a run's calibration is scored against the renderer's segmentation
(``calibration["held_out"]`` in the detector file). In BabyBench's scene the hands are in view
in only a few percent of babbling frames, and one 1,000-step episode (seed 1) showed none."""
HELD_OUT_EPISODE = 500
"""Steps per held-out babbling episode."""


def calibrate_by_babbling(
    cfg: HandRegardConfig, progress: bool = True, held_out_steps: int = HELD_OUT_STEPS
) -> DetectorParams:
    """Babble (``cfg.babbling_*``, in ``cfg.scene`` from ``cfg.start``) and calibrate the
    detector (``cfg.correlation_threshold``); ``progress`` prints a line every few seconds.

    Then score the detector on ``held_out_steps`` of fresh babbling against the segmentation
    (never seen by the detector): per (eye, hand) pair its precision and recall (truth: at
    least 20 of the hand's pixels, eval's ``pixels``; and any pixel), stored in
    ``params.calibration["held_out"]`` and printed when ``progress``.
    """
    import sys

    from devlearn import build_infant
    from devlearn_hand_regard.babbling import babble
    from devlearn_hand_regard.calibration import calibrate
    from devlearn_hand_regard.detector import HandDetector
    from devlearn_hand_regard.measure import held_out, score

    infant = build_infant(cfg.scene, senses=("proprioception", "eyes"), appearance=cfg.appearance)
    try:
        data = babble(
            cfg.babbling_steps,
            seed=cfg.babbling_seed,
            hold_steps=cfg.babbling_hold_steps,
            head_hold_steps=cfg.babbling_head_hold_steps,
            head_scale=cfg.babbling_head_scale,
            infant=infant,
            start=cfg.start,
            progress=progress,
            arms=cfg.babbling_arms,
        )
        if progress:
            print("babbling done; calibrating the hand detector", file=sys.stderr, flush=True)
        params = calibrate(
            data,
            threshold=cfg.correlation_threshold,
            per_hand_colours=cfg.babbling_arms == "alternate",
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
            result = score(HandDetector(params), test, segmentation)
            params.calibration["held_out"] = {
                "steps": held_out_steps,
                "episode_steps": HELD_OUT_EPISODE,
                "seed": cfg.babbling_seed + 1,
                "truth": "pixels: at least 20 of the hand's pixels (precision_pixels, "
                "recall_pixels); any pixel (precision, recall)",
                "pairs": result["pairs"],
                "pair_mean": result["pair_mean"],
            }
            if progress:
                print(_held_out_line(result, held_out_steps), file=sys.stderr, flush=True)
    finally:
        infant.close()
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
