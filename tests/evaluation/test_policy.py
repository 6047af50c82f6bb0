"""One Policy for every kind an evaluation plays (issue #59): a checkpoint, another learner's
scripted policy and the baselines answer the same questions, and their actions act on batches
of observations with the draws of one env acting in order."""

from __future__ import annotations

import numpy as np
import pytest
import torch

import devlearn.gym
from devlearn.api.errors import UsageError
from devlearn.config.resolve import RunRequest, resolve_config
from devlearn.config.run_config import to_dict
from devlearn.env.behavior_env import BehaviorEnv
from devlearn.evaluation.evaluate import EvalRequest, open_subject
from devlearn.evaluation.policy import (
    HOLD_STEPS,
    Baseline,
    CheckpointPolicy,
    HeldActions,
    UniformActions,
    batch_of_one,
)
from devlearn.evaluation.scripted_policy import ScriptedPolicy
from devlearn.gym.env import DevlearnEnv
from devlearn.testing import registry_for
from devlearn.testing.fake_infant import TinyBehavior, fake_infant_factory
from devlearn.testing.runs import policy_file, policy_network, save_checkpoint

REGISTRY = registry_for(TinyBehavior)


class Reach(torch.nn.Module):
    """Moves every joint toward 0.5: the action 5 * (0.5 - position), clipped."""

    def forward(self, proprioception: torch.Tensor) -> torch.Tensor:
        return torch.clamp(5.0 * (0.5 - proprioception), -1.0, 1.0)


@pytest.fixture()
def first_obs():
    env = BehaviorEnv(TinyBehavior(), 0, fake_infant_factory, training=False)
    try:
        yield env.reset(), env.action_dim
    finally:
        env.close()


@pytest.fixture()
def checkpoint(tmp_path, first_obs):
    """A policy file of the tiny behaviour that trained 96 physics steps at 9 months."""
    obs, action_dim = first_obs
    cfg = resolve_config(RunRequest("tiny", ["seed=6"]), REGISTRY)
    behavior = REGISTRY.create("tiny", cfg.behavior)
    torch.manual_seed(0)
    actor = policy_network(cfg, behavior, obs, action_dim)
    state = policy_file(to_dict(cfg), behavior, actor.state_dict(), env_steps=96)
    state["age_months"] = 9.0
    save_checkpoint(state, tmp_path / "policy.pt")
    return tmp_path / "policy.pt"


@pytest.fixture()
def scripted(tmp_path):
    env = DevlearnEnv("tiny", {"seed": 4}, registry=REGISTRY, infant_factory=fake_infant_factory)
    try:
        return devlearn.gym.save_policy(
            Reach(), env, tmp_path / "reach.pt", learner="mine", env_steps=40
        )
    finally:
        env.close()


def test_every_kind_answers_what_an_evaluation_asks(checkpoint, scripted):
    ours = open_subject(EvalRequest("tiny", checkpoint), REGISTRY).policy
    theirs = open_subject(EvalRequest("tiny", scripted), REGISTRY).policy
    zero = open_subject(EvalRequest("tiny", policy="zero"), REGISTRY).policy
    assert isinstance(ours, CheckpointPolicy) and isinstance(theirs, ScriptedPolicy)
    assert (ours.name, ours.path, ours.learner) == ("checkpoint", checkpoint, None)
    assert (theirs.name, theirs.path, theirs.learner) == ("checkpoint", scripted, "mine")
    assert (zero.name, zero.path, zero.learner) == ("zero", None, None)
    assert (ours.env_steps, theirs.env_steps, zero.env_steps) == (96, 40, None)
    assert (ours.age_months, zero.age_months) == (9.0, None)
    assert ours.config.seed == 6 and theirs.config.seed == 4
    assert ours.saved_config["seed"] == 6 and theirs.saved_config["seed"] == 4
    assert zero.saved_config == to_dict(zero.config)
    for policy in (ours, theirs, zero):
        assert policy.behavior() is policy.behavior()  # built once
        assert policy.behavior().name == "tiny"


def test_a_file_that_does_not_say_its_steps_is_judged_at_the_end_of_its_config(
    checkpoint, tmp_path
):
    state = torch.load(checkpoint, weights_only=True)
    del state["env_steps"]
    save_checkpoint(state, tmp_path / "stepless.pt")
    subject = open_subject(EvalRequest("tiny", tmp_path / "stepless.pt"), REGISTRY)
    assert subject.policy.env_steps is None and subject.trained_steps == 0
    assert subject.stage_steps == subject.config.total_steps
    with_steps = open_subject(EvalRequest("tiny", checkpoint), REGISTRY)
    assert with_steps.trained_steps == with_steps.stage_steps == 96


