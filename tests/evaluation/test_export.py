"""devlearn export: ONNX and TorchScript policies match torch on recorded observations."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch

from devlearn.cli import main
from devlearn.config.run_config import from_dict, to_dict
from devlearn.env import BehaviorEnv
from devlearn.evaluation.export import DeterministicPolicy, export_policy, load_policy
from devlearn.plugins import PluginRegistry
from devlearn.testing import run_config
from devlearn.training.checkpoint import (
    FORMAT,
    Checkpoint,
    build_actor,
    load_checkpoint,
    save_atomic,
)
from devlearn.training.checkpoint import observation_batch as _batch

ROOT = Path(__file__).resolve().parents[2]
PUBLISHED = {
    # issue #30's median seed (shared layout)
    "self_touch": ROOT / "results/self_touch/i30/curriculum/two_stage/policy.pt",
    # issue #40's CNN policy at the paper's budget (separate layout, sees the eyes; its detector)
    "hand_regard": ROOT / "results/hand_regard/i40/cnn/policy.pt",
    # a small fixture as every run before the layouts saved it (separate, double uint8 scale)
    "hand_to_mouth": ROOT / "tests/training/data/hand_to_mouth_separate_legacy.pt",
}
# A hand-regard CNN policy saved as before the layouts (no network section: separate, double
# uint8 image scale), made in the test: its published file (results/hand_regard/run/) moved to
# git history to keep the tree small.
LEGACY_CNN = [
    "behavior.policy=cnn",
    "behavior.critic=same",
    "network.layout=separate",
    "network.legacy_uint8_scale=true",
    "network.head=paper",
]
BEHAVIORS = ["self_touch", "hand_regard", "hand_to_mouth"]


@pytest.fixture(scope="module")
def registry():
    return PluginRegistry()


def record(behavior, steps: int = 4) -> dict[str, np.ndarray]:
    """Observations of ``steps`` random-action steps of one env: name -> (steps, *shape)."""
    env = BehaviorEnv(behavior, 0, training=False)
    rng = np.random.default_rng(0)
    try:
        seen = [env.reset()]
        for _ in range(steps - 1):
            seen.append(env.step(rng.uniform(-1, 1, env.action_dim))[0])
    finally:
        env.close()
    return {k: np.stack([np.array(o[k]) for o in seen]) for k in seen[0]}


def fresh_checkpoint(name: str, registry, path: Path, overrides=(), legacy=False) -> Path:
    """A checkpoint of an untrained policy in today's default (shared) layout, or as
    ``overrides`` configure it; ``legacy``: its config saved without a network section."""
    cfg = run_config(registry.behavior(name), list(overrides))
    behavior = registry.create(name, cfg.behavior)
    env = BehaviorEnv(behavior, 0, training=False)
    obs = env.reset()
    env.close()
    torch.manual_seed(0)
    actor = build_actor(cfg, behavior, obs, env.action_dim)
    with torch.no_grad():  # undo the small initial head: actions far from 0
        [m for m in actor.mlp if isinstance(m, torch.nn.Linear)][-1].weight.mul_(100.0)
    saved = to_dict(cfg)
    if legacy:
        del saved["network"]
    state = {"format": FORMAT, "behavior": name, "config": saved}
    state["actor_state_dict"] = actor.state_dict()
    save_atomic(state, path)
    return path


@pytest.mark.slow
@pytest.mark.parametrize("name", BEHAVIORS)
def test_exported_policies_match_torch_on_recorded_observations(name, registry, tmp_path):
    import onnxruntime  # an optional extra, installed by scripts/setup.sh for the tests

    # an untrained policy of today's defaults, and a published (or committed) policy file
    checkpoints = [fresh_checkpoint(name, registry, tmp_path / f"{name}.pt"), PUBLISHED[name]]
    if name == "hand_regard":
        legacy = fresh_checkpoint(name, registry, tmp_path / "legacy.pt", LEGACY_CNN, legacy=True)
        saved = from_dict(load_checkpoint(legacy)["config"], registry.behavior(name))
        assert saved.network.layout == "separate" and saved.network.legacy_uint8_scale
        checkpoints.append(legacy)
    for checkpoint in checkpoints:
        # observations of the behaviour as the checkpoint configures it, with its artifacts
        # (a published hand-regard policy sees the eyes and carries its detector)
        recorded = record(Checkpoint.open(checkpoint, registry, name).behavior())
        policy, obs = load_policy(name, checkpoint, registry)
        inputs = [recorded[n] for n in policy.names]
        with torch.inference_mode():
            want = policy(*map(torch.from_numpy, inputs)).numpy()
        assert want.shape == (4, len(want[0])) and np.abs(want).max() > 1e-2

        onnx_file = export_policy(policy, obs, "onnx", tmp_path / "policy.onnx")
        session = onnxruntime.InferenceSession(str(onnx_file))
        assert [i.name for i in session.get_inputs()] == policy.names
        got = session.run(["action"], dict(zip(policy.names, inputs)))[0]
        np.testing.assert_allclose(got, want, atol=1e-5, rtol=0)
        one = session.run(["action"], {n: x[:1] for n, x in zip(policy.names, inputs)})[0]
        np.testing.assert_allclose(one, want[:1], atol=1e-5, rtol=0)  # a robot's batch of one

        script = torch.jit.load(str(export_policy(policy, obs, "torchscript", tmp_path / "p.pt")))
        with torch.inference_mode():
            got = script(*map(torch.from_numpy, inputs)).numpy()
        np.testing.assert_allclose(got, want, atol=1e-5, rtol=0)


def test_the_exported_policy_is_the_actor_mean(registry, tmp_path):
    checkpoint = fresh_checkpoint("hand_to_mouth", registry, tmp_path / "c.pt")
    policy, obs = load_policy("hand_to_mouth", checkpoint, registry)
    assert isinstance(policy, DeterministicPolicy)
    batch = _batch(obs)
    with torch.inference_mode():
        policy.actor(batch, stochastic_output=True)
        mean = policy.actor.output_mean  # as the env applies it: clipped to [-1, 1]
        torch.testing.assert_close(policy(*[batch[n] for n in policy.names]), mean.clamp(-1, 1))


def errors(capsys) -> str:
    """stderr without warnings about other installed plugins."""
    lines = capsys.readouterr().err.strip().splitlines()
    return "\n".join(line for line in lines if not line.startswith("devlearn: warning:"))


def test_bad_input_is_one_line_and_exit_2(registry, tmp_path, capsys):
    ours = str(fresh_checkpoint("hand_to_mouth", registry, tmp_path / "h2m.pt"))
    (tmp_path / "junk.pt").write_bytes(b"not a checkpoint")
    out = str(tmp_path / "p.onnx")
    cases = [
        ("does not exist", ["hand_to_mouth", "--checkpoint", str(tmp_path / "none.pt")]),
        ("corrupt or unreadable", ["hand_to_mouth", "--checkpoint", str(tmp_path / "junk.pt")]),
        ("not 'self_touch'", ["self_touch", "--checkpoint", ours]),
        (
            "unknown export format 'tflite'; valid: onnx, torchscript",
            ["hand_to_mouth", "--checkpoint", ours, "--format", "tflite"],
        ),
        ("unknown behavior", ["no_such_behavior", "--checkpoint", ours]),
    ]
    for expected, args in cases:
        code = main(["export", *args, "--out", out])
        err = errors(capsys)
        assert code == 2 and len(err.splitlines()) == 1 and expected in err, (args, err)
    for fmt in ("onnx", "torchscript"):  # an unwritable place
        code = main(
            [
                "export",
                "hand_to_mouth",
                "--checkpoint",
                ours,
                "--format",
                fmt,
                "--out",
                str(tmp_path / "no" / "p"),
            ]
        )
        err = errors(capsys)
        assert code == 2 and len(err.splitlines()) == 1 and "cannot write" in err, err
    code = main(
        ["export", "hand_to_mouth", "--checkpoint", ours, "--format", "torchscript", "--out", out]
    )
    assert code == 0 and Path(out).stat().st_size > 0
    assert "wrote" in capsys.readouterr().out


def test_a_successful_export_prints_one_line_and_no_exporter_noise(registry, tmp_path, capfd):
    import warnings

    checkpoint = str(fresh_checkpoint("hand_to_mouth", registry, tmp_path / "c.pt"))
    capfd.readouterr()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        code = main(
            [
                "export",
                "hand_to_mouth",
                "--checkpoint",
                checkpoint,
                "--format",
                "onnx",
                "--out",
                str(tmp_path / "p.onnx"),
            ]
        )
    out, err = capfd.readouterr()
    assert code == 0 and len(out.splitlines()) == 1 and out.startswith("wrote ")
    assert [line for line in err.splitlines() if not line.startswith("devlearn: ")] == []
    assert [str(w.message) for w in caught] == []
