"""A behaviour that counts and orders its episode-hook calls (dm_control's hook tracker idea).

:class:`HookTracker` runs on the fake infant (:mod:`devlearn.testing.fake_infant`) and reports,
as episode metrics, the order in which devlearn called its episode hooks (``on_episode_start``,
``before_step``, ``process_action``) and ``facts``: what docs/writing-a-plugin.md ("Episode
hooks") promises a behaviour, in one env, a batch or worker processes.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any

import numpy as np

import devlearn
from devlearn import StepContext
from devlearn.testing.fake_infant import TinyBehavior, TinyConfig

if TYPE_CHECKING:
    from devlearn.infant import Infant


class CallLog(devlearn.EpisodeHooks):
    """One environment's hook calls of the current episode (``calls``), checked as they come
    (``problems``)."""

    def __init__(self) -> None:
        self.episodes = 0
        self.calls: list[str] = []
        self.pending_action: np.ndarray | None = None
        self.problems: list[str] = []

    def on_episode_start(self, infant: Any, rng: np.random.Generator) -> None:
        if not isinstance(rng, np.random.Generator):
            self.problems.append(f"rng is {type(rng).__name__}")
        if np.any(infant.position != 0):  # fixed-pose stage: the reset already happened
            self.problems.append("on_episode_start before the infant's reset")
        self.episodes += 1
        self.calls = ["start"]

    def before_step(self, infant: Infant, action: np.ndarray) -> None:
        if np.any(np.abs(action) > 1.0):
            self.problems.append("before_step saw an unclipped action")
        self.pending_action = np.array(action, copy=True)
        self.calls.append("before")

    def process_action(self, action: np.ndarray, stage: dict[str, Any]) -> np.ndarray:
        if self.pending_action is None or not np.array_equal(action, self.pending_action):
            self.problems.append("process_action without a before_step of the same action")
        self.pending_action = None
        self.calls.append("process")
        return action


class HookTracker(TinyBehavior):
    """TinyBehavior whose episode hooks (:class:`CallLog`) log every call of the current
    episode.

    Each step's facts carry the calls so far in this episode and the episode number, so that
    the evaluator's episode summary (which travels back from worker processes) reports them.
    """

    name = "hook_tracker"

    def __init__(self, config: TinyConfig | None = None) -> None:
        super().__init__(config)
        self.log = CallLog()

    def episode(self) -> devlearn.EpisodeSpec:
        return dataclasses.replace(super().episode(), hooks=self.log)

    @devlearn.per_env
    def facts(self, infant: Infant) -> dict[str, Any]:
        log = self.log
        log.calls.append("facts")
        return {"calls": list(log.calls), "episode": log.episodes, "problems": len(log.problems)}

    def evaluation(self) -> devlearn.EvalProtocol:
        return dataclasses.replace(super().evaluation(), evaluator=lambda training: CallEvaluator())


class CallEvaluator(devlearn.Evaluator):
    """Reports the hook calls of each episode as metrics."""

    def __init__(self) -> None:
        self.last: dict[str, Any] = {}

    def record(self, ctx: StepContext) -> None:
        self.last = ctx.facts

    def end_episode(self) -> dict[str, float]:
        calls = self.last["calls"]
        steps = calls.count("before")
        # start, facts (first observation), then per step: before, process, facts
        ordered = calls == ["start", "facts", *["before", "process", "facts"] * steps]
        return {
            "episode": float(self.last["episode"]),
            "starts": float(calls.count("start")),
            "before_steps": float(steps),
            "facts": float(calls.count("facts")),
            "ordered": float(ordered),
            "problems": float(self.last["problems"]),
        }
