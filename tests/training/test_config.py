"""RunConfig: overrides with type conversion, clear errors, save/load and rsl-rl's train_cfg."""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any, ClassVar

import pytest
import tiny_run

from devlearn.api.behavior import BehaviorConfig
from devlearn.api.errors import UsageError
from devlearn.config.run_config import (
    RunConfig,
    from_dict,
    to_dict,
    to_rsl_rl,
)
from devlearn.config.values import apply_overrides, valid_keys
from devlearn.testing import run_config
from devlearn.testing.fake_infant import TinyBehavior, TinyConfig


def test_every_field_is_documented():
    import ast
    import inspect

    from devlearn.config import run_config as config

    tree = ast.parse(inspect.getsource(config))
    for node in (n for n in tree.body if isinstance(n, ast.ClassDef)):
        body = node.body
        for i, item in enumerate(body):
            if isinstance(item, ast.AnnAssign):
                doc = body[i + 1] if i + 1 < len(body) else None
                assert isinstance(doc, ast.Expr) and isinstance(doc.value, ast.Constant), (
                    f"{node.name}.{item.target.id} has no docstring"
                )


def test_overrides_convert_to_field_types():
    cfg = RunConfig(behavior_name="tiny", behavior=TinyConfig())
    apply_overrides(
        cfg,
        [
            "ppo.learning_rate=3e-4",
            "total_steps=1e6",
            "behavior.use_eyes=true",
            "behavior.stage_steps=1000",
            "ppo.desired_kl=none",
            "device=cuda",
        ],
    )
    assert cfg.ppo.learning_rate == 3e-4 and isinstance(cfg.ppo.learning_rate, float)
    assert cfg.total_steps == 1_000_000 and isinstance(cfg.total_steps, int)
    assert cfg.behavior.use_eyes is True
    assert cfg.behavior.stage_steps == 1000
    assert cfg.ppo.desired_kl is None
    assert cfg.device == "cuda"


def test_sequence_fields_convert():
    from dataclasses import dataclass, field

    @dataclass
    class Seq:
        dims: tuple[int, ...] = (1,)
        """Dims."""
        names: list[str] = field(default_factory=list)
        """Names."""

    cfg = RunConfig(behavior=Seq())
    apply_overrides(cfg, ["behavior.dims=64,32", 'behavior.names=["a", "b"]'])
    assert cfg.behavior.dims == (64, 32)
    assert cfg.behavior.names == ["a", "b"]


@pytest.mark.parametrize(
    "override, message",
    [
        ("ppo.learnin_rate=1", "key 'ppo.learnin_rate'; did you mean 'ppo.learning_rate'?"),
        ("learning_rate=1", "did you mean 'ppo.learning_rate'?"),
        ("behavior.stage_step=1", "did you mean 'behavior.stage_steps'?"),
        ("behavior.nope=1", "unknown config key 'behavior.nope'; behavior keys: behavior.target,"),
        ("ppo.clip=1", "did you mean 'ppo.clip_param'?"),
        ("bogus=1", "unknown config key 'bogus' (`devlearn config tiny` lists all"),
        ("ppo=1", "config key 'ppo' is a section; set one of its keys, e.g. ppo.learning_rate"),
        ("ppo.num_mini_batches=two", "bad value 'two' for ppo.num_mini_batches: expected int ("),
        ("num_envs=abc", "bad value 'abc' for num_envs: expected int (a whole number"),
        ("total_steps=1.5", "for total_steps: expected int"),
        ("ppo.desired_kl=abc", "expected float (a number, e.g. 3e-4) or none"),
        ("behavior.use_eyes=maybe", "expected bool (true or false)"),
        ("seed", "override 'seed' must look like key=value"),
    ],
)
def test_override_errors_are_clear(override, message):
    cfg = RunConfig(behavior_name="tiny", behavior=TinyConfig())
    with pytest.raises(UsageError) as info:
        apply_overrides(cfg, [override])
    assert message in str(info.value)
    assert "could not convert" not in str(info.value) and len(str(info.value)) < 160


def test_precedence_defaults_behaviour_cli_set():
    cfg = run_config(TinyBehavior, ["ppo.num_mini_batches=4"], num_envs=3, seed=None)
    assert cfg.ppo.num_steps_per_env == 8  # from TinyBehavior.about.train_defaults
    assert cfg.ppo.num_mini_batches == 4  # --set beats train_defaults
    assert cfg.num_envs == 3 and cfg.seed == 0
    assert "ppo.clip_param" in valid_keys(cfg)
    assert cfg.ppo.clip_param == 0.2  # paper, sec. II-A5


