"""Where a run's hand detector comes from: calibrated by babbling, stored in a policy file, or
found beside a checkpoint whose config names a path from another machine."""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path
from typing import Any

from devlearn.errors import UsageError
from devlearn_hand_regard.config import HandRegardConfig
from devlearn_hand_regard.detector import FORMAT_VERSION, DetectorParams

HELD_OUT_STEPS = 1000
"""Fresh babbling steps (seed ``babbling_seed + 1``) on which a run's calibration is scored
against the renderer's segmentation (``calibration["held_out"]`` in the detector file)."""


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

    from devlearn.infant import build_infant
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
        )
        if progress:
            print("babbling done; calibrating the hand detector", file=sys.stderr, flush=True)
        params = calibrate(data, threshold=cfg.correlation_threshold)
        del data
        if held_out_steps >= 2:
            test, segmentation = held_out(
                infant,
                held_out_steps,
                cfg.babbling_seed + 1,
                start=cfg.start,
                hold_steps=cfg.babbling_hold_steps,
            )
            result = score(HandDetector(params), test, segmentation)
            params.calibration["held_out"] = {
                "steps": held_out_steps,
                "seed": cfg.babbling_seed + 1,
                "truth": "pixels: at least 20 of the hand's pixels (precision_pixels, "
                "recall_pixels); any pixel (precision, recall)",
                "pairs": result["pairs"],
                "pair_mean": result["pair_mean"],
            }
            if progress:
                mean = result["pair_mean"]
                print(
                    f"hand detector on {held_out_steps} fresh babbling steps, against >= 20 "
                    f"hand pixels: precision {mean['precision_pixels']:.2f}, recall "
                    f"{mean['recall_pixels']:.2f} (mean of the 4 eye-hand pairs)",
                    file=sys.stderr,
                    flush=True,
                )
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
