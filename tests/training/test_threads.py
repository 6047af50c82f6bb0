"""ThreadPlan: all cores while that is faster, one thread while other programs make it slower."""

from __future__ import annotations

import os

from devlearn.env.workers import WORKER_THREADS, _worker_environment
from devlearn.training.process import ThreadPlan


def run(plan: ThreadPlan, seconds: dict[int, float], iterations: int) -> list[int]:
    """Drive the plan like the runner: choose, update (taking ``seconds[threads]``), record."""
    chosen = []
    for _ in range(iterations):
        collect, update = plan.next_iteration()
        assert collect == update
        chosen.append(update)
        plan.record(seconds[update])
    return chosen


def test_fixed_counts_are_kept():
    plan = ThreadPlan(1, 1, cores=2)
    assert run(plan, {1: 1.0}, 5) == [1] * 5
    plan = ThreadPlan(1, 2, cores=4)  # rollouts on 1, updates on 2, as configured
    assert [plan.next_iteration() for _ in range(3)] == [(1, 2)] * 3


def test_automatic_uses_all_cores_when_that_is_faster():
    plan = ThreadPlan(0, 0, cores=2, probe_every=10)
    chosen = run(plan, {2: 1.0, 1: 1.8}, 25)
    # warm-up on 2 (not timed), 2 timed, 1 timed; then 2, except one probe of 1 every 10
    assert chosen[:3] == [2, 2, 1]
    assert [i for i, c in enumerate(chosen) if c == 1] == [2, 10, 20]


def test_automatic_falls_back_to_one_thread_when_the_machine_is_busy():
    plan = ThreadPlan(0, 0, cores=2, probe_every=10)
    busy = run(plan, {2: 6.0, 1: 1.0}, 12)  # another program holds a core
    assert busy[3:10] == [1] * 7 and busy[10] == 2
    idle = run(plan, {2: 0.5, 1: 1.0}, 25)  # it finished: the next probe finds 2 faster again
    # the lost probe at 10 (6x slower) doubled the wait: the next probe is at 30, not 20
    assert idle[:18] == [1] * 18 and idle[18:] == [2] * 7


def test_probes_that_lose_badly_back_off_and_a_close_one_resets_the_wait():
    plan = ThreadPlan(0, 0, cores=2, probe_every=10)
    busy = run(plan, {2: 6.0, 1: 1.0}, 400)  # a core held throughout: each probe costs 6x
    probes = [i for i, c in enumerate(busy) if c == 2][2:]  # after the warm-up and first timing
    assert probes == [10, 30, 70, 150, 310]  # waits 20, 40, 80, 160 (the cap: 16 x 10)
    close = run(plan, {2: 1.5, 1: 1.0}, 400)  # lighter load: the probe loses, but by < 2x
    # the wait of 160 runs out at 470 (70 here); from then on every 10 again
    assert [i for i, c in enumerate(close) if c == 2] == list(range(70, 400, 10))


def test_one_core_means_one_thread():
    assert run(ThreadPlan(0, 0, cores=1), {1: 1.0}, 4) == [1] * 4


def test_workers_are_spawned_single_threaded():
    before = {key: os.environ.get(key) for key in WORKER_THREADS}
    with _worker_environment():
        assert {key: os.environ[key] for key in WORKER_THREADS} == WORKER_THREADS
    assert {key: os.environ.get(key) for key in WORKER_THREADS} == before


def test_rollouts_beside_env_workers_take_one_thread():
    """Automatic: the rollout's policy runs on one thread while env workers step (an idle
    libgomp thread would spin on their cores); the update still gets every core."""
    assert ThreadPlan(0, 0, cores=2, workers=2).next_iteration() == (1, 2)
    assert ThreadPlan(0, 0, cores=2, workers=0).next_iteration() == (2, 2)  # in-process envs
    assert ThreadPlan(2, 0, cores=2, workers=2).next_iteration() == (2, 2)  # as configured
