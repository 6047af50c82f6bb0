"""Batches of BehaviorEnvs, in process or in worker processes writing to shared memory."""

from __future__ import annotations

import contextlib
import copy
import ctypes
import multiprocessing as mp
import os
import signal
import sys
import traceback
from collections.abc import Callable, Iterator
from multiprocessing.connection import wait
from typing import TYPE_CHECKING, Any

import numpy as np

from devlearn.env.behavior_env import (
    BehaviorEnv,
    InfantFactory,
    load_run_memories,
    run_memories,
    share_batched_terms,
    step_batch,
)
from devlearn.env.buffers import attach, env_spec, write_obs
from devlearn.env.guards import GuardError
from devlearn.env.settings import EnvSettings

if TYPE_CHECKING:
    from multiprocessing.connection import Connection

    from devlearn.api.behavior import Behavior

EpisodeInfos = list[tuple[int, dict[str, float]]]
"""(global env index, episode_info) for every episode that ended this step."""


class EnvWorkerError(RuntimeError):
    """An environment worker process failed; the message holds the worker's traceback.

    ``died`` is True when the process ended without reporting (killed, out of memory).
    """

    died: bool = False


def step_envs(envs: list[BehaviorEnv], offset: int, arrays: dict[str, np.ndarray]) -> EpisodeInfos:
    """Step envs ``offset..offset+len(envs)`` with their rows of ``arrays["actions"]``.

    The envs are stepped as one batch (:func:`~devlearn.env.behavior_env.step_batch`), so
    batched reward terms run once for all of them. ``term_rewards`` and ``final/<name>``
    (:class:`~devlearn.env.buffers.EnvBuffers`) are written where ``arrays`` has them.
    """
    infos = []
    rows = slice(offset, offset + len(envs))
    obs_out = {key[4:]: a[rows] for key, a in arrays.items() if key.startswith("obs/")}
    results = step_batch(envs, arrays["actions"][rows], obs_out)
    terms = arrays.get("term_rewards")
    finals = any(key.startswith("final/") for key in arrays)
    for i, (env, (_, reward, done, time_out, info)) in enumerate(zip(envs, results)):
        j = offset + i
        arrays["rewards"][j] = reward
        arrays["dones"][j] = done
        arrays["time_outs"][j] = time_out
        if terms is not None:
            terms[j] = env.decision_rewards
        if info is not None:
            infos.append((j, info))
            if finals and env.final_observation is not None:
                write_obs(arrays, j, env.final_observation, prefix="final/")
    return infos


def make_envs(
    behavior: Behavior,
    seeds: list[int],
    infant_factory: InfantFactory | None,
    offset: int = 0,
    settings: EnvSettings | None = None,
    age_months: float | None = None,
    training: bool = True,
) -> list:
    """Build one BehaviorEnv per seed (indices ``offset...``), each with its own copy of the
    behaviour, the run's ``settings`` (default ``EnvSettings()``), the body at ``age_months``
    and an evaluator
    for ``training`` (False: ``devlearn eval``'s); the envs share their batched reward terms
    (one instance over all of them)."""
    envs = [
        BehaviorEnv(
            copy.deepcopy(behavior),
            s,
            infant_factory,
            training=training,
            index=offset + i,
            age_months=age_months,
            settings=settings,
        )
        for i, s in enumerate(seeds)
    ]
    share_batched_terms(envs)
    return envs


def _die_with_parent() -> None:
    """Ask Linux to SIGTERM this worker when its parent dies (kill -9 included)."""
    if sys.platform.startswith("linux"):
        try:
            ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
        except OSError:
            pass  # the closed pipe (EOFError below) still ends the worker


