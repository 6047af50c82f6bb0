"""Issue #54 item 5: where devlearn's PPO update differs from SB3's, by torch operations.

One update of each learner on the same rollout size and settings (``devlearn bench``'s
``bench_update`` and ``bench_sb3_update``: self-touch's networks, 16 envs x 64 decisions,
random observations, one thread), each under torch's profiler; prints the number of aten
operations of each and the operations whose counts differ most. Counts do not depend on the
machine's load (times do, and are not printed):

    .venv/bin/python experiments/i54_update_ops.py      # ~1 min
"""

from __future__ import annotations

import collections
from typing import Any

import stable_baselines3
import torch
from torch.profiler import ProfilerActivity, profile

from devlearn.bench import learner
from devlearn.plugins import PluginRegistry
from devlearn.training.ppo import UniqueParamPPO

counts: dict[str, collections.Counter] = {}


def counted(cls: Any, method: str, tag: str) -> None:
    """Make ``cls.method`` record its operation counts under ``tag``."""
    original = getattr(cls, method)

    def wrapper(self: Any, *args: Any, **kwargs: Any) -> Any:
        with profile(activities=[ProfilerActivity.CPU]) as prof:
            result = original(self, *args, **kwargs)
        counts[tag] = collections.Counter({e.key: e.count for e in prof.key_averages()})
        return result

    setattr(cls, method, wrapper)


def main() -> None:
    counted(UniqueParamPPO, "update", "devlearn")
    counted(stable_baselines3.PPO, "train", "sb3")
    registry = PluginRegistry()
    behavior = registry.behaviors()["self_touch"]()
    torch.set_num_threads(1)
    learner.bench_update(behavior, "separate", 16, 64, 1, 1, registry)
    learner.bench_sb3_update(behavior, 16, 64, 1, 1, registry)
    for tag, counter in counts.items():
        aten = sum(n for key, n in counter.items() if key.startswith("aten::"))
        print(f"{tag}: {aten} aten operations in one update")
    ours, theirs = counts["devlearn"], counts["sb3"]
    keys = sorted(set(ours) | set(theirs), key=lambda k: ours[k] - theirs[k])
    print(f"{'operation':50s} {'devlearn':>8s} {'sb3':>8s}")
    for key in keys[-15:][::-1] + keys[:8]:
        print(f"{key:50s} {ours[key]:8d} {theirs[key]:8d}")


if __name__ == "__main__":
    main()
