"""An evaluation as a request and its steps: the request checked when made, the subject opened
and its config resolved once, the conditions taken from what the contract declares
(``EvalProtocol.start``, ``Evaluator.mergeable``, the infant's ``start``), the measures and
the records apart."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

import devlearn
from devlearn.api.errors import UsageError
from devlearn.config.resolve import RunRequest, resolve_config
from devlearn.config.run_config import to_dict
from devlearn.evaluation import evaluate as evaluation_module
from devlearn.evaluation.evaluate import (
    EvalRequest,
    Evaluation,
    evaluation_conditions,
    open_subject,
)
from devlearn.testing import registry_for
from devlearn.testing.fake_infant import CloseEvaluator, FakeInfant, TinyBehavior


class Fixed(TinyBehavior):
    """Evaluated without random poses, from the infant's own start (declares no eval_start)."""

    name = "fixed"

    def evaluation(self) -> devlearn.EvalProtocol:
        return dataclasses.replace(super().evaluation(), stage={"random_pose": False})


class FromBabybench(Fixed):
    """Trains from rest, evaluates from BabyBench's start (as hand regard does)."""

    name = "from_babybench"

    def evaluation(self) -> devlearn.EvalProtocol:
        return dataclasses.replace(super().evaluation(), start="babybench")


class Unmerged(TinyBehavior):
    """An evaluator that cannot merge (the contract's default)."""

    name = "unmerged"

    def evaluation(self) -> devlearn.EvalProtocol:
        return dataclasses.replace(super().evaluation(), evaluator=lambda t: devlearn.Evaluator())


class Decisive(TinyBehavior):
    """A new run of it decides every 2 physics steps (a saved config without the key: 1)."""

    name = "decisive"

    about = dataclasses.replace(
        TinyBehavior.about,
        train_defaults={**TinyBehavior.about.train_defaults, "env.action_repeat": 2},
    )


class StartingInfant(FakeInfant):
    """A stand-in with the real infant's settable ``start``: keeps each episode's start."""

    start = "rest"
    taken: list[str] = []

    def reset(self, rng: np.random.Generator, random_pose: bool = False) -> None:
        StartingInfant.taken.append("random" if random_pose else self.start)
        super().reset(rng, random_pose)


def starting(scene: str, senses: Any = ("proprioception",), **kwargs: Any) -> StartingInfant:
    return StartingInfant(scene, senses, episode_steps=10)


@pytest.fixture(scope="module")
def registry():
    return registry_for(TinyBehavior, Fixed, FromBabybench, Unmerged, Decisive)


@pytest.mark.parametrize(
    "values, message",
    [
        ({"episodes": 0}, "--episodes must be at least 1, got 0"),
        ({"seed": -1}, "--seed must be at least 0, got -1"),
        ({"envs": 0}, "--envs must be at least 1, got 0"),
        ({"workers": -2}, "--workers must be at least 0, got -2"),
        ({"start": "sideways"}, "unknown start 'sideways'; valid: stage, babybench, rest, random"),
        ({"action": "max"}, "unknown action 'max'; valid: mean, sample"),
        ({"policy": "greedy"}, "unknown policy 'greedy'; valid: checkpoint, zero, random"),
        ({"action": "sample"}, "--action sample is a checkpoint's"),
        ({"checkpoint": "x.pt"}, "not both"),
    ],
)
def test_the_request_refuses_a_bad_protocol_value_in_one_line(values, message):
    with pytest.raises(UsageError, match=message) as err:
        EvalRequest("tiny", **{"policy": "zero", **values})
    assert "\n" not in str(err.value)


def test_a_checkpoints_request_takes_only_the_age():
    request = EvalRequest("tiny", "run/policy.pt", overrides=["infant.age_months=6"])
    assert request.ages == ["infant.age_months=6"] and request.overrides == ("infant.age_months=6",)
    with pytest.raises(UsageError, match="--set applies to baselines only"):
        EvalRequest("tiny", "run/policy.pt", overrides=["infant.age_months=6", "seed=7"])


