"""Runtime checks behind devlearn.testing.check_behavior: observations, checked reward terms and
evaluators, scripted contact (the value checks: :mod:`devlearn.conformance_values`)."""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from devlearn.conformance_values import (
    check_number,
    json_problem,
    pickle_problem,
    require,
)
from devlearn.rewards import BatchedIntrinsicReward

OBS_DTYPES = (np.float32, np.uint8)
"""Observation dtypes the networks accept (float32 features, uint8 images)."""


def check_observations(
    obs: Any, shapes: dict[str, tuple] | None, where: str
) -> dict[str, tuple[int, ...]]:
    """Check one step's observations: a dict of fixed-shape, finite float32/uint8 arrays.

    Args:
        obs: What ``Behavior.observe`` returned.
        shapes: The first step's shapes (None on the first step: they are recorded).
        where: Which phase of the check this is, for messages.
    Returns:
        Name -> shape.
    """
    require(isinstance(obs, dict), f"observe() must return a dict, got {type(obs).__name__}")
    if shapes is not None:
        require(
            set(obs) == set(shapes),
            f"observation names changed {where}: {sorted(shapes)} -> {sorted(obs)}",
        )
    out = {}
    for key, value in obs.items():
        require(
            isinstance(value, np.ndarray),
            f"observation '{key}' is a {type(value).__name__}, not a numpy array {where}",
        )
        require(
            value.dtype in OBS_DTYPES,
            f"observation '{key}' has dtype {value.dtype}; use float32 (or uint8 images) {where}",
        )
        if shapes is not None:
            require(
                value.shape == shapes[key],
                f"observation '{key}' changed shape from {shapes[key]} to {value.shape} {where}",
            )
        require(bool(np.all(np.isfinite(value))), f"observation '{key}' has NaN or inf {where}")
        out[key] = tuple(value.shape)
    return out


def check_batched_observations(behavior: Any, infants: list[Any], where: str = "") -> None:
    """Require ``batch_facts`` / ``batch_observe`` to give, for every infant, exactly (bit for
    bit) what ``facts`` / ``observe`` give for it alone.

    Args:
        behavior: The behaviour (one instance serves every infant, as in a worker).
        infants: Infants in the states to compare (after a step or a reset).
        where: Which phase of the check this is, for messages.
    """
    n = len(infants)
    per_env = [behavior.facts(infant) for infant in infants]
    batched = behavior.batch_facts(infants)
    require(
        isinstance(batched, list) and len(batched) == n,
        f"batch_facts() must return a list of {n} facts dicts, one per infant {where}",
    )
    for i, (got, want) in enumerate(zip(batched, per_env)):
        require(
            set(got) == set(want),
            f"batch_facts()[{i}] has facts {sorted(got)}, facts() {sorted(want)} {where}",
        )
        for key, value in want.items():
            require(
                _identical(got[key], value),
                f"batch_facts()[{i}]['{key}'] differs from facts()['{key}'] {where}",
            )
    observed = behavior.batch_observe(infants, batched)
    for i, (infant, facts) in enumerate(zip(infants, per_env)):
        want = behavior.observe(infant, facts)
        require(
            set(observed) == set(want),
            f"batch_observe() gives {sorted(observed)}, observe() {sorted(want)} {where}",
        )
        for key, value in want.items():
            require(
                np.shape(observed[key]) == (n, *np.shape(value))
                and _identical(np.asarray(observed[key])[i], np.asarray(value)),
                f"batch_observe()['{key}'][{i}] differs from observe()['{key}'] {where}",
            )


