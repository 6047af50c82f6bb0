"""Core-test behaviours on top of devlearn.testing's fake infant: another name for
checkpoint-mismatch tests, and a batched term with run-wide memory."""

from __future__ import annotations

from typing import Any

import numpy as np

import devlearn
from devlearn.testing.fake_infant import TinyBehavior


class OtherBehavior(TinyBehavior):
    """Same as tiny, under another name (for checkpoint-mismatch tests)."""

    name = "other"


class StepNovelty(devlearn.BatchedIntrinsicReward):
    """A third-party batched term with run-wide memory (the core mechanism, no self_touch):
    pays 1 the first time the run reaches episode step t (a bool per step index) and keeps
    the largest batch it has seen (an int, merged by maximum)."""

    name = "step_novelty"

    def __init__(self, episode_steps: int = 10) -> None:
        super().__init__(1.0)
        self.seen = np.zeros(episode_steps, dtype=bool)
        self.widest = np.zeros(1, dtype=np.int64)

    def __call__(self, batch: devlearn.BatchContext) -> np.ndarray:
        pay = np.zeros(len(batch))
        for i, t in enumerate(batch.step.tolist()):  # the first env in batch order is paid
            if not self.seen[t]:
                self.seen[t] = True
                pay[i] = 1.0
        self.widest[0] = max(self.widest[0], len(batch))
        return pay

    def state_dict(self, env: int) -> dict[str, Any]:
        return {"seen": self.seen.copy(), "widest": self.widest.copy()}

    def load_state_dict(self, env: int, state: dict[str, Any]) -> None:
        memory = {"seen": state["seen"], "widest": state["widest"]}
        if env > 0:
            memory = self.merge_run_memory([self.run_memory(), memory])
        self.load_run_memory(memory)

    def run_memory(self) -> dict[str, np.ndarray]:
        return {"seen": self.seen, "widest": self.widest}

    def load_run_memory(self, memory: dict[str, np.ndarray]) -> None:
        self.seen = np.array(memory["seen"], dtype=bool)
        self.widest = np.array(memory["widest"], dtype=np.int64)


class NoveltyBehavior(TinyBehavior):
    """The tiny behaviour with :class:`StepNovelty` as its only reward term."""

    name = "novelty"

    def reward_terms(self) -> list:
        return [StepNovelty()]


class BodyAge(devlearn.IntrinsicReward):
    """Pays the age (months) of the body that took the step: shows which body every env,
    in process or in a worker, stepped (issue #41's growth)."""

    name = "body_age"

    def __call__(self, ctx: devlearn.StepContext) -> float:
        age = getattr(ctx.infant, "age_months", None)
        return -1.0 if age is None else float(age)


class AgeBehavior(TinyBehavior):
    """The tiny behaviour paid only the age of its body (:class:`BodyAge`)."""

    name = "aged"

    def reward_terms(self) -> list[devlearn.IntrinsicReward]:
        return [BodyAge(1.0)]