def test_eval_start_is_declared_with_the_infants_own_start_as_default(registry):
    assert devlearn.Behavior.evaluation(TinyBehavior()).start is None
    fixed = open_subject(EvalRequest("fixed", policy="zero"), registry)
    own = evaluation_conditions(EvalRequest("fixed", policy="zero"), fixed)
    assert own.infant_start is None and own.stage == {"random_pose": False}
    declared = open_subject(EvalRequest("from_babybench", policy="zero"), registry)
    stage = evaluation_conditions(EvalRequest("from_babybench", policy="zero"), declared)
    assert stage.infant_start == "babybench" and stage.stage == {"random_pose": False}
    rest = evaluation_conditions(
        EvalRequest("from_babybench", policy="zero", start="rest"), declared
    )
    assert rest.infant_start == "rest"
    moved = evaluation_conditions(
        EvalRequest("from_babybench", policy="zero", start="random"), declared
    )
    assert moved.infant_start is None and moved.stage["random_pose"] is True


def test_episodes_play_from_the_declared_eval_start(registry):
    for name, start in (("fixed", "rest"), ("from_babybench", "babybench")):
        StartingInfant.taken = []
        request = EvalRequest(name, policy="zero", episodes=2)
        summary = Evaluation(request, registry, infant_factory=starting, progress=False).run()
        assert summary["start"] == summary["protocol"]["start"] == start
        assert StartingInfant.taken and set(StartingInfant.taken) == {start}


def test_a_fake_infant_declares_its_one_start():
    infant = FakeInfant("crib")
    assert infant.start == "rest"
    infant.start = "rest"
    with pytest.raises(ValueError, match="only rest"):
        infant.start = "babybench"


def test_an_evaluator_that_does_not_merge_plays_in_one_env(registry):
    assert not devlearn.Evaluator.mergeable and CloseEvaluator.mergeable
    many = {"policy": "zero", "episodes": 400, "envs": None, "workers": None}
    for name, parallel in (("tiny", True), ("unmerged", False)):
        request = EvalRequest(name, **many)
        conditions = evaluation_conditions(request, open_subject(request, registry), cores=4)
        assert (conditions.envs > 1) == parallel and (conditions.workers > 0) == parallel
    request = EvalRequest("unmerged", policy="zero", envs=2)
    with pytest.raises(UsageError, match="does not merge"):
        evaluation_conditions(request, open_subject(request, registry))


def test_a_baseline_resolves_its_config_once(registry, monkeypatch):
    calls = []

    def counted(request: RunRequest, registry: Any) -> Any:
        calls.append(request)
        return resolve_config(request, registry)

    monkeypatch.setattr(evaluation_module, "resolve_config", counted)
    subject = open_subject(EvalRequest("decisive", policy="zero", overrides=["seed=9"]), registry)
    assert len(calls) == 1
    # what a baseline always acted with: a saved config without values (1 decision per
    # physics step), at the decision rate of a new run (2), then --set
    assert subject.config.env.action_repeat == 2 and subject.config.seed == 9
    fresh = resolve_config(RunRequest("decisive"), registry)
    saved = RunRequest("decisive", ["env.action_repeat=2", "seed=9"], saved={})
    assert fresh.env.action_repeat == 2
    assert to_dict(subject.config) == to_dict(resolve_config(saved, registry))
    assert subject.policy.path is None and subject.policy.name == "zero"
    assert subject.trained_steps == 0
    assert subject.stage_steps == subject.config.total_steps


def test_measures_record_the_protocol_apart_from_playing(registry):
    request = EvalRequest("decisive", policy="random", episodes=3, seed=4, start="rest")
    evaluation = Evaluation(request, registry, progress=False)
    subject = open_subject(request, registry)
    conditions = evaluation_conditions(request, subject)
    summary = evaluation.measures(subject, conditions, CloseEvaluator(0.5), "rest")
    protocol = summary["protocol"]
    assert (protocol["episodes"], protocol["seed"], protocol["action"]) == (3, 4, "random")
    assert protocol["start_option"] == "rest" and protocol["action_repeat"] == 2
    assert summary["checkpoint"] is None and summary["config"]["env"]["action_repeat"] == 2
    assert summary["episodes"] == 0  # the evaluator's own summary, nothing played