def test_actions_act_on_a_batch_of_observations(checkpoint, scripted, first_obs):
    obs, action_dim = first_obs
    rows = {k: np.stack([v, v * 0.5, v + 0.25]) for k, v in obs.items()}
    ours = CheckpointPolicy.open(checkpoint, REGISTRY, "tiny")
    network = ours.actions(batch_of_one(obs), action_dim, seed=0, action="mean")
    three = ours.actions(rows, action_dim, seed=0, action="mean")
    together = three.act(rows)
    assert together.shape == (3, action_dim)
    for i in range(3):
        alone = network.act({k: v[i : i + 1] for k, v in rows.items()})
        assert alone.shape == (1, action_dim)
        np.testing.assert_allclose(alone[0], together[i], atol=1e-6)
    theirs = ScriptedPolicy.open(scripted, REGISTRY, "tiny")
    acted = theirs.actions(rows, action_dim, seed=0, action="mean").act(rows)
    expected = np.clip(5 * (0.5 - rows["proprioception"]), -1, 1)
    np.testing.assert_allclose(acted, expected, atol=1e-6)
    assert theirs.act(obs) == pytest.approx(expected[0], abs=1e-6)
    with pytest.raises(UsageError, match="a scripted policy .* gives one deterministic action"):
        theirs.actions(rows, action_dim, seed=0, action="sample")
    cfg = resolve_config(RunRequest("tiny", ["env.action_repeat=2"]), REGISTRY)
    for name in ("zero", "random", "held_random"):
        actions = Baseline(name, cfg, TinyBehavior()).actions(rows, action_dim, 3, "mean")
        acted = actions.act(rows)
        assert acted.shape == (3, action_dim) and np.all(np.abs(acted) <= 1)
        assert np.any(acted != 0) == (name != "zero")


def test_the_baselines_draw_as_one_env_did(first_obs):
    """Seeded by the evaluation seed, on streams apart from the env's: uniform [seed, 1], held
    [seed, 2] with a redraw chance of repeat / HOLD_STEPS per decision."""
    obs, action_dim = first_obs
    one = batch_of_one(obs)
    uniform = UniformActions(1, action_dim, 5)
    rng = np.random.default_rng([5, 1])
    for _ in range(3):
        assert np.array_equal(uniform.act(one)[0], rng.uniform(-1.0, 1.0, action_dim))
    held = HeldActions(1, action_dim, 5, repeat=2)
    rng = np.random.default_rng([5, 2])
    expected = rng.uniform(-1.0, 1.0, action_dim)
    for _ in range(4):
        redraw = rng.random(action_dim) < 2 / HOLD_STEPS
        expected[redraw] = rng.uniform(-1.0, 1.0, int(redraw.sum()))
        assert np.array_equal(held.act(one)[0], expected)


@pytest.mark.parametrize("name", ["random", "held_random", "sample"])
def test_skipping_draws_what_acting_would(name, checkpoint, first_obs):
    """A slot starting later skips the decisions before it: its next action is the one the
    reference (one env acting every decision) takes there."""
    obs, action_dim = first_obs
    one = batch_of_one(obs)
    if name == "sample":
        policy = CheckpointPolicy.open(checkpoint, REGISTRY, "tiny")
        torch.manual_seed(2)
        reference = policy.actions(one, action_dim, seed=2, action="sample")
        slot = reference.for_slot()
    else:
        cfg = resolve_config(RunRequest("tiny", ["env.action_repeat=2"]), REGISTRY)
        reference = Baseline(name, cfg, TinyBehavior()).actions(one, action_dim, 2, "mean")
        slot = reference.for_slot()
    for _ in range(5):
        reference.act(one)
    slot.skip(5)
    assert slot.rng_state() is not None
    assert slot.rng_state() == reference.rng_state()
    assert np.array_equal(slot.act(one), reference.act(one))


def test_a_baseline_is_one_of_the_named_ones():
    cfg = resolve_config(RunRequest("tiny"), REGISTRY)
    with pytest.raises(ValueError, match="unknown baseline 'greedy'; valid: zero, random"):
        Baseline("greedy", cfg, TinyBehavior())


def fixed_mean_policy(path, first_obs, mean):
    """A policy file of the tiny behaviour whose network's mean is ``mean`` whatever it sees
    (its last layer's weights zero, its bias ``mean``)."""
    obs, action_dim = first_obs
    cfg = resolve_config(RunRequest("tiny", ["seed=6"]), REGISTRY)
    behavior = REGISTRY.create("tiny", cfg.behavior)
    actor = policy_network(cfg, behavior, obs, action_dim)
    with torch.no_grad():
        actor.mlp[-1].weight.zero_()
        actor.mlp[-1].bias.copy_(torch.tensor(mean))
    save_checkpoint(policy_file(to_dict(cfg), behavior, actor.state_dict(), env_steps=96), path)
    return path