def worker_main(
    conn: Connection,
    behavior: Behavior,
    seeds: list[int],
    offset: int,
    infant_factory: InfantFactory | None,
    settings: EnvSettings | None = None,
    age_months: float | None = None,
    training: bool = True,
) -> None:
    """Entry point of one worker process: serve commands from the parent until told to close.

    Replies ``("ok", payload)`` or, on any exception, ``("error", traceback text)`` and exits;
    the ``call`` command (``arg(envs, send)``: a picklable function run on this worker's envs,
    e.g. evaluation episodes) may send ``("progress", payload)`` messages before its reply.
    The worker ignores SIGINT so that Ctrl-C reaches only the parent, which can then still ask
    for the envs' state to write its interrupt checkpoint.
    """
    _die_with_parent()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    envs: list[BehaviorEnv] = []
    blocks: list = []
    arrays: dict[str, np.ndarray] = {}
    try:
        envs = make_envs(behavior, seeds, infant_factory, offset, settings, age_months, training)
        first = [env.reset() for env in envs]
        conn.send(("ok", env_spec(envs[0], first[0])))
        while True:
            cmd, arg = conn.recv()
            if cmd == "close":
                break
            if cmd == "attach":
                arrays, blocks = attach(arg)
                for i, obs in enumerate(first):
                    write_obs(arrays, offset + i, obs)
                reply: Any = None
            elif cmd == "step":
                reply = step_envs(envs, offset, arrays)
            elif cmd == "set_stage":
                for env in envs:
                    env.set_stage(arg)
                reply = [None] * len(envs)
            elif cmd == "set_age":
                for env in envs:
                    env.set_age(arg)
                reply = None
            elif cmd == "state":
                reply = [env.state_dict() for env in envs]
            elif cmd == "memory":
                reply = run_memories(envs)
            elif cmd == "load_memory":
                load_run_memories(envs, arg)
                reply = None
            elif cmd == "call":
                reply = arg(envs, lambda payload: conn.send(("progress", payload)))
            elif cmd == "load":
                for i, (env, state) in enumerate(zip(envs, arg)):
                    env.load_state_dict(state)
                    write_obs(arrays, offset + i, env.reset())
                reply = None
            else:
                raise ValueError(f"unknown worker command {cmd!r}")
            conn.send(("ok", reply))
    except (EOFError, BrokenPipeError, KeyboardInterrupt):
        pass  # the parent is gone: nothing to report to
    except GuardError as exc:
        try:
            conn.send(("guard", exc))  # re-raised as is by the parent
        except (BrokenPipeError, OSError):
            pass
    except BaseException:
        try:
            conn.send(("error", traceback.format_exc()))
        except (BrokenPipeError, OSError):
            pass
    finally:
        arrays = {}
        for env in envs:
            env.close()
        for block in blocks:
            block.close()


WORKER_THREADS = {
    "OMP_NUM_THREADS": "1",
    "MKL_NUM_THREADS": "1",
    "OPENBLAS_NUM_THREADS": "1",
    "OPENCV_FOR_THREADS_NUM": "1",
}
"""Environment of worker processes: one thread per native pool. There is one worker per core,
and idle pool threads that spin-wait would compete with the other workers and with the
training process's inference and update threads."""


@contextlib.contextmanager
def _worker_environment() -> Iterator[None]:
    """Set :data:`WORKER_THREADS` while workers are spawned (they inherit ``os.environ``)."""
    saved = {key: os.environ.get(key) for key in WORKER_THREADS}
    os.environ.update(WORKER_THREADS)
    try:
        yield
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


