"""Issue #31: the core runs one term contract; a per-environment term wrapped once in
BatchedFromPerEnv pays, resets and saves exactly as the term in each environment."""

from __future__ import annotations

import numpy as np

import devlearn
from devlearn import BatchContext, BatchedFromPerEnv, StepContext


class Counter(devlearn.IntrinsicReward):
    """Pays the number of steps of this episode with fact ``x`` set."""

    name = "counter"

    def __init__(self, weight: float = 1.0) -> None:
        super().__init__(weight)
        self.count = 0

    def reset(self) -> None:
        self.count = 0

    def __call__(self, ctx: StepContext) -> float:
        self.count += int(ctx.facts["x"])
        return float(self.count)

    def state_dict(self):
        return {"count": self.count}

    def load_state_dict(self, state):
        self.count = state["count"]


def _ctx(x: bool) -> StepContext:
    return StepContext(None, {}, {"x": x}, 0, False)


def test_wrapped_term_equals_one_term_per_env():
    rng = np.random.default_rng(0)
    wrapped = BatchedFromPerEnv(Counter(0.5))
    wrapped.bind(3)
    own = [Counter(0.5) for _ in range(3)]
    for step in range(40):
        facts = rng.random(3) < 0.5
        contexts = [_ctx(bool(f)) for f in facts]
        got = wrapped(BatchContext(contexts))
        assert got.tolist() == [float(t(c)) for t, c in zip(own, contexts)]
        if step == 20:
            wrapped.reset(1)
            own[1].reset()
    assert [wrapped.state_dict(i) for i in range(3)] == [t.state_dict() for t in own]
    assert wrapped.weight == 0.5 and wrapped.name == "counter"
