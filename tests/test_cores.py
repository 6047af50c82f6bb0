"""One answer to "how many cores?" (issue #59): the cores this process may run on, which
training (per rank), evaluation and the sweep all read from devlearn.cores."""

from __future__ import annotations

import os

import pytest

import devlearn.cores
from devlearn.cores import available_cores
from devlearn.evaluation import evaluate
from devlearn.training import process


def test_the_cores_are_this_processs_affinity():
    cores = available_cores()
    assert cores == sorted(cores) and len(set(cores)) == len(cores) >= 1
    if hasattr(os, "sched_getaffinity"):
        assert set(cores) == os.sched_getaffinity(0)


def test_without_an_affinity_mask_every_core_of_the_machine(monkeypatch):
    monkeypatch.delattr(os, "sched_getaffinity", raising=False)
    monkeypatch.setattr(os, "cpu_count", lambda: 3)
    assert devlearn.cores.available_cores() == [0, 1, 2]
    monkeypatch.setattr(os, "cpu_count", lambda: None)
    assert devlearn.cores.available_cores() == [0]


@pytest.mark.parametrize(("cores", "local_ranks", "per_rank"), [(8, 1, 8), (8, 2, 4), (3, 4, 1)])
def test_a_rank_gets_its_share_and_sizes_its_workers_by_it(
    monkeypatch, cores, local_ranks, per_rank
):
    monkeypatch.setattr(process, "available_cores", lambda: list(range(cores)))
    monkeypatch.setenv("LOCAL_WORLD_SIZE", str(local_ranks))
    assert process.rank_cores() == per_rank
    assert process.resolve_workers(-1, 64) == (per_rank if per_rank >= 2 else 0)


def test_an_evaluation_counts_the_same_cores(monkeypatch):
    monkeypatch.setattr(evaluate, "available_cores", lambda: list(range(4)))
    # automatic: one worker per core from PARALLEL_MIN_EPISODES episodes per core on
    enough = evaluate.PARALLEL_MIN_EPISODES * 4
    assert evaluate.parallelism(enough, None, None, merges=True) == (
        4 * evaluate.ENVS_PER_WORKER,
        4,
    )
    assert evaluate.parallelism(enough - 1, None, None, merges=True) == (1, 0)