class WorkerPool:
    """Envs split over worker processes; commands go through pipes, arrays through shared memory.

    Args:
        behavior: Pickled to every worker; each env gets its own deep copy.
        seeds: One seed per env, in global order.
        workers: Number of processes (at most one per env).
        infant_factory: Picklable infant factory (None: the real infant).
        settings: The run's settled env settings (the decision rate), handed to every env.
        age_months: The body's age (None: the default body).
        context: multiprocessing start method; ``spawn`` (default) imports everything afresh, so
            no parent state (threads, torch, open files) leaks into workers.
        training: The envs' evaluators are training ones (False: ``devlearn eval``'s).
    """

    def __init__(
        self,
        behavior: Behavior,
        seeds: list[int],
        workers: int,
        infant_factory: InfantFactory | None = None,
        settings: EnvSettings | None = None,
        context: str = "spawn",
        age_months: float | None = None,
        training: bool = True,
    ) -> None:
        ctx = mp.get_context(context)
        self._pending: set[int] = set()
        self.conns: list = []
        self.procs: list = []
        self.chunks = np.array_split(np.arange(len(seeds)), min(workers, len(seeds)))
        try:
            for chunk in self.chunks:
                parent_conn, child_conn = ctx.Pipe()
                chunk_seeds = [seeds[i] for i in chunk]
                proc = ctx.Process(  # type: ignore[attr-defined]  # every concrete context has it
                    target=worker_main,
                    args=(
                        child_conn,
                        behavior,
                        chunk_seeds,
                        int(chunk[0]),
                        infant_factory,
                        settings,
                        age_months,
                        training,
                    ),
                    daemon=True,
                    name=f"devlearn-env-worker-{len(self.procs)}",
                )
                with _worker_environment():
                    proc.start()
                child_conn.close()
                self.conns.append(parent_conn)
                self.procs.append(proc)
            self.spec = self._gather()[0]
        except BaseException:
            self.close()
            raise

    def _gather(self, progress: Callable[[Any], None] | None = None) -> list:
        """Every worker's reply, in worker order; ``progress`` gets the ``("progress", payload)``
        messages a ``call`` sends before its reply, from whichever worker sends them."""
        # Workers still owed a reply are remembered, so a call interrupted by Ctrl-C (the
        # interrupt checkpoint then asks for state) first drains the stale replies.
        self._pending = set(range(len(self.conns)))
        replies: list = [None] * len(self.conns)
        guards: dict[int, BaseException] = {}
        while self._pending:
            ready = wait([self.conns[k] for k in sorted(self._pending)])
            for k in sorted(self._pending):
                if self.conns[k] not in ready:
                    continue
                status, payload = self._receive(k)
                if status == "progress":
                    if progress is not None:
                        progress(payload)
                    continue
                self._pending.discard(k)
                if status == "guard":
                    guards[k] = payload
                else:
                    replies[k] = payload
        if guards:  # the first worker's, whichever replied first: the same report on any load
            self.close()
            raise guards[min(guards)]
        return replies

    def _receive(self, k: int) -> tuple[str, Any]:
        """Worker ``k``'s next message; its failure (a traceback, death) is raised here after
        the pool is closed. A guard (a reward term's bad value or exception) is returned:
        :meth:`_gather` raises the first worker's once every worker has replied, so that the
        same run reports the same env whichever worker's reply came first."""
        conn, proc = self.conns[k], self.procs[k]
        try:
            status, payload = conn.recv()
        except (EOFError, OSError):
            proc.join(timeout=1.0)
            code = proc.exitcode
            self.close()
            how = f"exit code {code}"
            if code is not None and code < 0:
                try:
                    how = f"killed by {signal.Signals(-code).name}"
                except ValueError:
                    how = f"killed by signal {-code}"
                how += " (out of memory?)" if code == -signal.SIGKILL else ""
            error = EnvWorkerError(f"env worker {k} (pid {proc.pid}) died unexpectedly, {how}")
            error.died = True
            raise error from None
        if status == "guard":  # raised by _gather once every worker replied
            return status, payload
        if status == "error":
            self.close()
            raise EnvWorkerError(f"env worker {k} (pid {proc.pid}) failed:\n{payload}")
        return status, payload

    def call(
        self, cmd: str, args: list | None = None, progress: Callable[[Any], None] | None = None
    ) -> list:
        """Send ``cmd`` (with ``args[k]`` to worker k, or None) to every worker; return replies
        (``progress`` takes a ``call`` command's progress messages, see :func:`worker_main`)."""
        for k in sorted(self._pending):
            try:
                while self.conns[k].recv()[0] == "progress":
                    pass
            except (EOFError, OSError):
                pass  # reported by the send or receive below
        self._pending = set()
        for k, conn in enumerate(self.conns):
            try:
                conn.send((cmd, None if args is None else args[k]))
            except (BrokenPipeError, OSError):
                self.close()
                raise EnvWorkerError(f"env worker {k} is gone (pipe closed)") from None
        return self._gather(progress)

    def split(self, items: list) -> list[list]:
        """Split a per-env list into per-worker lists."""
        return [[items[i] for i in chunk] for chunk in self.chunks]

    def close(self) -> None:
        """Ask workers to close, then terminate any that do not exit within a few seconds."""
        for conn in self.conns:
            try:
                conn.send(("close", None))
            except (BrokenPipeError, OSError):
                pass
        for proc in self.procs:
            proc.join(timeout=5.0)
            if proc.is_alive():
                proc.terminate()
                proc.join(timeout=1.0)
        for conn in self.conns:
            conn.close()
        self.conns, self.procs = [], []
