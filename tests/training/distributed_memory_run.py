"""Run under torchrun by test_distributed.py: train a behaviour whose batched term keeps a
run-wide memory that differs by rank, so the checkpoint shows whether ranks were merged.

Usage: ``torchrun --nproc_per_node 2 distributed_memory_run.py OUT_DIR TOTAL_STEPS``.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "env"))

from tiny_behaviors import NoveltyBehavior, StepNovelty  # noqa: E402

from devlearn.testing import registry_for, run_config  # noqa: E402
from devlearn.testing.fake_infant import fake_infant_factory  # noqa: E402
from devlearn.training import train  # noqa: E402


class RankNovelty(StepNovelty):
    """StepNovelty whose ``widest`` also counts 10 per rank: rank r alone holds 10 r + 4."""

    def __call__(self, batch):
        pay = super().__call__(batch)
        self.widest[0] = max(self.widest[0], 10 * int(os.environ["RANK"]) + len(batch))
        return pay


class RankBehavior(NoveltyBehavior):
    name = "rank_novelty"

    def reward_terms(self) -> list:
        return [RankNovelty()]


if __name__ == "__main__":
    out, steps = sys.argv[1], int(sys.argv[2])
    top = {"num_envs": 4, "workers": 0, "save_interval": 1, "total_steps": steps}
    cfg = run_config(RankBehavior, out_dir=out, **top)
    train(cfg, registry_for(RankBehavior), infant_factory=fake_infant_factory, progress=False)
