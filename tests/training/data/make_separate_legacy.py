"""Make hand_to_mouth_separate_legacy.pt and .txt (its pinned raw head) in this folder.

A policy file as every run before the shared layout saved it (a config without a network
section: separate actor, double uint8 scale), small enough for the tree; it stands in for the
published runs' policy files of that kind that moved to git history (issue #32). Run from the
repository root: ``.venv/bin/python tests/training/data/make_separate_legacy.py``.
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests/training
from test_layouts import raw_head, rebuild, saved_the_old_way

from devlearn.plugins import PluginRegistry
from devlearn.training.checkpoint import save_atomic

registry = PluginRegistry()
overrides = [
    "network.layout=separate",
    "network.legacy_uint8_scale=true",
    "network.head=paper",  # the head every run before issue #28 had
    "seed=5",
]
state, actor, _ = saved_the_old_way("hand_to_mouth", overrides, 5, registry)
assert not actor.shared
out = Path(__file__).resolve().parent / "hand_to_mouth_separate_legacy.pt"
save_atomic(state, out)
cfg2, env2, obs2, actor2 = rebuild(out, registry)
env2.close()
assert cfg2.network.layout == "separate" and cfg2.network.legacy_uint8_scale
values = raw_head(actor2, obs2)
out.with_suffix(".txt").write_text(" ".join(f"{v:.8g}" for v in values) + "\n")
print(out.stat().st_size, values)
