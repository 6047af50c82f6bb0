"""The CPU cores this process may run on: the one answer every part that sizes its work by
cores asks (training's workers and threads, the evaluation's workers, a sweep's pinning).
Imports nothing of devlearn, so any layer may use it."""

from __future__ import annotations

import os


def available_cores() -> list[int]:
    """The ids of the CPU cores this process may run on, sorted: its affinity mask where the
    operating system has one (Linux; ``taskset`` and a sweep's pinning narrow it), else every
    core of the machine. Their number is ``len(available_cores())``."""
    if hasattr(os, "sched_getaffinity"):
        return sorted(os.sched_getaffinity(0))
    return list(range(os.cpu_count() or 1))
