"""Sweeps: a grid of config values times seeds, each run trained and evaluated, then reported.

``devlearn sweep BEHAVIOR`` (devlearn/cli/sweep.py) builds a :class:`SweepSpec` from its options
and an optional TOML sweep file (:func:`build_spec`) and calls :func:`run_sweep`. Runs execute
on this machine or as Ray tasks (:mod:`devlearn.sweep.executors`); each run is ``devlearn run``
then ``devlearn eval`` in subprocesses (:mod:`devlearn.sweep.job`).
"""

from __future__ import annotations

from devlearn.sweep.experiment import plan_sweep, run_sweep, write_sweep_report
from devlearn.sweep.spec import EvalSpec, SweepSpec, TrainSpec, Variant, variants
from devlearn.sweep.sweep_file import build_spec, read_sweep_file

__all__ = [
    "EvalSpec",
    "SweepSpec",
    "TrainSpec",
    "Variant",
    "build_spec",
    "plan_sweep",
    "read_sweep_file",
    "run_sweep",
    "variants",
    "write_sweep_report",
]
