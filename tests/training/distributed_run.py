"""Run under torchrun by test_distributed.py: train the tiny behaviour on this rank, then write
``rank<RANK>.json`` with hashes of the networks' parameters (before and after learning) and the
seeds of this rank's environments.

Usage: ``torchrun --nproc_per_node 2 distributed_run.py OUT_DIR TOTAL_STEPS``.
"""

from __future__ import annotations

import hashlib
import importlib
import json
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import tiny_run  # noqa: E402
import torch  # noqa: E402

from devlearn.training.runner import DevRunner  # noqa: E402

# the module, not the function devlearn.training re-exports under the same name
train_module = importlib.import_module("devlearn.training.train")


def parameter_hash(runner) -> str:
    """sha256 of every actor and critic parameter and buffer, in state-dict order."""
    digest = hashlib.sha256()
    for module in (runner.alg.actor, runner.alg.critic):
        for name, tensor in module.state_dict().items():
            digest.update(name.encode())
            digest.update(tensor.detach().cpu().contiguous().numpy().tobytes())
    return digest.hexdigest()


class RecordingRunner(DevRunner):
    """DevRunner that writes this rank's parameter hashes and env seeds around learn()."""

    def learn(self, total_steps: int) -> None:  # type: ignore[override]
        before = parameter_hash(self)
        super().learn(total_steps)
        envs = self.env.state_dict()["envs"]
        record = {
            "rank": int(os.environ["RANK"]),
            "world_size": self.gpu_world_size,
            "before": before,
            "after": parameter_hash(self),
            "iterations": self.current_learning_iteration,
            "env_rng": [json.dumps(e["rng"], sort_keys=True) for e in envs],
            "torch_rng": hashlib.sha256(torch.get_rng_state().numpy().tobytes()).hexdigest(),
        }
        out = self.run_dir / f"rank{record['rank']}.json"
        out.write_text(json.dumps(record))


if __name__ == "__main__":
    out, steps = sys.argv[1], int(sys.argv[2])
    train_module.DevRunner = RecordingRunner  # train() builds whatever DevRunner names
    cfg = tiny_run.config(out, steps)
    train_module.train(cfg, tiny_run.registry(), infant_factory=tiny_run.factory, progress=False)
