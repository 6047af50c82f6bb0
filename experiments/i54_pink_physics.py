"""Issue #54 item 2's seconds: does pink exploration make the physics work harder?

The infant in self-touch's crib, from its fixed pose, driven for 1,000 decisions (5 physics
steps each, as ``env.action_repeat``) by a fresh policy's exploration alone: actions
``clip(std * noise, -1, 1)`` with the policy's own :class:`ColoredNoise` draws, white
(``network.exploration_beta=0``, SB3's) or pink (1, devlearn's default), at the free head's
initial spread (1.0) and at the ceiling's end (0.3), 5 seeds each. Prints, per physics step,
MuJoCo's contacts (``ncon``), constraint rows (``nefc``) and solver iterations: counts, which
the machine's load does not change (times do, and are not printed).

    .venv/bin/python experiments/i54_pink_physics.py      # ~1 min
"""

from __future__ import annotations

import numpy as np
import torch

from devlearn.infant import build_infant
from devlearn.timing import PHYSICS_TIMESTEP
from devlearn.training.distribution import ColoredNoise

DECISIONS = 1000
REPEAT = 5
SEEDS = (1, 2, 3, 4, 5)


def counts(beta: float, std: float, seed: int) -> np.ndarray:
    """Mean (contacts, constraint rows, solver iterations) per physics step of one drive."""
    infant = build_infant("crib", senses=("proprioception", "touch"))
    infant.reset(np.random.default_rng(seed), random_pose=False)
    torch.manual_seed(seed)
    noise = ColoredNoise((infant.action_dim,), beta, PHYSICS_TIMESTEP * REPEAT)
    total = np.zeros(3)
    for _ in range(DECISIONS):
        action = torch.clamp(std * noise.next(), -1.0, 1.0).double().numpy()
        for _ in range(REPEAT):
            infant.step(action)
            data = infant.data
            total += (data.ncon, data.nefc, data.solver_niter[0])
    infant.close()
    return total / (DECISIONS * REPEAT)


def main() -> None:
    print("| exploration | spread | contacts | constraint rows | solver iterations |")
    print("|---|---|---|---|---|")
    for std in (1.0, 0.3):
        rows = {}
        for beta, name in ((0.0, "white"), (1.0, "pink")):
            per_seed = np.array([counts(beta, std, seed) for seed in SEEDS])
            rows[name] = per_seed.mean(axis=0)
            cells = " | ".join(
                f"{m:.2f} [{lo:.2f}, {hi:.2f}]"
                for m, lo, hi in zip(rows[name], per_seed.min(axis=0), per_seed.max(axis=0))
            )
            print(f"| {name} | {std} | {cells} |")
        ratio = rows["pink"] / rows["white"]
        print(f"| pink / white | {std} | " + " | ".join(f"{r:.2f}" for r in ratio) + " |")
    print(f"\nmeans over seeds {SEEDS} [their range], per physics step; {DECISIONS} decisions each")


if __name__ == "__main__":
    main()
