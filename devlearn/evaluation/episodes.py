"""Evaluation episodes played in several environments at once, in this process or in env worker
processes, with exactly the results of one environment playing them one after another.

One environment evaluating ``E`` episodes in order is the reference: its generator, seeded with
the evaluation seed, draws every episode's start at that episode's reset (the infant's pose or
kick, ``Behavior.on_episode_start``), and a baseline's or a sampling policy's generator draws
every decision's randomness in turn. ``devlearn eval --envs N`` gives each of N slots a run of
consecutive episodes (``np.array_split``: slot 0 the first ones). A slot reaches its first
episode ``k`` as the reference does: a fresh generator, ``k`` resets, and the policy's draws of
``k`` episodes made without acting. Its later episodes then follow by the environment's own
reset, as in the reference. Each slot acts on a batch of one observation, with the same calls
as the reference (a batch of several rows can round differently in float32). Its evaluator
sees its episodes only; the slots' evaluators are merged in slot order
(:meth:`~devlearn.api.behavior.Evaluator.merge`; an evaluator that is not
:attr:`~devlearn.api.behavior.Evaluator.mergeable` plays in one env). No env computes reward
terms: an evaluation reports none.

That a slot's skip reaches the reference's state rests on a property of the behaviour: the env's
generator is drawn at resets only, in amounts that do not depend on the episode before, and the
policy draws the same amount every decision. Every slot reports its generators' states where its
run begins and where it ends, and :func:`merged_results` refuses results whose runs do not meet
(slot i's end differs from slot i + 1's beginning), so a behaviour without the property is
refused rather than evaluated differently.
"""

from __future__ import annotations

import contextlib
import time
from collections import deque
from collections.abc import Callable, Generator
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from devlearn.api.errors import UsageError
from devlearn.env.behavior_env import step_batch
from devlearn.env.settings import EnvSettings
from devlearn.env.workers import WorkerPool, make_envs
from devlearn.evaluation.policy import batch_of_one
from devlearn.files import replaced_atomically

if TYPE_CHECKING:
    from devlearn.api.behavior import Behavior
    from devlearn.env.behavior_env import BehaviorEnv, InfantFactory
    from devlearn.evaluation.policy import Actions

VIDEO_FPS = 25
"""Frame rate of evaluation videos (every k-th decision is rendered to match it)."""
VIDEO_FORMATS = {".mp4": "mp4", ".mkv": "matroska", ".mov": "mov", ".avi": "avi"}
"""The video files ``devlearn eval --video`` writes, by extension, and ffmpeg's container for
each (H.264 inside; WebM and GIF need other codecs, and ffmpeg writes them empty without one)."""
STILL_WINDOW_S = 1.0
"""An episode's end, in simulated seconds, over which :class:`EndStillness` measures the body."""
STILL_SPEED = 0.05
"""Mean absolute joint velocity (rad/s, m/s for a free joint) below which the body is still: a
held posture's tremor is ~0.01-0.03, a moving arm's ~1 (hand_to_mouth, issue #54)."""


class EndStillness:
    """Whether a policy's episode ends with the body still (issue #54 item 3).

    A deterministic policy (the mean action) can hold a posture it never leaves: a fixed point
    of the closed loop, which the exploration noise kicked it out of in training. On
    ``hand_to_mouth`` 16 of 30 random-pose episodes of a policy whose sampled actions reach
    the mouth in 0.8 of them ended so (mean joint speed 0.005-0.04 over the last second). The
    figures, per episode: ``end_speed`` (the mean absolute joint velocity over the last
    :data:`STILL_WINDOW_S` simulated seconds) and ``ends_still`` (1 below
    :data:`STILL_SPEED`); none for a body without MuJoCo data (a stand-in infant).

    Args:
        decision_s: Simulated seconds per decision.
    """

    def __init__(self, decision_s: float) -> None:
        self.speeds: deque[float] = deque(maxlen=max(1, round(STILL_WINDOW_S / decision_s)))
        """The body's speed after each of the window's last decisions."""

    def add(self, infant: Any) -> None:
        """Record the body's speed after one decision."""
        qvel = getattr(getattr(infant, "data", None), "qvel", None)
        if qvel is not None and len(qvel):
            self.speeds.append(float(np.abs(qvel).mean()))

    def figures(self) -> dict[str, float]:
        """The episode's figures, counted afresh for the next."""
        if not self.speeds:
            return {}
        speed = float(np.mean(self.speeds))
        self.speeds.clear()
        return {"end_speed": speed, "ends_still": float(speed < STILL_SPEED)}


