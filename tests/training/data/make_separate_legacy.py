"""Make hand_to_mouth_separate_legacy.pt and .txt (its pinned raw head) in this folder.

A policy file as every run before the shared layout saved it (a config without a network
section: separate actor, double uint8 scale), small enough for the tree; it stands in for the
published runs' policy files of that kind that moved to git history (issue #32). Run from the
repository root: ``.venv/bin/python tests/training/data/make_separate_legacy.py``.
"""

import sys
from pathlib import Path

import torch

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests/training
from test_layouts import raw_head, rebuild, untrained_actor

from devlearn.config.run_config import default_config, to_dict
from devlearn.env import BehaviorEnv
from devlearn.plugins import PluginRegistry
from devlearn.training.checkpoint import FORMAT, save_atomic

registry = PluginRegistry()
cfg = default_config(
    registry.behavior("hand_to_mouth"),
    ["network.layout=separate", "network.legacy_uint8_scale=true", "seed=5"],
)
behavior = registry.create("hand_to_mouth", cfg.behavior)
env = BehaviorEnv(behavior, 0, training=False)
obs = env.reset()
env.close()
torch.manual_seed(5)
actor = untrained_actor(cfg, behavior, obs, env.action_dim)
assert not actor.shared
with torch.no_grad():
    for p in actor.parameters():
        p.add_(0.05 * torch.randn_like(p))  # away from the initialisation, like trained weights
saved = to_dict(cfg)
del saved["network"]  # as every run before the layouts wrote it
state = {
    "format": FORMAT,
    "behavior": "hand_to_mouth",
    "config": saved,
    "policy_only": True,
    "iteration": 0,
    "env_steps": 0,
    "actor_state_dict": actor.state_dict(),
}
out = Path(__file__).resolve().parent / "hand_to_mouth_separate_legacy.pt"
save_atomic(state, out)
cfg2, env2, obs2, actor2 = rebuild(out, registry)
env2.close()
assert cfg2.network.layout == "separate" and cfg2.network.legacy_uint8_scale
values = raw_head(actor2, obs2)
out.with_suffix(".txt").write_text(" ".join(f"{v:.8g}" for v in values) + "\n")
print(out.stat().st_size, values)
