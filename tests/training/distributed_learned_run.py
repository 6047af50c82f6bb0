"""Run under torchrun by test_learned_rewards.py: the tiny behaviour with a learned reward; each
rank writes ``learned<RANK>.json`` with a hash of the learned model before and after learning.

Usage: ``torchrun --nproc_per_node 2 distributed_learned_run.py OUT_DIR TOTAL_STEPS``.
"""

from __future__ import annotations

import hashlib
import importlib
import json
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import tiny_run  # noqa: E402
from learned_terms import LinearPredictor  # noqa: E402

from devlearn.testing import registry_for  # noqa: E402
from devlearn.testing.fake_infant import TinyBehavior  # noqa: E402
from devlearn.training.runner import DevRunner  # noqa: E402

train_module = importlib.import_module("devlearn.training.train")


def learned_hash(runner) -> str:
    """sha256 of the learned model's parameters and its reward scale."""
    digest = hashlib.sha256()
    term = runner.learned.terms["linear"]
    for tensor in [*term.model.state_dict().values(), *term.scale.buffers()]:
        digest.update(tensor.detach().cpu().contiguous().numpy().tobytes())
    return digest.hexdigest()


class RecordingRunner(DevRunner):
    """DevRunner that writes this rank's learned-model hashes around learn()."""

    def learn(self, total_steps: int) -> None:  # type: ignore[override]
        before = learned_hash(self)
        super().learn(total_steps)
        rank = int(os.environ["RANK"])
        record = {"before": before, "after": learned_hash(self), "last": self.learned.last}
        (self.run_dir / f"learned{rank}.json").write_text(json.dumps(record))


if __name__ == "__main__":
    out, steps = sys.argv[1], int(sys.argv[2])
    train_module.DevRunner = RecordingRunner
    cfg = tiny_run.config(out, steps, "curiosity=linear")
    registry = registry_for(TinyBehavior, learned_rewards=(LinearPredictor,))
    train_module.train(cfg, registry, infant_factory=tiny_run.factory, progress=False)