PROGRESS_SECONDS = 0.5
"""How often a worker reports its progress (physics steps, episodes) to the progress bar."""


# --- the plan and one process's slots -------------------------------------------------------


@dataclass(frozen=True)
class EpisodePlan:
    """What every slot needs to play its episodes (picklable: it travels to env workers).

    Attributes:
        blocks: Per slot, its episodes ``(first, stop)``, consecutive, slot 0 first.
        seed: The evaluation seed (the env's generator).
        stage: The evaluation stage's options.
        start: The infant start to set (``babybench``, ``rest``), or None: the infant's own.
        decisions: Decisions per episode (physics steps / decision rate).
        actions: The policy's actions in their initial state, for batches of one (each slot
            plays a copy).
        video: Write the first episode's frames here (MP4), or None.
        video_stride: Render every this many decisions.
    """

    blocks: tuple[tuple[int, int], ...]
    seed: int
    stage: dict[str, Any]
    start: str | None
    decisions: int
    actions: Actions
    video: str | None = None
    video_stride: int = 1


@dataclass
class SlotResult:
    """What one slot played.

    Attributes:
        episodes: Each episode's ``end_episode`` metrics, in episode order.
        evaluator: The slot's evaluator, over its episodes only.
        started: The start its episodes took (babybench, rest or random).
        begins: (env generator, policy randomness) states at its first episode's first decision.
        ends: The same after its last episode (the env's after the reset that follows it).
        video_error: Why the video this slot filmed could not be written, or None.
    """

    episodes: list[dict[str, float]]
    evaluator: Any
    started: str
    begins: tuple[Any, Any]
    ends: tuple[Any, Any]
    video_error: str | None = None


def set_infant_start(infant: Any, start: str) -> None:
    """Make an env's infant start its episodes with ``start`` (babybench or rest): its
    ``start`` attribute (:class:`~devlearn.infant.Infant`'s; a stand-in declares its own and
    refuses a start it does not have with ValueError).

    Raises:
        UsageError: The infant has no such start.
    """
    try:
        infant.start = start
    except ValueError as err:
        raise UsageError(f"--start {start}: {err}") from None


def prepare_env(env: BehaviorEnv, stage: dict[str, Any], start: str | None) -> str:
    """Put ``env`` under the evaluation stage and start; return the start its episodes take."""
    if start is not None:
        set_infant_start(env.infant, start)
    env.set_stage(stage)
    return "random" if stage.get("random_pose") else str(env.infant.start)


class _Slot:
    """One env playing its run of episodes: reaches the first as the reference does."""

    def __init__(self, env: BehaviorEnv, plan: EpisodePlan) -> None:
        self.env = env
        # An evaluation pays no rewards (eval.json holds none): its envs compute no reward
        # terms, a fifth of a self-touch step.
        env.terms = []
        first, stop = plan.blocks[env.index]
        self.first, self.left = first, stop - first
        self.started = prepare_env(env, plan.stage, plan.start)
        env.rng = np.random.default_rng(plan.seed)
        for _ in range(first):
            env.reset()
        self.obs = env.reset()
        self.actions = plan.actions.for_slot()
        self.actions.skip(first * plan.decisions)
        self.begins = (env.rng.bit_generator.state, self.actions.rng_state())
        self.episodes: list[dict[str, float]] = []
        self.video_error: str | None = None
        step_s = float(getattr(env.infant, "physics_timestep", 0.0)) * env.action_repeat
        self.stillness = EndStillness(step_s) if step_s > 0 else None

    def step(self, obs: dict[str, np.ndarray], info: dict[str, Any] | None) -> bool:
        """Take one decision's outcome; True when it ended an episode."""
        self.obs = obs
        if info is None:
            if self.stillness is not None:  # not at an episode's end: that body is the reset's
                self.stillness.add(self.env.infant)
            return False
        metrics = {k: v for k, v in info.items() if k.startswith("metrics/")}
        figures = {k.removeprefix("metrics/"): float(v) for k, v in metrics.items()}
        own = self.actions.episode_figures()
        still = self.stillness.figures() if self.stillness is not None else {}
        if own:  # a network's: how its episode ended too (baselines report no policy figures)
            own = {**own, **still}
        policy = {f"policy/{k}": v for k, v in own.items()}
        self.episodes.append({**figures, **policy})
        self.left -= 1
        return True

    def result(self) -> SlotResult:
        ends = (self.env.rng.bit_generator.state, self.actions.rng_state())
        return SlotResult(
            self.episodes, self.env.evaluator, self.started, self.begins, ends, self.video_error
        )


