"""``devlearn eval --envs N --workers W``: the episodes of one env playing them in order, played
in several envs (in process and in worker processes), for a checkpoint's mean and sampled
actions and the baselines; the guard against behaviours whose episodes cannot be split; the
automatic envs and workers."""

from __future__ import annotations

import dataclasses
import functools
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import devlearn
from devlearn.api.errors import UsageError
from devlearn.config.resolve import RunRequest, resolve_config
from devlearn.evaluation.evaluate import EvalRequest, Evaluation, parallelism
from devlearn.testing import registry_for
from devlearn.testing.fake_infant import FakeInfant, TinyBehavior, fake_infant_factory
from devlearn.training.train import train

EPISODE_STEPS = 12
factory = functools.partial(fake_infant_factory, episode_steps=EPISODE_STEPS)


class PathEvaluator(devlearn.Evaluator):
    """Per episode: the mean and last position of the point (they differ with every start and
    every action, so an episode played otherwise shows); summary: their list and mean."""

    mergeable = True  # merge() below: devlearn eval may play its episodes in several envs

    def __init__(self) -> None:
        self.episodes: list[dict[str, float]] = []
        self.positions: list[np.ndarray] = []

    def record(self, ctx: devlearn.StepContext) -> None:
        self.positions.append(np.array(ctx.observations["proprioception"], dtype=np.float64))

    def end_episode(self) -> dict[str, float]:
        path = np.array(self.positions)
        metrics = {"mean": float(path.mean()), "last": float(path[-1].sum())}
        self.episodes.append(metrics)
        self.positions = []
        return metrics

    def summary(self) -> dict[str, Any]:
        means = [e["mean"] for e in self.episodes]
        return {
            "episodes": len(self.episodes),
            "path": self.episodes,
            "mean": float(np.mean(means)),
        }

    def merge(self, later: devlearn.Evaluator) -> None:
        assert isinstance(later, PathEvaluator)
        self.episodes += later.episodes


class Drift(TinyBehavior):
    """The tiny behaviour, evaluated from random poses by :class:`PathEvaluator`."""

    name = "drift"

    def evaluation(self) -> devlearn.EvalProtocol:
        return devlearn.EvalProtocol(
            evaluator=lambda training: PathEvaluator(), stage={"random_pose": True}
        )


class RngDraws(devlearn.EpisodeHooks):
    """Keeps the env's generator at every episode start and draws from it on every action."""

    def on_episode_start(self, infant: Any, rng: np.random.Generator) -> None:
        self.rng = rng

    def process_action(self, action: np.ndarray, stage: dict[str, Any]) -> np.ndarray:
        return action + self.rng.normal(0.0, 0.1, action.shape)


class StepDraws(Drift):
    """Draws from the env's generator during episodes (against the contract parallel
    evaluation rests on): its episodes depend on the ones played before in the same env."""

    name = "step_draws"

    def episode(self) -> devlearn.EpisodeSpec:
        return dataclasses.replace(super().episode(), hooks=RngDraws())


class Unmerged(Drift):
    """An evaluator that cannot merge (the contract's default)."""

    name = "unmerged"

    def evaluation(self) -> devlearn.EvalProtocol:
        return dataclasses.replace(super().evaluation(), evaluator=lambda t: devlearn.Evaluator())


class CountingInfant(FakeInfant):
    """Counts every physics step of every infant of this process."""

    steps = 0

    def step(self, action: np.ndarray) -> None:
        CountingInfant.steps += 1
        super().step(action)


def counting(scene: str, senses: Any = ("proprioception",), **kwargs: Any) -> CountingInfant:
    return CountingInfant(scene, senses, episode_steps=EPISODE_STEPS)


@pytest.fixture(scope="module")
def registry():
    return registry_for(Drift, StepDraws, Unmerged)


