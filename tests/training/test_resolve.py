"""resolve_config(): one path for a fresh run, --resume, --from, --config, --preset and --set,
checked once, with errors that name the option; and Checkpoint, an opened checkpoint."""

from __future__ import annotations

import json

import numpy as np
import pytest
import tiny_run
import torch

from devlearn.api.errors import UsageError
from devlearn.config.resolve import RunRequest, resolve_config, resolve_run, write_config_file
from devlearn.config.run_config import to_dict
from devlearn.env import BehaviorEnv
from devlearn.testing.fake_infant import TinyBehavior
from devlearn.training import train
from devlearn.training.checkpoint import Checkpoint, checkpoint_config, observation_batch

REGISTRY = tiny_run.registry()


def resolve(*overrides: str, **fields) -> object:
    request = RunRequest("tiny", list(overrides), **fields)
    return resolve_config(request, REGISTRY, checkpoint_config)


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    """A tiny run of 64 steps (checkpoints at 32 and 64)."""
    out = tmp_path_factory.mktemp("source") / "run"
    cfg = tiny_run.config(out, 64, "behavior.target=0.7", seed=5)
    train(cfg, REGISTRY, infant_factory=tiny_run.factory, progress=False)
    return out


def test_fresh_layers_defaults_behaviour_top_then_overrides():
    cfg = resolve("ppo.learning_rate=1e-3", "seed=9", top={"seed": 4, "num_envs": None})
    defaults = TinyBehavior.about.train_defaults
    assert cfg.seed == 9  # --set comes last
    assert cfg.num_envs == 16  # None: not given
    assert cfg.ppo.learning_rate == 1e-3
    for key, value in defaults.items():  # the behaviour's own defaults, unless overridden
        section, _, name = key.partition(".")
        assert getattr(getattr(cfg, section), name) == value if name else cfg.seed == 9
    assert cfg.network.layout in ("shared", "separate")  # the behaviour's choice, recorded
    assert resolve(out_dir="runs/x").out_dir == "runs/x"


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"top": {"total_steps": 0}}, "--steps must be at least 1, got 0"),
        ({"top": {"seed": -1}}, "--seed must be an integer from 0"),
        ({"overrides": ["ppo.gamma=2"]}, r"ppo.gamma must be a finite number in \(0, 1\]"),
        ({"overrides": ["network.head=tanh"]}, "unknown network.head 'tanh'; valid: gaussian"),
        ({"overrides": ["ppo.lr=1"]}, "did you mean 'ppo.learning_rate'"),
        ({"preset": "nope"}, "unknown preset 'nope' for tiny"),
        ({"behavior": "tiyn"}, "tiyn"),
    ],
)
def test_every_value_is_checked_once_with_what_is_valid(fields, message):
    request = RunRequest(**{"behavior": "tiny", **fields})
    with pytest.raises(UsageError, match=message):
        resolve_config(request, REGISTRY)


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"resume": "r", "preset": "p"}, "--resume keeps the run's config"),
        ({"resume": "r", "start_from": "c.pt"}, "--resume keeps the run's config"),
        ({"resume": "r", "out_dir": "o"}, "--out and --resume exclude each other"),
        ({"start_from": "c.pt", "config_file": "f.json"}, "--from and --config exclude"),
        ({"config_file": "f.json", "preset": "p"}, "--preset does not apply"),
        ({"resume": "no/such/run"}, "run directory no/such/run does not exist"),
        ({"start_from": "no.pt"}, "checkpoint no.pt does not exist"),
        ({"config_file": "no.json"}, "cannot read no.json"),
        ({"saved": {}, "baseline": True}, "a saved config and a baseline exclude each other"),
        ({"resume": "r", "baseline": True}, "--resume and a baseline exclude each other"),
    ],
)
def test_options_that_exclude_each_other_or_name_nothing_are_refused(fields, message):
    with pytest.raises(UsageError, match=message):
        resolve_config(RunRequest("tiny", **fields), REGISTRY, checkpoint_config)


def test_only_a_start_from_needs_the_checkpoint_reader():
    # config sits below training: resolving reads no checkpoint unless --from asks, and then
    # through the reader the caller passes (so `devlearn config` loads no torch:
    # tests/cli/test_startup.py)
    with pytest.raises(TypeError, match="start_from needs read_checkpoint"):
        resolve_config(RunRequest("tiny", start_from="c.pt"), REGISTRY)


