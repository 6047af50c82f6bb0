"""Committed checkpoints of both network layouts rebuild and act as trained; images in [0, 1]."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch
import torch.nn as nn

from devlearn.config.run_config import from_dict, to_dict
from devlearn.env import BehaviorEnv
from devlearn.plugins import PluginRegistry
from devlearn.testing import run_config
from devlearn.training.checkpoint import (
    FORMAT,
    build_actor,
    load_actor,
    load_checkpoint,
    save_atomic,
)
from devlearn.training.checkpoint import observation_batch as _batch

ROOT = Path(__file__).resolve().parents[2]
DATA = Path(__file__).resolve().parent / "data"
LEGACY_CNN = [
    "behavior.policy=cnn",
    "behavior.critic=same",
    "network.layout=separate",
    "network.legacy_uint8_scale=true",
    "network.head=paper",
]
# Policies saved before the layouts (separate actor, double uint8 scale): the published runs
# of that kind (max_std/run and max_std_seed2/run at fc8804f, issue #32; self_touch/run and
# hand_regard/run at 2d704d9) moved to git history to keep the tree small. The small committed
# fixture data/hand_to_mouth_separate_legacy.pt stands for their file format, and a hand-regard
# CNN policy saved the old way in the test below for their image scale.


@pytest.fixture(scope="module")
def registry():
    return PluginRegistry()


def synthetic(obs: dict[str, np.ndarray], seed: int = 0) -> dict[str, np.ndarray]:
    """Observations of the same shapes and dtypes: uint8 noise images, normal floats."""
    rng = np.random.default_rng(seed)
    out = {}
    for key, value in obs.items():
        value = np.asarray(value)
        if value.dtype == np.uint8:
            out[key] = rng.integers(0, 256, value.shape, dtype=np.uint8)
        else:
            out[key] = rng.standard_normal(value.shape).astype(np.float32)
    return out


def rebuild(path: Path, registry, **network):
    """The checkpoint's behaviour, policy and one env, its config's network section updated."""
    state = load_checkpoint(path)
    cfg = from_dict(state["config"], registry.behavior(state["behavior"]))
    for key, value in network.items():
        setattr(cfg.network, key, value)
    if hasattr(cfg.behavior, "detector_file"):  # the run's own copy of its hand detector
        cfg.behavior.detector_file = str(ROOT / "results/hand_regard/hand_detector.json")
    behavior = registry.create(state["behavior"], cfg.behavior)
    env = BehaviorEnv(behavior, 0, training=False)
    obs = env.reset()
    return cfg, env, obs, load_actor(cfg, state, behavior, obs, env.action_dim)


def raw_head(actor, obs) -> list[float]:
    with torch.inference_mode():
        raw = actor.mlp(actor.get_latent(_batch(synthetic(obs))))[0]
    return raw[0, :4].tolist() + raw[1, :4].tolist()


def act_a_few_steps(env, actor, obs, steps: int = 5) -> None:
    for _ in range(steps):
        with torch.inference_mode():
            action = actor(_batch(obs))[0].numpy()
        assert np.all(np.abs(action) <= 1.0)
        obs = env.step(action)[0]


def saved_the_old_way(name: str, overrides: list[str], seed: int, registry):
    """A policy file's state as every run before the layouts saved it (a config without a
    network section), of a seeded actor moved off its initialisation like trained weights;
    and the actor and one observation."""
    cfg = run_config(registry.behavior(name), overrides)
    behavior = registry.create(name, cfg.behavior)
    env = BehaviorEnv(behavior, 0, training=False)
    obs = env.reset()
    env.close()
    torch.manual_seed(seed)
    actor = build_actor(cfg, behavior, obs, env.action_dim).eval()
    with torch.no_grad():
        for p in actor.parameters():
            p.add_(0.05 * torch.randn_like(p))
    saved = to_dict(cfg)
    del saved["network"]
    state = {
        "format": FORMAT,
        "behavior": name,
        "config": saved,
        "policy_only": True,
        "iteration": 0,
        "env_steps": 0,
        "actor_state_dict": actor.state_dict(),
    }
    return state, actor, obs


def test_an_old_cnn_policy_keeps_its_double_image_scale(registry, tmp_path):
    """A hand-regard CNN policy saved before the layouts (no network section) is rebuilt
    separate with the double uint8 scale it was trained with; [0, 1] images act otherwise."""
    state, actor, obs = saved_the_old_way("hand_regard", LEGACY_CNN, 3, registry)
    path = tmp_path / "old_cnn.pt"
    save_atomic(state, path)
    as_saved = raw_head(actor, obs)
    cfg, env, obs, rebuilt = rebuild(path, registry)
    try:
        assert cfg.network.layout == "separate" and cfg.network.legacy_uint8_scale
        assert not rebuilt.shared
        np.testing.assert_allclose(raw_head(rebuilt, obs), as_saved, rtol=1e-5, atol=1e-6)
        act_a_few_steps(env, rebuilt, obs)
    finally:
        env.close()
    _, env, obs, fixed = rebuild(path, registry, legacy_uint8_scale=False)
    env.close()
    assert not np.allclose(raw_head(fixed, obs), as_saved, rtol=1e-5, atol=1e-6)


def test_committed_separate_legacy_checkpoint_acts_as_saved(registry):
    """A policy file as every run before the layouts saved it (no network section): rebuilt in
    the separate layout with the double uint8 scale; its raw head as pinned when it was made
    (data/hand_to_mouth_separate_legacy.txt, by data/make_separate_legacy.py)."""
    cfg, env, obs, actor = rebuild(DATA / "hand_to_mouth_separate_legacy.pt", registry)
    try:
        assert cfg.network.layout == "separate" and cfg.network.legacy_uint8_scale
        assert not actor.shared
        text = (DATA / "hand_to_mouth_separate_legacy.txt").read_text()
        np.testing.assert_allclose(
            raw_head(actor, obs), [float(v) for v in text.split()], rtol=1e-5, atol=1e-6
        )
        act_a_few_steps(env, actor, obs)
    finally:
        env.close()


def test_committed_shared_checkpoint_acts_as_trained(registry):
    cfg, env, obs, actor = rebuild(DATA / "hand_to_mouth_shared.pt", registry)
    try:
        assert cfg.network.layout == "shared" and not cfg.network.legacy_uint8_scale
        assert actor.shared and not hasattr(actor, "encoders")
        expected = [float(v) for v in (DATA / "hand_to_mouth_shared.txt").read_text().split()]
        np.testing.assert_allclose(raw_head(actor, obs), expected, rtol=1e-5, atol=1e-6)
        act_a_few_steps(env, actor, obs)
    finally:
        env.close()


@pytest.mark.parametrize("name", ["self_touch", "hand_regard", "hand_to_mouth"])
def test_every_encoder_sees_images_in_zero_one(name, registry):
    """Through the real builder: a white image reaches each first layer as 1, not 1/255."""
    for legacy, white in ((False, 1.0), (True, 1.0 / 255.0)):
        cfg = run_config(registry.behavior(name), [f"network.legacy_uint8_scale={legacy}"])
        behavior = registry.create(name, cfg.behavior)
        env = BehaviorEnv(behavior, 0, training=False)
        obs = env.reset()
        env.close()
        actor = build_actor(cfg, behavior, obs, env.action_dim).eval()
        encoders = actor.body.encoders if actor.shared else actor.encoders
        seen: dict[str, float] = {}
        for group, encoder in encoders.items():
            layers = [m for m in encoder.modules() if isinstance(m, (nn.Conv2d, nn.Linear))]
            first = layers[0] if layers else encoder  # a flat sense: its value, as it came
            first.register_forward_pre_hook(
                lambda m, args, g=group, seen=seen: seen.__setitem__(g, float(args[0].max()))
            )
        images = [k for k, v in obs.items() if np.asarray(v).dtype == np.uint8]
        batch = {k: np.full_like(v, 255) if k in images else v for k, v in obs.items()}
        with torch.inference_mode():
            actor(_batch(batch))
        for group in images:
            assert seen[group] == pytest.approx(white, rel=1e-6), (name, group, legacy)
        assert set(seen) == set(obs)
