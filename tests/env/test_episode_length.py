"""How long an episode lasts, in simulated seconds (issue #57): the infant's 5 s, a behaviour's
``episode_seconds``, or an evaluation's session (``EnvSettings.episode_seconds``)."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest

import devlearn
from devlearn.api.errors import UsageError
from devlearn.env import BehaviorEnv, EnvSettings
from devlearn.evaluation.evaluate import EvalRequest, Evaluation
from devlearn.testing import registry_for
from devlearn.testing.fake_infant import TinyBehavior, fake_infant_factory
from devlearn.timing import physics_steps

factory = functools.partial(fake_infant_factory, episode_steps=10)  # 0.05 s of 5 ms steps


class Tenth(TinyBehavior):
    """Episodes of a tenth of a second (20 physics steps of the fake infant's 5 ms)."""

    name = "tenth"

    def episode(self) -> devlearn.EpisodeSpec:
        return dataclasses.replace(super().episode(), seconds=0.1)


class StepsEvaluator(devlearn.Evaluator):
    """Counts the steps of every episode."""

    mergeable = True

    def __init__(self) -> None:
        self.steps, self.episodes = 0, []

    def record(self, ctx: devlearn.StepContext) -> None:
        self.steps += 1

    def end_episode(self) -> dict[str, float]:
        self.episodes.append(self.steps)
        self.steps = 0
        return {"steps": float(self.episodes[-1])}

    def summary(self) -> dict:
        return {"episode_steps": self.episodes}

    def merge(self, later: devlearn.Evaluator) -> None:
        assert isinstance(later, StepsEvaluator)
        self.episodes += later.episodes


class Counted(TinyBehavior):
    """The tiny behaviour at a decision every 5 physics steps, its evaluator counting each
    episode's physics steps."""

    name = "counted"

    about = dataclasses.replace(
        TinyBehavior.about,
        train_defaults={**TinyBehavior.about.train_defaults, "env.action_repeat": 5},
    )

    def evaluation(self) -> devlearn.EvalProtocol:
        return devlearn.EvalProtocol(evaluator=lambda training: StepsEvaluator())


def steps_until_reset(env: BehaviorEnv) -> int:
    """Physics steps of one episode, from a reset to the step that ends it."""
    env.reset()
    for decision in range(1, 10_000):
        *_, done, _, info = env.step(np.zeros(env.action_dim))
        if done:
            assert info is not None
            return decision * env.action_repeat
    raise AssertionError("the episode never ended")


def test_seconds_are_physics_steps():
    assert physics_steps(300) == 60_000 and physics_steps(5.0) == 1000
    assert physics_steps(0.05) == 10 and physics_steps(1.0, 0.0025) == 400
    with pytest.raises(ValueError, match="0.0123 s is not a whole number of physics steps"):
        physics_steps(0.0123)
    with pytest.raises(ValueError, match="the nearest: 0.005 s"):
        physics_steps(0.001)


def test_the_infant_a_behaviour_and_a_session_set_the_episode_length():
    assert steps_until_reset(BehaviorEnv(TinyBehavior(), 0, factory)) == 10  # the infant's
    assert steps_until_reset(BehaviorEnv(Tenth(), 0, factory)) == 20  # the behaviour's 0.1 s
    session = EnvSettings(action_repeat=5, episode_seconds=0.25)  # overrides both
    for behavior in (TinyBehavior(), Tenth()):
        env = BehaviorEnv(behavior, 0, factory, settings=session)
        assert env.episode_steps == 50 and steps_until_reset(env) == 50


def test_an_episode_must_be_whole_decisions():
    with pytest.raises(ValueError, match="episode_seconds must be above 0"):
        EnvSettings(episode_seconds=0.0)
    with pytest.raises(UsageError, match="the evaluation's session: 0.0123 s is not a whole"):
        BehaviorEnv(TinyBehavior(), 0, factory, settings=EnvSettings(1, 0.0123))
    with pytest.raises(ValueError, match="action_repeat=5 must divide the episode \\(4 physics"):
        BehaviorEnv(TinyBehavior(), 0, factory, settings=EnvSettings(5, 0.02))


def test_an_evaluation_session_is_one_episode_without_a_reset():
    registry = registry_for(Counted)

    def evaluate(episodes, **options):
        request = EvalRequest(
            "counted", episodes=episodes, policy="random", start="rest", **options
        )
        return Evaluation(request, registry, infant_factory=factory, progress=False).run()

    plain = evaluate(2)
    assert plain["episode_steps"] == [10, 10] and plain["protocol"]["session_s"] is None
    session = evaluate(2, session=0.5)
    assert session["episode_steps"] == [100, 100]  # 0.5 s of 5 ms steps each, no reset
    assert session["protocol"]["session_s"] == 0.5
    assert session["episode_metrics"] == [{"steps": 100.0}, {"steps": 100.0}]
    in_two_envs = evaluate(2, session=0.5, envs=2)
    assert in_two_envs["episode_steps"] == [100, 100]
    with pytest.raises(UsageError, match="--session 0.02: env.action_repeat=5 must divide"):
        evaluate(1, session=0.02)
    with pytest.raises(UsageError, match="--session must be above 0 seconds"):
        evaluate(1, session=-1.0)