def test_resume_keeps_the_runs_config_and_seed(trained):
    cfg = resolve(resume=str(trained), top={"total_steps": 96})
    assert (cfg.total_steps, cfg.seed, cfg.behavior.target) == (96, 5, 0.7)
    assert resolve_config(RunRequest(resume=str(trained)), REGISTRY).seed == 5  # any behaviour
    with pytest.raises(UsageError, match="trained with seed 5, which a resumed run keeps"):
        resolve(resume=str(trained), top={"seed": 6})
    with pytest.raises(UsageError, match="trains 'tiny', not 'other'"):
        resolve_config(RunRequest("other", resume=str(trained)), REGISTRY)


def test_from_starts_with_the_checkpoints_config_then_preset_top_and_overrides(trained):
    source = str(trained / "checkpoint_32.pt")
    cfg = resolve("behavior.stage_steps=7", start_from=source, top={"seed": 8}, out_dir="b")
    assert (cfg.behavior.target, cfg.behavior.stage_steps, cfg.seed) == (0.7, 7, 8)
    assert (cfg.start_from, cfg.out_dir) == (source, "b")
    with pytest.raises(UsageError, match="trained for 'tiny', not 'other'"):
        resolve_config(RunRequest("other", start_from=source), REGISTRY, checkpoint_config)


def test_a_config_file_starts_a_run_with_exactly_its_config(tmp_path):
    direct = resolve("behavior.target=0.3", "torch_threads=1", top={"seed": 2, "num_envs": 4})
    path = write_config_file(direct, tmp_path / "run_config.json")
    again = resolve(config_file=str(path))
    assert to_dict(again) == to_dict(direct)
    moved = resolve("ppo.gamma=0.9", config_file=str(path), out_dir="elsewhere")
    assert (moved.out_dir, moved.ppo.gamma, moved.behavior.target) == ("elsewhere", 0.9, 0.3)
    with pytest.raises(UsageError, match="trains 'tiny', not 'other'"):
        resolve_config(RunRequest("other", config_file=str(path)), REGISTRY)
    path.write_text("[1, 2]")
    with pytest.raises(UsageError, match="is not a run config: it holds a JSON list"):
        resolve(config_file=str(path))
    saved = resolve_config(RunRequest("tiny", saved={}), REGISTRY)  # a config of old runs
    assert (saved.network.head, saved.ppo.normalize_rewards) == ("paper", False)


def test_checkpoint_opens_config_behaviour_and_actor(trained):
    opened = Checkpoint.open(trained / "checkpoint_latest.pt", REGISTRY, "tiny")
    assert (opened.behavior_name, opened.env_steps) == ("tiny", 64)
    assert opened.config.behavior.target == 0.7
    saved = json.loads((trained / "config.json").read_text())
    assert to_dict(opened.config) == saved
    behavior = opened.behavior()
    assert behavior is opened.behavior() and behavior.config.target == 0.7
    env = BehaviorEnv(behavior, 0, tiny_run.factory, training=False)
    try:
        obs = env.reset()
        actor = opened.actor(obs, env.action_dim)
    finally:
        env.close()
    weights = opened.state["actor_state_dict"]
    for key, value in actor.state_dict().items():
        assert torch.equal(value, weights[key])
    with torch.inference_mode():
        action = actor(observation_batch(obs))[0].numpy()
    assert action.shape == (env.action_dim,) and np.all(np.isfinite(action))
    with pytest.raises(UsageError, match="trained for 'tiny', not 'other'"):
        Checkpoint.open(trained / "checkpoint_latest.pt", REGISTRY, "other")


def test_a_run_trains_the_one_behaviour_resolving_built_and_checked(tmp_path, monkeypatch):
    # resolve_run builds the behaviour on the final config (after --set and the run-length
    # defaults) and the run trains that instance: train builds none of its own.
    request = RunRequest(
        "tiny",
        ["behavior.target=0.7"],
        top={"total_steps": 32, "num_envs": 4, "workers": 0, "save_interval": 1},
        out_dir=str(tmp_path / "run"),
    )
    resolved = resolve_run(request, REGISTRY)
    assert isinstance(resolved.behavior, TinyBehavior)
    assert resolved.behavior.config is resolved.cfg.behavior
    assert resolved.behavior.config.target == 0.7
    built: list[TinyBehavior] = []
    init = TinyBehavior.__init__

    def counted(self, config=None):
        built.append(self)
        init(self, config)

    monkeypatch.setattr(TinyBehavior, "__init__", counted)
    result = train(resolved, REGISTRY, infant_factory=tiny_run.factory, progress=False)
    assert result.env_steps == 32
    assert built == []
    # a bare config (resolve_config's) still trains: its behaviour is built from it
    cfg = resolve_config(
        RunRequest("tiny", top=request.top, out_dir=str(tmp_path / "two")), REGISTRY
    )
    built.clear()
    train(cfg, REGISTRY, infant_factory=tiny_run.factory, progress=False)
    assert len(built) == 1
