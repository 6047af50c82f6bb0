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


def calibrate_by_babbling(cfg: HandRegardConfig, progress: bool = True) -> DetectorParams:
    """Babble (``cfg.babbling_*``, in ``cfg.scene`` from ``cfg.start``) and calibrate the
    detector (``cfg.correlation_threshold``); ``progress`` prints a line every few seconds."""
    from devlearn_hand_regard.babbling import babble
    from devlearn_hand_regard.calibration import calibrate

    data = babble(
        cfg.babbling_steps,
        appearance=cfg.appearance,
        seed=cfg.babbling_seed,
        hold_steps=cfg.babbling_hold_steps,
        head_hold_steps=cfg.babbling_head_hold_steps,
        head_scale=cfg.babbling_head_scale,
        scene=cfg.scene,
        start=cfg.start,
        progress=progress,
    )
    return calibrate(data, threshold=cfg.correlation_threshold)


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