@pytest.fixture(scope="module")
def checkpoint(registry, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("drift") / "run"
    settings = ["total_steps=96", "num_envs=2", "workers=0", "seed=3", f"out_dir={out}"]
    train(resolve_config(RunRequest("drift", settings), registry), registry, infant_factory=factory)
    return out / "checkpoint_latest.pt"


def played(registry, checkpoint, policy, action="mean", episodes=7, **where) -> dict:
    request = EvalRequest(
        "drift",
        checkpoint if policy == "checkpoint" else None,
        episodes=episodes,
        seed=5,
        policy=policy,
        action=action,
        **where,
    )
    summary = Evaluation(request, registry, infant_factory=factory, progress=False).run()
    assert summary.pop("execution")["envs"] == where.get("envs", 1)
    return summary


POLICIES = [("checkpoint", "mean"), ("checkpoint", "sample"), ("random", "mean")]
POLICIES += [("held_random", "mean")]


@pytest.mark.parametrize(("policy", "action"), POLICIES)
def test_envs_in_process_play_the_episodes_of_one_env(registry, checkpoint, policy, action):
    one = played(registry, checkpoint, policy, action)
    means = [e["mean"] for e in one["episode_metrics"]]
    assert len(means) == 7 and len(set(means)) == 7  # every episode its own
    for envs in (2, 3, 7):  # runs of 4+3, 3+2+2 and 1 episode per env
        assert played(registry, checkpoint, policy, action, envs=envs) == one


@pytest.mark.slow
@pytest.mark.parametrize(("policy", "action"), [("checkpoint", "sample"), ("random", "mean")])
def test_worker_processes_play_the_episodes_of_one_env(registry, checkpoint, policy, action):
    one = played(registry, checkpoint, policy, action)
    assert played(registry, checkpoint, policy, action, envs=3, workers=2) == one


def test_no_episode_is_played_beyond_the_count(registry, checkpoint, monkeypatch):
    monkeypatch.setattr("devlearn.env.behavior_env.build_default_infant", counting)
    CountingInfant.steps = 0
    summary = Evaluation(
        EvalRequest("drift", checkpoint, episodes=5, envs=3), registry, progress=False
    ).run()
    assert summary["episodes"] == len(summary["episode_metrics"]) == 5
    # the one env that builds the network takes no step; the envs play 2 + 2 + 1 episodes
    assert CountingInfant.steps == 5 * EPISODE_STEPS


def test_a_behaviour_drawing_during_episodes_is_refused_in_several_envs(registry):
    def run(envs):
        return Evaluation(
            EvalRequest("step_draws", episodes=4, policy="zero", envs=envs),
            registry,
            infant_factory=factory,
            progress=False,
        ).run()

    assert run(1)["episodes"] == 4
    with pytest.raises(UsageError, match="evaluate it with --envs 1"):
        run(2)


def test_an_evaluator_that_does_not_merge_plays_in_one_env(registry):
    def run(envs, workers):
        return Evaluation(
            EvalRequest("unmerged", episodes=20, policy="zero", envs=envs, workers=workers),
            registry,
            infant_factory=factory,
            progress=False,
        ).run()

    execution = run(None, None)["execution"]
    assert (execution["envs"], execution["workers"]) == (1, 0)
    with pytest.raises(UsageError, match="does not merge"):
        run(2, 0)


def test_automatic_envs_and_workers():
    assert parallelism(100, None, None, True, cores=2) == (8, 2)  # 4 envs per worker
    assert parallelism(10, None, None, True, cores=2) == (1, 0)  # too few to repay workers
    assert parallelism(100, None, None, True, cores=1) == (1, 0)
    assert parallelism(3, 8, 4, True, cores=2) == (3, 3)  # never more envs than episodes
    assert parallelism(100, 1, 2, True, cores=2) == (1, 0)  # one env plays in process
    assert parallelism(100, None, 0, True, cores=2) == (1, 0)
    assert parallelism(100, 2, None, True, cores=2) == (2, 2)
    assert parallelism(100, None, None, False, cores=2) == (1, 0)
