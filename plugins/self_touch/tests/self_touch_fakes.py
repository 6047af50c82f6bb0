"""Fakes for the self_touch tests: synthetic step contexts, a fake region table and skin."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from devlearn import StepContext
from devlearn.testing import EPISODE_RECORD

TINY_RUN = ["env.action_repeat=1", "ppo.num_steps_per_env=20", "ppo.num_mini_batches=2"]
"""One iteration is one 20-step episode per env (SwappingInfant's script), two minibatches."""


def make_ctx(
    touched=(),
    hand_contacts=(),
    hand_parts=(),
    step: int = 0,
    last_step: bool = False,
) -> StepContext:
    """A synthetic StepContext (no infant) with the facts the reward terms read.

    Args:
        touched: Region indices touched this step.
        hand_contacts: (hand, region) pairs in contact this step.
        hand_parts: (hand, part) pairs touched this step.
    """
    t = np.zeros(68, dtype=bool)
    t[list(touched)] = True
    hc = np.zeros((2, 68), dtype=bool)
    for h, j in hand_contacts:
        hc[h, j] = True
    hp = np.zeros((2, 34), dtype=bool)
    for h, p in hand_parts:
        hp[h, p] = True
    facts = {"touched": t, "hand_contacts": hc, "hand_parts": hp}
    return StepContext(infant=None, observations={}, facts=facts, step=step, last_step=last_step)


def make_regions() -> SimpleNamespace:
    """A 68-region table: regions 0-33 left side, 34-67 right; part p = j % 34; part 32 is
    "hand", part 33 "fingers"."""
    names = [f"p{p}" for p in range(32)] + ["hand", "fingers"]
    return SimpleNamespace(
        names=[f"{s}_{names[j % 34]}" for s in ("left", "right") for j in range(34)],
        sides=np.array(["left"] * 34 + ["right"] * 34),
        parts=np.arange(68) % 34,
        part_names=names,
    )


class FakeInfant:
    """Just enough of :class:`devlearn.infant.Infant` for :meth:`SelfTouch.facts`.

    Skin: 3 sensors per region (sensor i in region i // 3), so region_sizes are all 3.

    Args:
        touch: (204, 3) forces; zeros if None.
        hand_contacts: (2, 68) bool; all False if None.
    """

    def __init__(self, touch=None, hand_contacts=None) -> None:
        self.skin = SimpleNamespace(
            num_sensors=204,
            sensor_region=np.repeat(np.arange(68), 3),
            region_sizes=np.full(68, 3),
        )
        self.regions = make_regions()
        self._touch = np.zeros((204, 3), np.float32) if touch is None else touch
        self._contacts = np.zeros((2, 68), bool) if hand_contacts is None else hand_contacts

    def touch(self) -> np.ndarray:
        return self._touch

    def touch_sparse(self) -> tuple[np.ndarray, np.ndarray]:
        sensors = np.flatnonzero(self._touch.any(axis=1))
        return sensors, self._touch[sensors]

    def hand_contacts(self) -> np.ndarray:
        return self._contacts

    def proprioception(self) -> np.ndarray:
        return np.arange(10, dtype=np.float32)


class ScriptedInfant(FakeInfant):
    """A fake infant for :class:`devlearn.testing.Play` whose hands follow a script.

    On episode step t the left hand touches region t while t < ``left`` and the right hand
    touches region 34 + t while t < ``right`` (both hands, the same part index t).
    """

    action_dim = 4
    episode_steps = 20
    control_timestep = 0.005
    physics_timestep = 0.005

    def __init__(self, scene: str = "crib", senses=(), left: int = 12, right: int = 10) -> None:
        super().__init__()
        self.left, self.right, self.t = left, right, 0
        self.resets: list[bool] = []

    def reset(self, rng, random_pose: bool = False) -> None:
        self.t = 0
        self.resets.append(random_pose)

    def step(self, action) -> None:
        self.t += 1

    def hand_contacts(self) -> np.ndarray:
        contacts = np.zeros((2, 68), bool)
        k = self.t - 1
        if 0 <= k < self.left:
            contacts[0, k] = True
        if 0 <= k < self.right:
            contacts[1, 34 + k] = True
        return contacts

    def close(self) -> None:
        pass


class SwappingInfant(ScriptedInfant):
    """A scripted infant whose discoveries depend on its env and episode (picklable, so it
    also runs in env worker processes).

    The env's identity is the parity k of its seed (``rng``'s seed: envs are seeded
    ``seed + index``). In its e-th episode the left hand touches regions 5g .. 5g + 4 on steps
    1 to 5, one per step, with g = (k + e) % 2: on the first episode env 0 discovers regions
    0-4 and env 1 regions 5-9, on the second each touches what the other discovered.
    """

    def __init__(self, scene: str = "crib", senses=()) -> None:
        super().__init__(scene, senses)
        self.episodes = 0
        self.group = 0

    def reset(self, rng, random_pose: bool = False) -> None:
        super().reset(rng, random_pose)
        parity = int(rng.bit_generator.seed_seq.entropy) % 2
        self.group = (parity + self.episodes) % 2
        self.episodes += 1

    def hand_contacts(self) -> np.ndarray:
        contacts = np.zeros((2, 68), bool)
        if 1 <= self.t <= 5:
            contacts[0, 5 * self.group + self.t - 1] = True
        return contacts


def same_info(a: dict | None, b: dict | None) -> bool:
    """Episode infos equal, the evaluator's record (an array, for the run's metrics) by value."""
    if a is None or b is None:
        return a is b
    a, b = dict(a), dict(b)
    ra, rb = a.pop(EPISODE_RECORD, None), b.pop(EPISODE_RECORD, None)
    return a == b and np.array_equal(ra, rb) if ra is not None else a == b and rb is None


def train_swapping(out, overrides=(), steps: int = 40, workers: int = 2) -> None:
    """Train self-touch on two :class:`SwappingInfant` envs, ``steps`` physics steps (40: one
    iteration, one episode per env) in ``workers`` worker processes, into ``out``."""
    from devlearn_self_touch import SelfTouch

    from devlearn.testing import registry_for, run_config, train

    cfg = run_config(
        SelfTouch, [*TINY_RUN, *overrides], out_dir=str(out), num_envs=2, workers=workers
    )
    cfg.total_steps = steps
    train(cfg, registry_for(SelfTouch), infant_factory=SwappingInfant, progress=False)
