"""Experiments as data: a TOML file declares the arms, seeds, budget, evaluation protocols,
baselines and reference figures; one command runs it, one publishes it, one tabulates it.

``devlearn experiment run FILE OUT`` reads the file (:func:`read_experiment`), checks every
arm's config and every protocol (:func:`plan_experiment`) and runs it on the sweep's executors
and bookkeeping (:func:`run_experiment`, :mod:`devlearn.sweep`); ``publish`` keeps the
evaluations, configs, curves and one policy per arm (:func:`publish_experiment`); ``table``
prints the comparison (:func:`experiment_table`, :func:`markdown`). docs/experiments.md.
"""

from __future__ import annotations

from devlearn.experiment.plan import ExperimentPlan, describe_plan, plan_experiment
from devlearn.experiment.publish import publish_experiment
from devlearn.experiment.runner import check_experiment_folder, run_experiment
from devlearn.experiment.spec import ExperimentSpec, read_experiment
from devlearn.experiment.table import experiment_table, markdown

__all__ = [
    "ExperimentPlan",
    "ExperimentSpec",
    "check_experiment_folder",
    "describe_plan",
    "experiment_table",
    "markdown",
    "plan_experiment",
    "publish_experiment",
    "read_experiment",
    "run_experiment",
]
