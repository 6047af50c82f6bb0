"""The core's run-wide memory of batched reward terms: merged across workers and ranks."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import numpy as np
import torch
from tiny_behaviors import NoveltyBehavior, StepNovelty

from devlearn.env import DevVecEnv
from devlearn.testing.fake_infant import fake_infant_factory

STEPS = 10  # the fake infant's episode


@contextlib.contextmanager
def novelty_envs(workers: int = 0) -> Iterator[DevVecEnv]:
    """Two envs of the novelty behaviour on fake infants (over ``workers`` processes), closed
    after the block."""
    vec = DevVecEnv(
        NoveltyBehavior(), 2, seed=0, workers=workers, infant_factory=fake_infant_factory
    )
    try:
        yield vec
    finally:
        vec.close()


def episode(vec: DevVecEnv) -> list[float]:
    """Step one episode; return each env's ``reward/step_novelty`` sum, in env order."""
    infos = []
    for _ in range(STEPS):
        infos += vec.step(torch.zeros(vec.num_envs, 3))[3]["episode_infos"]
    return [info["reward/step_novelty"] for info in infos]


def test_default_merge_ors_flags_and_keeps_the_largest_count():
    copies = [
        {"seen": np.array([True, False, False]), "widest": np.array([2])},
        {"seen": np.array([False, False, True]), "widest": np.array([5])},
    ]
    merged = StepNovelty().merge_run_memory(copies)
    assert merged["seen"].tolist() == [True, False, True] and merged["widest"].tolist() == [5]


def test_one_batch_pays_each_discovery_once():
    with novelty_envs() as vec:
        assert episode(vec) == [10.0, 0.0]  # the first env in batch order
        assert episode(vec) == [0.0, 0.0]


def test_workers_pay_once_each_until_the_merge_then_never_again():
    with novelty_envs(2) as vec:
        assert episode(vec) == [10.0, 10.0]  # one env per worker: each its own discovery
        vec.sync_run_memory()
        states = vec.state_dict()["envs"]
        assert [s["terms"]["step_novelty"]["widest"].tolist() for s in states] == [[1], [1]]
        # a third run memory, as another torchrun rank would hold it, merged through gather
        other = {"step_novelty": {"seen": np.zeros(STEPS, bool), "widest": np.array([7])}}
        vec.sync_run_memory(gather=lambda mine: [mine, other])
        for state in vec.state_dict()["envs"]:
            assert state["terms"]["step_novelty"]["seen"].all()
            assert state["terms"]["step_novelty"]["widest"].tolist() == [7]
        assert episode(vec) == [0.0, 0.0]


def test_memory_loads_merged_into_another_worker_count():
    with novelty_envs(2) as pooled:
        episode(pooled)  # not merged: each worker's copy has widest 1
        state = pooled.state_dict()
    state["envs"][1]["terms"]["step_novelty"]["widest"] = np.array([3])
    with novelty_envs() as local:
        local.load_state_dict(state)
        widest = [s["terms"]["step_novelty"]["widest"].tolist() for s in local.state_dict()["envs"]]
        assert widest == [[3], [3]]  # env 0 replaced, env 1 merged in: one memory
