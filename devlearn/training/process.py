"""Process-wide settings of a training process: the distributed group, device, torch threads,
environment workers, seeds, console."""

from __future__ import annotations

import contextlib
import io
import os
import random
import signal
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
import torch.distributed as dist

from devlearn.api.errors import UsageError
from devlearn.cores import available_cores


def init_distributed(device: str) -> None:
    """Join torchrun's process group once: gloo on the CPU, NCCL on cuda.

    On cuda the rank's GPU (``cuda:LOCAL_RANK``) is made current first, so that NCCL's
    barriers and object collectives use it rather than guessing from the global rank.
    """
    if int(os.getenv("WORLD_SIZE", "1")) > 1 and not dist.is_initialized():
        if torch.device(device).type == "cuda":
            torch.cuda.set_device(int(os.getenv("LOCAL_RANK", "0")))
            dist.init_process_group("nccl")
        else:
            dist.init_process_group("gloo")


def rank_cores() -> int:
    """The cores this rank may use: those this process may run on
    (:func:`~devlearn.cores.available_cores`), shared among torchrun's local ranks (at
    least 1)."""
    local_ranks = int(os.environ.get("LOCAL_WORLD_SIZE", "1"))
    return max(len(available_cores()) // local_ranks, 1)


PROBE_BACKOFF_RATIO = 2.0
"""A probe of the slower thread count slower than this times the faster count's time backs off."""
PROBE_BACKOFF_MAX = 16
"""The longest wait between probes, in multiples of ``probe_every``."""


class ThreadPlan:
    """How many torch threads the rollout inference and the PPO update of each iteration get.

    A fixed count (``torch_threads`` / ``update_threads`` > 0) is used as given. Automatic (0)
    means all cores this process may use (:func:`rank_cores`): the env workers wait while
    the training process runs inference or updates, so those cores are idle (on two idle
    cores a self-touch update takes ~0.19 s with 2 threads against ~0.25 s with one, with
    libgomp's default wait policy: devlearn/__init__.py). But torch's
    OpenMP threads meet at a barrier after every operation, and when another program holds one
    of the cores each of the update's thousands of operations waits for that core's next time
    slice: measured on 2 cores with other jobs running, a self_touch update took 6.2 ms per
    sample with 2 threads against 0.71 ms with one (docs/benchmarks.md). So the automatic plan
    also times the update with one thread and keeps whichever count was faster, trying the
    other again every ``probe_every`` iterations. The first update (warm-up) is not timed.
    A probe that loses by more than :data:`PROBE_BACKOFF_RATIO` (another program holds a core:
    a 2-thread update then took 1-7 s against 0.3 s, results/learners/README.md) doubles the
    wait before the next one, up to :data:`PROBE_BACKOFF_MAX` times ``probe_every``; a probe
    that does not lose by that much resets it.

    Rollouts whose envs step in worker processes get one thread when automatic: the policy's
    forward pass on one batch of observations gains little from a second thread, and after
    each of its operations libgomp's idle thread spin-waits (up to its ``GOMP_SPINCOUNT``) on a
    core that a worker is stepping on: with 2 threads the training process burnt about 0.05 s
    more CPU per self-touch rollout than with one (64 decisions; the workers' time).

    Results repeat bit for bit only for a fixed thread count (floating-point sums split
    differently); set ``torch_threads`` for runs that must repeat exactly.

    Args:
        collect: Threads during rollouts (0: automatic: 1 with env ``workers``, else the
            update's count).
        update: Threads of the update (0: ``collect`` if fixed, else automatic).
        cores: Cores available (default :func:`rank_cores`).
        probe_every: Iterations between trials of the slower count.
        workers: Env worker processes stepping while the rollout's policy waits (0: the envs
            step in this process).
    """

    def __init__(
        self,
        collect: int,
        update: int,
        cores: int | None = None,
        probe_every: int = 25,
        workers: int = 0,
    ) -> None:
        self.cores = cores or rank_cores()
        self.fixed_collect = collect or (1 if workers > 0 else 0)
        fixed = update or collect
        self.candidates = [fixed] if fixed else sorted({self.cores, 1}, reverse=True)
        self.probe_every = probe_every
        self.interval = probe_every  # the wait before the next probe (it backs off, above)
        self.next_probe = probe_every
        self.probing = False
        self.seconds: dict[int, float] = {}
        self.iteration = 0
        self.current = self.candidates[0]

    def next_iteration(self) -> tuple[int, int]:
        """Choose the counts of the coming iteration; returns ``(collect, update)`` threads."""
        unmeasured = [c for c in self.candidates if c not in self.seconds]
        if self.iteration == 0 or len(self.candidates) == 1:
            self.current = self.candidates[0]
        elif unmeasured:
            self.current = unmeasured[0]
        else:
            ranked = sorted(self.candidates, key=self.seconds.__getitem__)
            self.probing = self.iteration >= self.next_probe
            self.current = ranked[-1] if self.probing else ranked[0]
        self.iteration += 1
        return self.fixed_collect or self.current, self.current

    def record(self, update_seconds: float) -> None:
        """Take note of how long the iteration's update took (the first is a warm-up)."""
        if self.iteration > 1:  # the latest time of each count: the load may have changed
            if self.probing:
                best = min(t for c, t in self.seconds.items() if c != self.current)
                lost = update_seconds > PROBE_BACKOFF_RATIO * best
                longest = self.probe_every * PROBE_BACKOFF_MAX
                self.interval = min(2 * self.interval, longest) if lost else self.probe_every
                self.next_probe = self.iteration - 1 + self.interval
                self.probing = False
            self.seconds[self.current] = update_seconds


def set_threads(threads: int) -> None:
    """``torch.set_num_threads(threads)`` unless already so (changing it is not free)."""
    if threads > 0 and torch.get_num_threads() != threads:
        torch.set_num_threads(threads)


@contextlib.contextmanager
def update_threads(threads: int) -> Iterator[None]:
    """Run the block with ``threads`` torch intra-op threads (0: unchanged), then restore."""
    before = torch.get_num_threads()
    if threads > 0 and threads != before:
        torch.set_num_threads(threads)
    try:
        yield
    finally:
        if torch.get_num_threads() != before:
            torch.set_num_threads(before)


@contextlib.contextmanager
def quiet() -> Iterator[None]:
    """Swallow rsl-rl's console report (the progress bar and metrics.jsonl replace it)."""
    with contextlib.redirect_stdout(io.StringIO()):
        yield


@contextlib.contextmanager
def interrupts_deferred() -> Iterator[None]:
    """Hold Ctrl-C and SIGTERM until the block ends, then deliver them to their handlers.

    The runner closes an iteration inside it (merge the reward memory, take the boundary
    snapshot, write its metrics row), so an interrupt saves a checkpoint that metrics.jsonl
    has a row for, never one a row ahead of it. (Blocking the signals would not do: the
    kernel hands a process's signal to any of its threads that does not block it.) Outside
    the main thread, where handlers cannot be set, it does nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    held: list[int] = []
    saved = {s: signal.signal(s, lambda signum, _: held.append(signum)) for s in _DEFERRED}
    try:
        yield
    finally:
        for signum, handler in saved.items():
            signal.signal(signum, signal.SIG_DFL if handler is None else handler)
        for held_signum in dict.fromkeys(held):
            signal.raise_signal(held_signum)


_DEFERRED = (signal.SIGINT, signal.SIGTERM)


def seed_everything(seed: int) -> None:
    """Seed torch, numpy's global generator and ``random`` (the envs have their own)."""
    random.seed(seed)
    np.random.seed(seed)
    torch.manual_seed(seed)


def rank_seed(seed: int, rank: int, env_steps: int) -> int:
    """A 32-bit seed for rank ``rank``'s sampling, distinct per (seed, rank, resume point)."""
    return int(np.random.SeedSequence([seed, rank, env_steps]).generate_state(1)[0])


def resolve_workers(workers: int, num_envs: int, cpus: int | None = None) -> int:
    """The number of env worker processes per rank.

    ``workers >= 0`` is taken as is. -1 (automatic) gives one worker per CPU core available to
    this rank (the cores this process may run on, divided among torchrun's local ranks), but at
    most ``num_envs // 4``: fewer than 8 envs, or a single core, stay in process, where a
    worker's start-up and per-step round trip would cost more than it gains.
    """
    if workers >= 0:
        return workers
    if cpus is None:
        cpus = rank_cores()
    return 0 if cpus < 2 or num_envs < 8 else min(cpus, num_envs // 4)


def resolve_device(device: str, local_rank: int, world_size: int) -> str:
    """The rank's torch device: ``cuda:LOCAL_RANK`` under torchrun (UsageError without CUDA)."""
    if device == "cuda" and world_size > 1:
        return f"cuda:{local_rank}"
    if device.startswith("cuda") and not torch.cuda.is_available():
        raise UsageError(f"device '{device}' requested but CUDA is not available; use --device cpu")
    return device


@dataclass(frozen=True)
class Ranks:
    """This process's place among the ranks of a (torchrun) distributed run."""

    rank: int = 0
    """Global rank (0: the one that logs and saves)."""
    world_size: int = 1
    """Number of ranks."""

    @property
    def is_main(self) -> bool:
        """Whether this rank logs and saves."""
        return self.rank == 0

    @property
    def is_distributed(self) -> bool:
        """Whether there is more than one rank."""
        return self.world_size > 1

    def all_gather(self, value: Any) -> list[Any]:
        """Every rank's ``value``, in rank order (a collective: all ranks call it together);
        ``[value]`` alone."""
        if not self.is_distributed:
            return [value]
        values: list[Any] = [None] * self.world_size
        dist.all_gather_object(values, value)
        return values


class StopRequests:
    """Ctrl-C and SIGTERM during training, taken at safe points.

    A handler that raised ``KeyboardInterrupt`` could raise it anywhere, inside a compiled
    kernel too (numba's dispatcher then reports ``SystemError: CPUDispatcher(contact_touch)
    returned a result with an exception set`` and no checkpoint is written). The handlers that
    :meth:`installed` sets only note the signal; the runner calls :meth:`check` between
    decisions, which raises ``KeyboardInterrupt`` there (the checkpoint path). A second signal
    before that raises at once, for a run that no longer reaches a safe point.
    """

    pending = False

    @classmethod
    def note(cls, signum: int, frame: Any) -> None:
        if cls.pending:
            raise KeyboardInterrupt
        cls.pending = True

    @classmethod
    def check(cls) -> None:
        """Raise ``KeyboardInterrupt`` if a stop was asked for since the last check."""
        if cls.pending:
            cls.pending = False
            raise KeyboardInterrupt

    @classmethod
    @contextlib.contextmanager
    def installed(cls) -> Iterator[None]:
        """Within the block Ctrl-C and SIGTERM are noted for :meth:`check`; the previous
        handlers come back afterwards (outside the main thread nothing changes)."""
        try:
            before = {s: signal.signal(s, cls.note) for s in _DEFERRED}
        except ValueError:  # not the main thread (an embedding program): leave its handlers
            before = {}
        cls.pending = False
        try:
            yield
        finally:
            for signum, handler in before.items():
                signal.signal(signum, handler)
            cls.pending = False