def play(
    envs: list[BehaviorEnv],
    plan: EpisodePlan,
    report: Callable[[int, int], None] | None = None,
) -> list[SlotResult]:
    """Play the episodes of ``envs``' slots (env ``index`` = slot), stepping them together.

    Episodes all last the infant's episode length, so the slots' episodes begin together; a
    slot whose run is over (runs are one episode shorter in the last slots) stops stepping.

    Args:
        envs: This process's envs, made with ``training=False``.
        plan: The evaluation's plan.
        report: ``report(physics_steps, episodes_ended)`` after every decision.
    Returns:
        One result per env, in env order.
    """
    slots = [_Slot(env, plan) for env in envs]
    filmed = next((s for s in slots if s.first == 0), None) if plan.video else None
    film = Film(plan.video) if plan.video is not None and filmed is not None else None
    if filmed is not None:  # this process plays episode 0
        frame = partial(filmed.env.behavior.evaluation().frame, filmed.env.infant)
    try:
        while playing := [s for s in slots if s.left]:
            batch = [s.env for s in playing]
            for t in range(plan.decisions):
                if film is not None and t % plan.video_stride == 0:
                    film.add(frame)
                # each slot acts on its own batch of one: a batch of several rows can round
                # differently in float32 from the reference's one env
                actions = [s.actions.act(batch_of_one(s.obs))[0] for s in playing]
                outcomes = step_batch(batch, actions)
                ended = sum(s.step(obs, info) for s, (obs, *_, info) in zip(playing, outcomes))
                if report is not None:
                    report(len(batch) * batch[0].action_repeat, ended)
            if film is not None:  # the first episode is over
                film.finish()
                if filmed is not None:
                    filmed.video_error = film.error
                film = None
    finally:
        if film is not None:  # stopped inside the first episode: no video
            film.abandon()
    return [s.result() for s in slots]


