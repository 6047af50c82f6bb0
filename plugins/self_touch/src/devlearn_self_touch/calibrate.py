"""Calibrate the ``touched`` threshold on g_j: mattress contact vs. a hand touching the body.

The paper marks region j touched when g_j > 0.1 in MIMo's units (sec. II-A3). Our skin reports
forces in newtons with its own sensor density, so we measure our own numbers:

1. **still**: the infant lies still (zero action) from the default pose; every region with
   g_j > 0 and no hand on it rests on the mattress.
2. **babbling**: random actions from random poses; g_j of regions no hand touches (mostly the
   mattress under the back, head, arms and legs as they move) against g_j of regions a hand
   does touch (``Infant.hand_contacts``): the light, accidental touches the agent starts from.

It prints both distributions and a suggested threshold (above every mattress value seen) as
JSON. Usage::

    python -m devlearn_self_touch.calibrate --steps 3000 --seed 0
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

import numpy as np

from devlearn_self_touch.body_map import body_map


def _stats(values: list[float]) -> dict[str, float]:
    """Summary statistics of a list of g_j values (N per sensor)."""
    if not values:
        return {"n": 0}
    a = np.asarray(values)
    qs = {f"p{q}": float(np.percentile(a, q)) for q in (1, 10, 50, 90, 99, 99.9)}
    return {"n": int(a.size), "min": float(a.min()), **qs, "max": float(a.max())}


def _g(infant: Any) -> np.ndarray:
    """(68,) body map of the infant's current touch."""
    return body_map(infant.touch(), infant.skin.sensor_region, infant.skin.region_sizes)


def measure(steps: int = 3000, still_steps: int = 400, seed: int = 0) -> dict[str, Any]:
    """Run the two measurements on the crib infant.

    Args:
        steps: Babbling steps (random actions, a random pose each 1000 steps).
        still_steps: Zero-action steps from the default pose (the first 100 are settling).
        seed: Seed of the poses and actions.

    Returns:
        ``still_mattress``, ``babbling_no_hand``, ``babbling_hand_touch``: statistics of g_j;
        ``still_regions``: names of regions resting on the mattress; ``suggested_threshold``.
    """
    from devlearn.infant import build_infant

    rng = np.random.default_rng(seed)
    infant = build_infant("crib", senses=("touch", "proprioception"))
    try:
        names = [str(n) for n in infant.regions.names]
        infant.reset(rng, random_pose=False)
        still: list[float] = []
        resting: set[int] = set()
        for t in range(still_steps):
            infant.step(np.zeros(infant.action_dim))
            if t < 100:
                continue
            g, hands = _g(infant), infant.hand_contacts().any(axis=0)
            for j in np.flatnonzero((g > 0) & ~hands):
                still.append(float(g[j]))
                resting.add(int(j))
        no_hand: list[float] = []
        hand: list[float] = []
        for t in range(steps):
            if t % infant.episode_steps == 0:
                infant.reset(rng, random_pose=True)
            infant.step(rng.uniform(-1.0, 1.0, infant.action_dim))
            g, hands = _g(infant), infant.hand_contacts().any(axis=0)
            no_hand += [float(v) for v in g[(g > 0) & ~hands]]
            hand += [float(v) for v in g[hands]]
    finally:
        infant.close()
    mattress_max = max(still + no_hand, default=0.0)
    return {
        "still_mattress": _stats(still),
        "still_regions": sorted(names[j] for j in resting),
        "babbling_no_hand": _stats(no_hand),
        "babbling_hand_touch": _stats(hand),
        "suggested_threshold": float(1.2 * mattress_max),
    }


def main(argv: list[str] | None = None) -> int:
    """Command line: print :func:`measure`'s result as JSON."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=3000, help="babbling steps")
    parser.add_argument("--still-steps", type=int, default=400, help="zero-action steps")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    result = measure(args.steps, args.still_steps, args.seed)
    json.dump(result, sys.stdout, indent=2)
    print()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
