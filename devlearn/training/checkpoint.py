"""Checkpoints: atomic writes, clear errors for missing, corrupt or foreign files."""

from __future__ import annotations

import json
import os
import re
from pathlib import Path
from typing import Any

import torch

from devlearn.errors import UsageError

FORMAT = "devlearn-checkpoint-1"
"""Value of the ``format`` key every devlearn checkpoint holds."""
LATEST = "checkpoint_latest.pt"
"""Name of the newest checkpoint in a run directory."""
_PERIODIC = re.compile(r"^checkpoint_(\d+)\.pt$")


def _fsync_dir(directory: Path) -> None:
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def save_atomic(state: dict[str, Any], path: Path) -> None:
    """Write ``state`` with torch.save to a temporary file, fsync it, then rename over ``path``.

    A crash (even kill -9) at any moment leaves either the previous file or the new one, never
    a partial file under ``path``.
    """
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    try:
        with open(tmp, "wb") as f:
            torch.save(state, f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    _fsync_dir(path.parent)


def link_atomic(source: Path, path: Path) -> None:
    """Make ``path`` a hard link to ``source`` atomically (a copy where links are unsupported)."""
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    try:
        os.link(source, tmp)
        os.replace(tmp, path)
    except OSError:
        if tmp.exists():
            tmp.unlink()
        save_atomic(torch.load(source, weights_only=False), path)
    _fsync_dir(path.parent)


def load_checkpoint(path: str | Path) -> dict[str, Any]:
    """Load a devlearn checkpoint (on the CPU).

    Raises:
        UsageError: The file is missing, truncated or unreadable, or not a devlearn checkpoint.
    """
    path = Path(path)
    if not path.is_file():
        raise UsageError(f"checkpoint {path} does not exist")
    try:
        # weights_only=False: checkpoints hold configs and reward-term state (numpy arrays).
        # Load only checkpoints you trust, as with any pickle.
        state = torch.load(path, map_location="cpu", weights_only=False)
    except Exception as exc:
        raise UsageError(
            f"checkpoint {path} is corrupt or unreadable ({type(exc).__name__})"
        ) from None
    if not isinstance(state, dict) or state.get("format") != FORMAT:
        raise UsageError(f"checkpoint {path} is not a devlearn checkpoint")
    return state


def check_behavior(state: dict[str, Any], path: str | Path, behavior_name: str) -> None:
    """Raise UsageError unless the checkpoint was trained for ``behavior_name``."""
    if state["behavior"] != behavior_name:
        raise UsageError(
            f"checkpoint {path} was trained for '{state['behavior']}', not '{behavior_name}'"
        )


def periodic_checkpoints(run_dir: Path) -> list[Path]:
    """``checkpoint_<step>.pt`` files of a run, newest (highest step) first."""
    found = [
        (int(m.group(1)), p)
        for p in run_dir.glob("checkpoint_*.pt")
        if (m := _PERIODIC.match(p.name))
    ]
    return [p for _, p in sorted(found, reverse=True)]


def resume_checkpoint(run_dir: str | Path) -> tuple[Path, dict[str, Any]]:
    """Return the newest readable checkpoint of a run: ``checkpoint_latest.pt``, or failing
    that the highest-step ``checkpoint_<step>.pt`` that loads.

    Raises:
        UsageError: No directory, or no readable checkpoint in it.
    """
    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise UsageError(f"run directory {run_dir} does not exist")
    candidates = [run_dir / LATEST] if (run_dir / LATEST).exists() else []
    candidates += periodic_checkpoints(run_dir)
    if not candidates:
        raise UsageError(f"no checkpoint in {run_dir} (expected {LATEST}); nothing to resume")
    errors = []
    for path in candidates:
        try:
            return path, load_checkpoint(path)
        except UsageError as exc:
            errors.append(str(exc))
    raise UsageError(f"no readable checkpoint in {run_dir}: {errors[0]}")


def forget_metrics_after(path: Path, step: int) -> None:
    """Drop ``metrics.jsonl`` rows past ``step`` (atomically): a killed run may have logged
    iterations after its last checkpoint, and the resumed run redoes (and logs) them again."""
    if not path.exists():
        return
    kept = []
    for line in path.read_text().splitlines():
        try:
            if json.loads(line)["step"] <= step:
                kept.append(line)
        except (ValueError, KeyError, TypeError):
            pass  # a line cut short by the kill
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text("".join(line + "\n" for line in kept))
    os.replace(tmp, path)