class Film:
    """The frames of an episode as a video file (:data:`VIDEO_FORMATS`), written to a temporary
    beside ``path`` and renamed over it by :meth:`finish`: a failed or killed evaluation leaves
    no partial video, and an existing ``path`` that is not a regular file is left alone.

    A failure (a frame that cannot be rendered, ffmpeg failing, a full disk) stops the filming
    and is kept in :attr:`error`; the episodes go on, so an evaluation is never lost to its
    video.

    Args:
        path: The video file.
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.error: str | None = None
        """Why the video could not be written, or None."""
        self._file = contextlib.ExitStack()  # the temporary, renamed when the stack closes
        self._frames: Generator[None, Any, None] | None = None
        self._tmp: Path | None = None
        try:
            self._tmp = self._file.enter_context(replaced_atomically(self.path))
        except Exception as exc:
            self._fail(exc)

    def add(self, render: Callable[[], np.ndarray]) -> None:
        """Add the frame ``render()`` draws ((H, W, 3) uint8 RGB), unless filming failed."""
        if self._tmp is None:
            return
        try:
            frame = np.ascontiguousarray(render(), dtype=np.uint8)
            if self._frames is None:
                import imageio_ffmpeg

                self._frames = imageio_ffmpeg.write_frames(
                    str(self._tmp),
                    (frame.shape[1], frame.shape[0]),
                    fps=VIDEO_FPS,
                    macro_block_size=1,
                    # the temporary's name has no extension for ffmpeg to read the container from
                    output_params=["-f", VIDEO_FORMATS.get(self.path.suffix.lower(), "mp4")],
                )
                self._frames.send(None)
            self._frames.send(frame)
        except Exception as exc:
            self._fail(exc)

    def finish(self) -> None:
        """Close the video and rename it over ``path`` (a failure is kept in :attr:`error`)."""
        if self._tmp is None:
            return
        try:
            if self._frames is not None:
                self._frames.close()
                self._frames = None
            self._tmp = None
            self._file.close()
        except Exception as exc:
            self._fail(exc)

    def abandon(self) -> None:
        """Stop filming and delete the temporary; ``path`` stays as it was."""
        if self._frames is not None:
            with contextlib.suppress(Exception):
                self._frames.close()
        self._frames = self._tmp = None
        with contextlib.suppress(Exception):
            self._file.__exit__(RuntimeError, RuntimeError("abandoned"), None)

    def _fail(self, exc: Exception) -> None:
        reason = getattr(exc, "strerror", None) or " ".join(str(exc).split())[-200:]
        self.error = f"cannot write the video {self.path}: {reason or type(exc).__name__}"
        self.abandon()


class _Throttled:
    """Sums ``(steps, episodes)`` and sends them at most every :data:`PROGRESS_SECONDS`."""

    def __init__(self, send: Callable[[Any], None]) -> None:
        self.send = send
        self.steps = self.episodes = 0
        self.last = time.monotonic()

    def add(self, steps: int, episodes: int) -> None:
        self.steps += steps
        self.episodes += episodes
        if time.monotonic() - self.last >= PROGRESS_SECONDS:
            self.flush()

    def flush(self) -> None:
        if self.steps or self.episodes:
            self.send((self.steps, self.episodes))
        self.steps = self.episodes = 0
        self.last = time.monotonic()


def play_in_worker(
    plan: EpisodePlan, envs: list[BehaviorEnv], send: Callable[[Any], None]
) -> list[SlotResult]:
    """:func:`play` in an env worker (its ``call`` command), progress sent to the parent."""
    progress = _Throttled(send)
    try:
        return play(envs, plan, progress.add)
    finally:
        progress.flush()


class Players:
    """The envs that play an evaluation's slots: in this process, or split over env worker
    processes (:class:`~devlearn.env.workers.WorkerPool`; started in this thread: a worker
    ends with the thread that started it). Close it (or use it as a context manager).

    Args:
        behavior: The behaviour (every env gets its own copy).
        slots: Envs, one per slot.
        workers: Env worker processes (0: in this process).
        seed: The evaluation seed.
        infant_factory: Infant builder (picklable with workers); None: the real infant.
        settings: The envs' settings (the decision rate; an evaluation session's length).
        age_months: The body's age (None: the default body).
    """

    def __init__(
        self,
        behavior: Behavior,
        slots: int,
        workers: int,
        seed: int,
        infant_factory: InfantFactory | None,
        settings: EnvSettings,
        age_months: float | None = None,
    ) -> None:
        seeds = [seed] * slots  # every slot seeds its generator afresh anyway
        self.envs: list[BehaviorEnv] = []
        self.pool: WorkerPool | None = None
        if workers == 0:
            self.envs = make_envs(
                behavior, seeds, infant_factory, 0, settings, age_months, training=False
            )
        else:
            self.pool = WorkerPool(
                behavior,
                seeds,
                workers,
                infant_factory,
                settings,
                age_months=age_months,
                training=False,
            )

    def play(self, plan: EpisodePlan, report: Callable[[int, int], None]) -> list[SlotResult]:
        """Play ``plan``; the slots' results in slot order (``report`` as in :func:`play`)."""
        if self.pool is None:
            return play(self.envs, plan, report)
        job = partial(play_in_worker, plan)
        replies = self.pool.call("call", [job] * len(self.pool.conns), lambda p: report(*p))
        return [result for reply in replies for result in reply]

    def close(self) -> None:
        """Stop the workers, or close the envs."""
        if self.pool is not None:
            self.pool.close()
        for env in self.envs:
            env.close()

    def __enter__(self) -> Players:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def merged_results(results: list[SlotResult]) -> tuple[Any, list[dict[str, float]], str]:
    """The slots' evaluators merged in slot order, every episode's metrics in order, and the
    start the episodes took.

    Raises:
        UsageError: A slot's run did not begin where the slot before it ended: the
            behaviour draws from the env's generator during episodes, or a reset draws
            amounts that depend on the episode before, or the policy draws unevenly; the
            episodes then differ from one env playing them in order (use ``--envs 1``).
    """
    for i, (before, after) in enumerate(zip(results, results[1:])):
        for what, end, begin in zip(
            ("env's generator", "policy's randomness"), before.ends, after.begins
        ):
            if end != begin:
                raise UsageError(
                    f"evaluation env {i + 1} began with the {what} elsewhere than env {i} "
                    "left it: this behaviour's episodes cannot be played in several envs "
                    "with the results of one (does it draw from the env's generator during "
                    "episodes?); evaluate it with --envs 1"
                )
    evaluator = results[0].evaluator
    for later in results[1:]:
        evaluator.merge(later.evaluator)
    episodes = [metrics for result in results for metrics in result.episodes]
    return evaluator, episodes, results[0].started