@pytest.mark.parametrize("sample", [False, True])
def test_an_evaluation_says_where_the_mean_action_sits_past_the_bounds(
    tmp_path, first_obs, sample
):
    """Issue #54: a mean past the action bounds plays the bound, and was unseen in eval.json
    (hand regard's CNN seed 1: 64% of components). A network whose mean is 3, -3 and 0 on its
    three actions, whatever it sees, has two thirds of its mean at the bounds; eval.json says
    so under ``policy_figures.mean_at_bound``, with the mean action and beside sampled ones."""
    from devlearn.evaluation.evaluate import Evaluation

    obs, action_dim = first_obs
    assert action_dim == 3
    fixed_mean_policy(tmp_path / "policy.pt", first_obs, [3.0, -3.0, 0.0])
    request = EvalRequest(
        "tiny",
        tmp_path / "policy.pt",
        episodes=2,
        action="sample" if sample else "mean",
        out_dir=tmp_path / "eval",
    )
    summary = Evaluation(request, REGISTRY, infant_factory=fake_infant_factory).run()
    assert summary["policy_figures"]["mean_at_bound"] == pytest.approx(2 / 3)
    import json

    saved = json.loads((tmp_path / "eval" / "eval.json").read_text())
    assert saved["policy_figures"]["mean_at_bound"] == pytest.approx(2 / 3)
    zero = EvalRequest("tiny", policy="zero", episodes=2)
    assert saved["policy"] == "checkpoint"  # the policy's name stays
    baseline = Evaluation(zero, REGISTRY, infant_factory=fake_infant_factory).run()
    assert "policy_figures" not in baseline


def test_an_evaluation_says_when_the_mean_action_ends_still(tmp_path, first_obs, capsys):
    """Issue #54 item 3: hand_to_mouth's mean action held a posture it never left in 16 of 30
    random-pose episodes (its noise moved the arm out in training), and eval.json did not
    say so. A network whose mean is 0 whatever it sees holds the point still; its sampled
    actions (spread 1) move it: eval.json's ``policy_figures.ends_still`` is 1 and 0, with
    ``end_speed`` the point's mean speed over the episode's last second, and the printed
    summary names the stall."""
    from devlearn.cli.evaluate import human_summary
    from devlearn.evaluation.evaluate import Evaluation

    fixed_mean_policy(tmp_path / "policy.pt", first_obs, [0.0, 0.0, 0.0])
    figures = {}
    for action in ("mean", "sample"):
        request = EvalRequest("tiny", tmp_path / "policy.pt", episodes=2, action=action)
        summary = Evaluation(request, REGISTRY, infant_factory=fake_infant_factory).run()
        figures[action] = summary["policy_figures"]
        if action == "mean":
            text = "\n".join(human_summary(summary, "", {}, None))
            assert "100% of episodes end with the body still" in text
            assert "compare --action sample" in text
    assert figures["mean"]["ends_still"] == 1.0 and figures["mean"]["end_speed"] == 0.0
    # a step of 0.1 * N(0, 1) per 5 ms: ~16 units a second, far above the threshold
    assert figures["sample"]["ends_still"] == 0.0 and figures["sample"]["end_speed"] > 5.0
    zero = EvalRequest("tiny", policy="zero", episodes=2)
    assert "policy_figures" not in Evaluation(zero, REGISTRY, fake_infant_factory).run()


def test_the_expected_clipped_action_is_the_mean_of_the_clipped_samples():
    """``--action expected_clipped`` plays E[clip(mean + std * noise, -1, 1)] (issue #40's seed
    1: its mean past the bounds played them, where training's clipped samples did not)."""
    from devlearn.evaluation.policy import expected_clipped

    mu = torch.tensor([0.0, 2.0, -3.0, 0.5, 0.9, 5.0])
    sigma = torch.tensor([1.0, 0.5, 2.0, 0.1, 3.0, 0.01])
    draws = mu + sigma * torch.randn(400_000, 6, generator=torch.Generator().manual_seed(0))
    monte_carlo = draws.clamp(-1.0, 1.0).mean(dim=0)
    exact = expected_clipped(mu, sigma)
    torch.testing.assert_close(exact, monte_carlo, atol=4e-3, rtol=0)
    assert exact[0] == pytest.approx(0.0, abs=1e-6) and exact[5] == pytest.approx(1.0)
    assert 0.9 < exact[1] < 1.0  # a mean past the bound plays less than the bound


def test_an_evaluation_plays_the_expected_clipped_action(tmp_path, first_obs, scripted):
    from devlearn.evaluation.evaluate import Evaluation

    obs, action_dim = first_obs
    fixed_mean_policy(tmp_path / "p.pt", first_obs, [3.0, -1.5, 0.2])
    ours = CheckpointPolicy.open(tmp_path / "p.pt", REGISTRY, "tiny")
    played = {
        action: ours.actions(batch_of_one(obs), action_dim, 0, action).act(batch_of_one(obs))[0]
        for action in ("mean", "expected_clipped")
    }
    np.testing.assert_allclose(played["mean"], [1.0, -1.0, 0.2], atol=1e-6)
    assert 0 < played["expected_clipped"][0] < 1 and -1 < played["expected_clipped"][1] < 0
    assert 0 < played["expected_clipped"][2] < 0.2  # a mean inside: pulled in by both bounds
    request = EvalRequest("tiny", tmp_path / "p.pt", episodes=2, action="expected_clipped")
    summary = Evaluation(request, REGISTRY, infant_factory=fake_infant_factory).run()
    assert summary["protocol"]["action"] == "expected_clipped"
    with pytest.raises(UsageError, match="--action expected_clipped: a scripted policy"):
        open_subject(EvalRequest("tiny", scripted, action="expected_clipped"), REGISTRY)