def _identical(a: Any, b: Any) -> bool:
    """Equal values; arrays of the same dtype and shape with the same bytes."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
    return bool(a == b)


class CheckedTerm:
    """A reward term whose every value is checked (finite Python float), naming the term."""

    def __init__(self, term: Any, phase: list[str]) -> None:
        self.term = term
        self.phase = phase

    def __getattr__(self, name: str) -> Any:
        return getattr(self.term, name)

    def __call__(self, ctx: Any) -> float:
        value = self.term(ctx)
        return check_number(value, f"reward term '{self.term.name}'", self.phase[0])


class CheckedBatchedTerm(BatchedIntrinsicReward):
    """A batched reward term whose every step is checked: a (num_envs,) array of finite real
    numbers, naming the term."""

    def __init__(self, term: BatchedIntrinsicReward, phase: list[str]) -> None:
        self.term = term
        self.phase = phase
        self.name = term.name
        self.weight = term.weight
        self.num_envs = term.num_envs

    def bind(self, num_envs: int) -> None:
        self.term.bind(num_envs)
        self.num_envs = self.term.num_envs

    def __call__(self, batch: Any) -> np.ndarray:
        values = self.term(batch)
        what = f"batched reward term '{self.term.name}'"
        shape = np.shape(values)
        require(
            shape == (len(batch.contexts),),
            f"{what} returned shape {shape} {self.phase[0]}; "
            f"it must return ({len(batch.contexts)},), one value per environment",
        )
        array = np.asarray(values)
        require(
            array.dtype.kind in "fiu" and bool(np.isfinite(array).all()),
            f"{what} returned {' '.join(repr(values).split())[:60]} {self.phase[0]}; "
            "it must return finite real numbers",
        )
        return array

    def reset(self, env: int) -> None:
        self.term.reset(env)

    def state_dict(self, env: int) -> dict[str, Any]:
        return self.term.state_dict(env)

    def load_state_dict(self, env: int, state: dict[str, Any]) -> None:
        self.term.load_state_dict(env, state)

    def run_memory(self) -> dict[str, np.ndarray]:
        return self.term.run_memory()

    def merge_run_memory(self, copies: list[dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
        return self.term.merge_run_memory(copies)

    def load_run_memory(self, memory: dict[str, np.ndarray]) -> None:
        self.term.load_run_memory(memory)


def checked_terms(terms: list[Any], phase: list[str]) -> list[Any]:
    """Wrap every term (per-env or batched) so each value it returns is checked."""
    return [
        CheckedBatchedTerm(t, phase)
        if isinstance(t, BatchedIntrinsicReward)
        else CheckedTerm(t, phase)
        for t in terms
    ]


class CheckedEvaluator:
    """Feeds a training and an evaluation evaluator the same steps; checks what they return."""

    def __init__(self, training: Any, evaluation: Any, phase: list[str]) -> None:
        self.training = training
        self.evaluation = evaluation
        self.phase = phase
        self.episodes = 0

    def record(self, ctx: Any) -> None:
        self.training.record(ctx)
        self.evaluation.record(ctx)

    def end_episode(self) -> dict[str, float]:
        self.episodes += 1
        out = {}
        for label, evaluator in (("training", self.training), ("evaluation", self.evaluation)):
            metrics = evaluator.end_episode()
            what = f"{label} evaluator's end_episode()"
            require(isinstance(metrics, dict), f"{what} must return a dict, got {metrics!r}")
            for key, value in metrics.items():
                require(isinstance(key, str), f"{what} has a non-string key {key!r}")
                value = check_number(value, f"{what} metric '{key}'", self.phase[0])
                if label == "training":
                    out[key] = value
        return out

    def episode_record(self) -> Any:
        """The training evaluator's record of the episode just ended (checked to pickle: it
        crosses from env workers to the runner)."""
        record = getattr(self.training, "episode_record", lambda: None)()
        if record is not None:
            problem = pickle_problem(record, "training evaluator's episode_record()")
            require(problem is None, f"{problem} (it crosses from env workers to the runner)")
        return record

    def summary(self) -> dict[str, Any]:
        return self.training.summary()


def check_summaries(checked: CheckedEvaluator) -> dict[str, Any]:
    """Check both evaluators' ``summary()`` is a JSON-serialisable dict; return the eval one."""
    result: dict[str, Any] = {}
    for label, evaluator in (("training", checked.training), ("evaluation", checked.evaluation)):
        summary = evaluator.summary()
        what = f"{label} evaluator's summary()"
        require(isinstance(summary, dict), f"{what} must return a dict, got {type(summary)}")
        problem = json_problem(summary, "summary()")
        require(problem is None, f"{what} is not JSON-serialisable: {problem}")
        result = summary
    return result


def place_hand_on_body(infant: Any, rng: np.random.Generator, tries: int = 200) -> bool:
    """Put the infant in a random pose where a hand touches its body (a scripted contact).

    Joint angles are drawn uniformly within their ranges until a hand (palm or fingers) is in
    contact with a body-map region and nothing penetrates deeper than 1 cm (so the next physics
    step does not fling the limbs apart).

    Returns:
        True if such a pose was found (the infant is left in it), else False.
    """
    index, ranges = infant._qpos_index, infant._ranges
    for _ in range(tries):
        infant.data.qpos[index] = rng.uniform(ranges[:, 0], ranges[:, 1])
        infant.data.qvel[:] = 0.0
        mujoco.mj_forward(infant.model, infant.data)
        infant._cache.clear()
        ncon = infant.data.ncon
        depth = float(-infant.data.contact.dist[:ncon].min()) if ncon else 0.0
        if depth < 0.01 and infant.hand_contacts().any():
            return True
    return False
