"""Measure g_j on mattress contact vs. self-touch, to choose what counts as "touched".

The paper marks region j touched when g_j > 0.1 in MIMo's units (sec. II-A3). Our skin reports
forces in newtons with its own sensor density, so we measure our own numbers. Every region in
contact is labelled by what touches it (MuJoCo's contact list: the mattress, another body part,
or a hand; :func:`contact_labels`), and g_j is collected per label in two phases:

1. **still**: the infant lies still (zero action) from the default pose;
2. **babbling**: random actions from random initial poses (the first ``settle_steps`` after
   each reset are left out: a random pose can start inside the mattress and the push-out
   produces forces of thousands of newtons per sensor, reported as ``reset_transient_max``).

If mattress-only values overlap self-touch values, no threshold on g_j separates them (that is
what we found; numbers in the README) and "touched" must come from hand contacts. Usage::

    python -m devlearn_self_touch.calibrate --steps 5000 --seed 0
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


def contact_labels(infant: Any) -> np.ndarray:
    """Label the regions in contact by what touches them (a measuring aid, not used in training).

    Reads MuJoCo's contact list: for each contact side with skin, the touched region is that of
    the nearest sensor to the contact point; the toucher is the other body.

    Returns:
        (3, 68) bool: rows ``scene`` (mattress or floor: a body without skin), ``self`` (another
        body part, not a hand), ``hand`` (a palm or fingers of either hand).
    """
    model, data, skin = infant.model, infant.data, infant.skin
    labels = np.zeros((3, 68), dtype=bool)
    has_skin = skin.body_spacing > 0
    for i in range(data.ncon):
        contact = data.contact[i]
        if contact.efc_address < 0:  # excluded or inactive: no force
            continue
        bodies = model.geom_bodyid[contact.geom]
        for side in range(2):
            body, other = int(bodies[side]), int(bodies[1 - side])
            if not has_skin[body]:
                continue
            rot = data.xmat[body].reshape(3, 3)
            point = (contact.pos - data.xpos[body]) @ rot
            sensor = skin.nearest(np.array([body]), point[None, :])[0]
            row = 0 if not has_skin[other] else 2 if infant.hand_of_body[other] >= 0 else 1
            labels[row, skin.sensor_region[sensor]] = True
    return labels


def measure(
    steps: int = 3000, still_steps: int = 400, seed: int = 0, settle_steps: int = 50
) -> dict[str, Any]:
    """Run the two measurements on the crib infant.

    Args:
        steps: Babbling steps (random actions, a random pose each 1000 steps).
        still_steps: Zero-action steps from the default pose (the first 100 are settling).
        seed: Seed of the poses and actions.
        settle_steps: Steps after each random-pose reset left out of the babbling statistics
            (their largest g_j is reported as ``reset_transient_max``).

    Returns:
        Statistics of g_j (N per sensor) for regions touched only by the mattress
        (``still_mattress``, ``babbling_mattress``), only by another non-hand body part
        (``still_self``, ``babbling_self``) and by a hand (``babbling_hand``); the regions
        resting on the mattress when still; ``reset_transient_max``.
    """
    from devlearn import build_infant

    rng = np.random.default_rng(seed)
    infant = build_infant("crib", senses=("touch", "proprioception"))
    names = [str(n) for n in infant.regions.names]
    seen: dict[str, list[float]] = {k: [] for k in ("still_mattress", "still_self",
                                                    "babbling_mattress", "babbling_self",
                                                    "babbling_hand")}  # fmt: skip
    resting: set[str] = set()
    transient = 0.0

    def record(phase: str) -> None:
        g = _g(infant)
        scene, self_, hand = contact_labels(infant)
        hand |= infant.hand_contacts().any(axis=0)
        seen[f"{phase}_mattress"] += g[scene & ~self_ & ~hand].tolist()
        seen[f"{phase}_self"] += g[self_ & ~scene & ~hand].tolist()
        if phase == "babbling":
            seen["babbling_hand"] += g[hand & ~scene].tolist()
        else:
            resting.update(names[j] for j in np.flatnonzero(scene))

    try:
        infant.reset(rng, random_pose=False)
        for t in range(still_steps):
            infant.step(np.zeros(infant.action_dim))
            if t >= 100:
                record("still")
        for t in range(steps):
            if t % infant.episode_steps == 0:
                infant.reset(rng, random_pose=True)
            infant.step(rng.uniform(-1.0, 1.0, infant.action_dim))
            if t % infant.episode_steps < settle_steps:  # a random pose may start inside the
                transient = max(transient, float(_g(infant).max()))  # mattress: skip its push-out
            else:
                record("babbling")
    finally:
        infant.close()
    return {
        **{k: _stats(v) for k, v in seen.items()},
        "still_mattress_regions": sorted(resting),
        "reset_transient_max": transient,
    }


def main(argv: list[str] | None = None) -> int:
    """Command line: print :func:`measure`'s result as JSON."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=3000, help="babbling steps")
    parser.add_argument("--still-steps", type=int, default=400, help="zero-action steps")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--settle-steps", type=int, default=50, help="skipped after resets")
    args = parser.parse_args(argv)
    result = measure(args.steps, args.still_steps, args.seed, args.settle_steps)
    json.dump(result, sys.stdout, indent=2)
    print()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