def test_dict_round_trip_through_json():
    cfg = run_config(TinyBehavior, ["behavior.target=0.25", "ppo.desired_kl=none"])
    data = json.loads(json.dumps(to_dict(cfg)))
    again = from_dict(data, TinyBehavior)
    assert again == cfg
    with pytest.raises(UsageError, match="unknown config key 'ppo.bogus'"):
        from_dict({**data, "ppo": {**data["ppo"], "bogus": 1}}, TinyBehavior)


@dataclass
class LegacyTinyConfig(TinyConfig, BehaviorConfig):
    """The tiny config after its ``target`` default changed: old runs trained with 0.9."""

    LEGACY_DEFAULTS: ClassVar[dict[str, Any]] = {"target": 0.9}


class LegacyTiny(TinyBehavior):
    config_class = LegacyTinyConfig


def test_legacy_defaults_fill_fields_an_old_saved_config_lacks():
    # A field added after a run was saved: that run loads with the legacy value its config
    # class declares (BehaviorConfig.LEGACY_DEFAULTS), a run saved with the field keeps its
    # own, a config without a behaviour section and a new run's config file get defaults.
    data = to_dict(run_config(LegacyTiny, ["behavior.target=0.25"]))
    assert from_dict(data, LegacyTiny).behavior.target == 0.25
    del data["behavior"]["target"]
    assert from_dict(data, LegacyTiny).behavior.target == 0.9
    new_run = from_dict(data, LegacyTiny, run_config(LegacyTiny))  # filling a fresh config
    assert new_run.behavior.target == TinyConfig().target
    assert from_dict({}, LegacyTiny).behavior.target == TinyConfig().target


def test_to_rsl_rl():
    cfg = tiny_run.config("unused")
    behavior = TinyBehavior(cfg.behavior)
    train_cfg = to_rsl_rl(cfg, behavior)
    alg = train_cfg["algorithm"]
    assert alg["class_name"] == "devlearn.training.ppo:UniqueParamPPO"
    assert alg["clip_param"] == 0.2 and "num_steps_per_env" not in alg
    assert train_cfg["num_steps_per_env"] == 8
    assert train_cfg["obs_groups"] == {"actor": ["proprioception"], "critic": ["proprioception"]}
    assert train_cfg["actor"]["class_name"] == "devlearn.training.networks:MultiSenseModel"
    dist = train_cfg["actor"]["distribution_cfg"]
    assert dist == {  # the default head (issue #54): free spread from 1.0, ceiling to 0.3,
        "class_name": "devlearn.training.distribution:FreeGaussian",  # pink exploration
        "init_std": 1.0,
        "final_std": 0.3,
        "noise_beta": 1.0,
        "noise_decision_s": 0.005,  # the tiny behaviour decides every physics step
    }
    paper = to_rsl_rl(tiny_run.config("unused", 256, "network.head=paper"), behavior)
    dist = paper["actor"]["distribution_cfg"]
    assert dist["class_name"] == "devlearn.training.networks:TanhSoftplusGaussian"
    assert "distribution_cfg" not in train_cfg["critic"]
    # every algorithm key is a PPO keyword argument (rsl-rl raises TypeError otherwise)
    import inspect

    from devlearn.training.ppo import UniqueParamPPO

    params = inspect.signature(UniqueParamPPO.__mro__[1].__init__).parameters
    # share_cnn_encoders is popped by rsl-rl's construct_algorithm before PPO sees it
    # adam_eps is UniqueParamPPO's own
    assert set(alg) - {"class_name", "share_cnn_encoders", "adam_eps"} <= set(params)


def test_automatic_workers_one_per_core_and_none_for_small_batches():
    from devlearn.training.process import resolve_workers

    assert resolve_workers(-1, 16, cpus=2) == 2
    assert resolve_workers(-1, 8, cpus=16) == 2  # at most num_envs // 4
    assert resolve_workers(-1, 4, cpus=2) == 0  # too few envs to pay for a worker
    assert resolve_workers(-1, 64, cpus=1) == 0
    assert resolve_workers(3, 4, cpus=1) == 3  # an explicit number is kept
