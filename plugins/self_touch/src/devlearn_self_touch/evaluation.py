"""Self-touch metrics (paper sec. II-A6, BabyBench scoring) and the body-map picture."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from devlearn import (
    Evaluator,
    RunMetrics,
    StepContext,
    episode_stats,
    write_atomically,
    write_text_atomically,
)
from devlearn_self_touch.body_map import HANDS, NUM_PARTS, NUM_REGIONS
from devlearn_self_touch.coding import CodedTouches

SETTLE_STEPS = 10
"""Steps at the start of an evaluation episode whose contacts are not credited: a random
reset pose and gravity make contacts on their own (6 of 100 resets touch on step 0), and
BabyBench likewise runs 10 steps before an episode is scored."""
EPISODE_METRICS = ("coverage_left", "coverage_right", "coverage_total", "score", "balance")
"""Per-episode metrics whose mean, spread and 95% interval :meth:`summary` reports."""
PAPER_RESULTS = {
    "two_stage": (
        "paper: two-stage, 8M (Tables I-II)",
        {
            "score": 0.85,
            "coverage_left": 28,
            "coverage_right": 30,
            "coverage_total": 32,
            "balance": 2,
        },
    ),
    "fixed_only": ("paper: fixed-only, 8M (Table II)", {"score": 0.72, "coverage_total": 26}),
    "random_only": ("paper: random-only, 8M (Table II)", {"score": 0.68, "coverage_total": 24}),
}
"""The paper's evaluation figures per curriculum (100 random-pose episodes, its protocol):
Table I for the two-stage run, Table II ("Eval" score and coverage) for the ablation."""


TRAINING_SCORE_PAPER = 0.88
"""The paper's "training score" of its two-stage 8M run (BabyBench's counter over the last
10,000 training episodes; see :class:`TrainingScore`)."""

BOOTSTRAP_RESAMPLES = 2000
"""Resamples of the union score's bootstrap interval."""


def union_score(touched: list[dict[str, list[int]]]) -> float:
    """The union score of episodes' touched parts (eval.json's ``episode_parts``): each hand's
    distinct parts over all the episodes, (left + right) / 68."""
    return sum(len(set().union(*(ep[hand] for ep in touched))) for hand in HANDS) / (2 * NUM_PARTS)


def union_score_interval(
    touched: list[dict[str, list[int]]], resamples: int = BOOTSTRAP_RESAMPLES, seed: int = 0
) -> dict[str, float | None]:
    """95% percentile-bootstrap interval of the union score: episodes drawn with replacement,
    ``resamples`` times, from a fixed seed (so it repeats). Empty with fewer than 2 episodes.

    Returns:
        ``score_boot_low`` and ``score_boot_high`` (None with fewer than 2 episodes).
    """
    if len(touched) < 2:
        return {"score_boot_low": None, "score_boot_high": None}
    masks = np.zeros((len(touched), len(HANDS), NUM_PARTS), dtype=bool)
    for e, episode in enumerate(touched):
        for h, hand in enumerate(HANDS):
            masks[e, h, episode[hand]] = True
    rng = np.random.default_rng(seed)
    draws = rng.integers(0, len(touched), (resamples, len(touched)))
    scores = masks[draws].any(axis=1).sum(axis=(1, 2)) / (2 * NUM_PARTS)
    low, high = np.percentile(scores, [2.5, 97.5])
    return {"score_boot_low": float(low), "score_boot_high": float(high)}


AREAS = ("face", "torso", "arm", "leg", "foot")
"""Body areas of the likeness measures' share of touches (the region table's categories)."""
PHYSICS_TIMESTEP = 0.005
"""Seconds per recorded step when no infant says otherwise (BabyBench's 200 Hz physics)."""


class Likeness:
    """How infant-like one evaluation's touching is (issue #43), from each hand's contacts
    with the 68 body regions after the settle period (``facts["hand_contacts"]``, one record
    per physics step).

    A touch is a contact onset: a hand's palm or fingers starting to touch a region it did not
    touch the step before (a contact held across the settle period's end is not an onset).
    Per episode: touches per simulated minute, distinct regions touched per minute, the share
    of time a hand touches the body, and the mean time between touches; over all touches, the
    share by body area (face, torso, arm, leg, foot). Set beside DiMercurio, Connell, Clark
    and Corbetta (2018) in ``results/self_touch/README.md``.
    """

    def __init__(self) -> None:
        self.previous = np.zeros((len(HANDS), NUM_REGIONS), dtype=bool)
        self.steps = self.contact_steps = 0
        self.onset_steps: list[int] = []
        self.regions = np.zeros(NUM_REGIONS, dtype=bool)
        self.by_region = np.zeros(NUM_REGIONS, dtype=np.int64)  # touches over all episodes
        self.episodes: list[dict[str, float]] = []

    def record(self, contacts: np.ndarray, counted: bool) -> None:
        """One step's (2, 68) contacts; ``counted``: after the settle period."""
        onsets = contacts & ~self.previous
        self.previous = contacts.copy()
        if not counted:
            return
        n = int(onsets.sum())
        if n:
            self.onset_steps += [self.steps] * n
            self.by_region += onsets.sum(axis=0)
        self.steps += 1
        self.contact_steps += int(contacts.any())
        self.regions |= contacts.any(axis=0)

    def end_episode(self, dt: float) -> None:
        minutes = self.steps * dt / 60 if self.steps else float("nan")
        gaps = np.diff(self.onset_steps) * dt if len(self.onset_steps) > 1 else np.array([])
        self.episodes.append(
            {
                "touches_per_minute": len(self.onset_steps) / minutes,
                "distinct_regions_per_minute": int(self.regions.sum()) / minutes,
                "contact_time_share": self.contact_steps / max(self.steps, 1),
                "mean_seconds_between_touches": float(gaps.mean()) if gaps.size else float("nan"),
            }
        )
        self.previous[:] = False
        self.steps = self.contact_steps = 0
        self.onset_steps = []
        self.regions[:] = False

    def merge(self, later: Likeness) -> None:
        """Add ``later``'s episodes after this one's (neither has an episode open)."""
        self.by_region += later.by_region
        self.episodes += later.episodes

    def summary(self, categories: np.ndarray | None) -> dict[str, Any]:
        """Means over episodes (the time between touches over episodes with two or more) and
        the share of all touches by area (empty without the infant's region table)."""
        out: dict[str, Any] = {}
        for key in self.episodes[0] if self.episodes else ():
            values = [e[key] for e in self.episodes if np.isfinite(e[key])]
            out[key] = float(np.mean(values)) if values else None
        total = int(self.by_region.sum())
        shares = {}
        if categories is not None and total:
            shares = {
                area: float(self.by_region[np.asarray(categories) == area].sum() / total)
                for area in AREAS
            }
        return {**out, "touches": total, "touch_share_by_area": shares}


class SelfTouchEvaluator(Evaluator):
    """Per-hand coverage of the 34 side-free body parts, and the self-touch score.

    A hand "touched" part p when its palm or fingers touched either side's region of p
    (``facts["hand_parts"]``). Coverage of a hand is the number of distinct parts it touched
    (of 34); ``coverage_total`` the union over both hands; ``score`` = (left + right) / 68
    (BabyBench's self-touch score, both hands counted fairly; paper Table I: 0.85 for
    28 + 30 parts); ``balance`` = |left - right| (sec. II-A6).

    :meth:`end_episode` reports one episode's values; :meth:`summary` reports the union over
    every recorded episode (how the paper's evaluation over 100 episodes is reported) plus
    each per-episode metric's mean, standard deviation and 95% t-interval, and per-part touch
    counts (steps in contact) per hand.

    Args:
        training: True inside training environments (per-episode metrics only).
        settle_steps: In evaluation (``training=False``), steps 0 .. settle_steps - 1 of each
            episode are not credited (see :data:`SETTLE_STEPS`). Training credits every step.
    """

    mergeable = True  # merge() below: devlearn eval may play its episodes in several envs

    def __init__(self, training: bool = True, settle_steps: int = SETTLE_STEPS) -> None:
        if settle_steps < 0:
            raise ValueError(f"settle_steps must be >= 0, got {settle_steps}")
        self.training = training
        self.settle_steps = 0 if training else int(settle_steps)
        self.region_steps = np.zeros((len(HANDS), NUM_REGIONS), dtype=np.int64)
        self.part_steps = np.zeros((len(HANDS), NUM_PARTS), dtype=np.int64)
        self.ever_parts = np.zeros((len(HANDS), NUM_PARTS), dtype=bool)
        self.episode_parts = np.zeros((len(HANDS), NUM_PARTS), dtype=bool)
        self.episodes: list[dict[str, float]] = []
        self.touched: list[dict[str, list[int]]] = []
        """Each evaluation episode's touched parts per hand (part indices), in eval.json."""
        self.last_parts = np.zeros((len(HANDS), NUM_PARTS), dtype=bool)
        """The touched parts of the episode :meth:`end_episode` closed last, (2, 34)."""
        self.regions: Any = None  # the infant's region table, taken from the first real step
        self.likeness = Likeness()
        self.coded = CodedTouches()
        """Touches as a video coder counts them (:mod:`devlearn_self_touch.coding`)."""
        self.dt = PHYSICS_TIMESTEP

    def record(self, ctx: StepContext) -> None:
        if self.regions is None and ctx.infant is not None:
            self.regions = ctx.infant.regions
            self.dt = float(ctx.infant.physics_timestep)
        if not self.training:
            contacts = np.asarray(ctx.facts["hand_contacts"], dtype=bool)
            counted = ctx.step >= self.settle_steps
            self.likeness.record(contacts, counted=counted)
            if counted:
                if ctx.infant is not None:  # its regions' areas, its bodies (once per body)
                    self.coded.see_infant(ctx.infant)
                self.coded.record(contacts, ctx.infant, self.dt)
        if ctx.step < self.settle_steps:
            return  # the reset pose settling under gravity, not the policy
        parts = np.asarray(ctx.facts["hand_parts"], dtype=bool)
        self.episode_parts |= parts
        if not self.training:
            self.part_steps += parts
            self.region_steps += np.asarray(ctx.facts["hand_contacts"], dtype=bool)

    @staticmethod
    def _coverage(parts: np.ndarray) -> dict[str, float]:
        """Coverage metrics of a (2, 34) bool touched-parts array."""
        left, right = (int(n) for n in parts.sum(axis=1))
        return {
            "coverage_left": float(left),
            "coverage_right": float(right),
            "coverage_total": float(parts.any(axis=0).sum()),
            "score": (left + right) / (2 * NUM_PARTS),
            "balance": float(abs(left - right)),
        }

    def end_episode(self) -> dict[str, float]:
        metrics = self._coverage(self.episode_parts)
        self.ever_parts |= self.episode_parts
        if not self.training:
            self.likeness.end_episode(self.dt)
            self.coded.end_episode()
            self.episodes.append(metrics)
            self.touched.append(
                {
                    hand: np.flatnonzero(self.episode_parts[h]).tolist()
                    for h, hand in enumerate(HANDS)
                }
            )
        self.last_parts = self.episode_parts.copy()
        self.episode_parts[:] = False
        return metrics

    def episode_record(self) -> np.ndarray | None:
        """In training, the closed episode's touched parts, (2, 34) bool (hands x parts), for
        the run's :class:`TrainingScore`; None in evaluation (its summary keeps them)."""
        return self.last_parts if self.training else None

    def merge(self, later: Evaluator) -> None:
        """Add ``later``'s evaluation episodes after this one's (``devlearn eval --envs N``):
        counts summed, touched parts united, per-episode lists joined in order."""
        assert isinstance(later, SelfTouchEvaluator)
        self.region_steps += later.region_steps
        self.part_steps += later.part_steps
        self.ever_parts |= later.ever_parts
        self.episodes += later.episodes
        self.touched += later.touched
        self.likeness.merge(later.likeness)
        self.coded.merge(later.coded)
        if self.regions is None:
            self.regions, self.dt = later.regions, later.dt

    def part_names(self) -> list[str]:
        """Names of the 34 parts (generic ``part_NN`` before a real infant was seen)."""
        if self.regions is not None:
            return [str(n) for n in self.regions.part_names]
        return [f"part_{p:02d}" for p in range(NUM_PARTS)]

    def summary(self) -> dict[str, Any]:
        union = self._coverage(self.ever_parts)
        names = self.part_names()
        spread: dict[str, Any] = {}
        for k in EPISODE_METRICS if self.episodes else ():
            spread.update(episode_stats(k, [e[k] for e in self.episodes]))
        return {
            "episodes": len(self.episodes),
            **{k: int(v) if k.startswith("coverage") else v for k, v in union.items()},
            "parts": NUM_PARTS,
            "balance": int(union["balance"]),
            **union_score_interval(self.touched),
            "settle_steps": self.settle_steps,
            **spread,
            "episode_parts": self.touched,
            "part_touch_steps": {
                hand: {names[p]: int(self.part_steps[h, p]) for p in range(NUM_PARTS)}
                for h, hand in enumerate(HANDS)
            },
            "parts_never_touched": [
                names[p] for p in range(NUM_PARTS) if not self.ever_parts[:, p].any()
            ],
            "likeness": self.likeness.summary(getattr(self.regions, "categories", None)),
            "likeness_coded": self.coded.summary(),
        }

    def protocol(self) -> dict[str, Any]:
        """Settle period and what counts as a touch (recorded in every eval JSON)."""
        return {
            "settle_steps": self.settle_steps,
            "criteria": {
                "hand_touch": "a palm or finger of the hand contacts either side's region of "
                "a part (steps after the settle period)",
                "coded_touch": "a bout of a limb's contact in "
                f"{self.coded.frame_rate} Hz frames, gaps shorter than "
                f"{self.coded.min_gap_frames} frames merged (likeness_coded)",
            },
            "headline": "score",
        }

    def write_artifacts(self, out_dir: Path) -> list[Path]:
        """Write ``self_touch_body_map.png`` and ``self_touch_region_counts.json``."""
        out_dir = Path(out_dir)
        out_dir.mkdir(parents=True, exist_ok=True)
        picture = draw_body_map_counts(self.region_steps, self.regions, out_dir)
        counts = out_dir / "self_touch_region_counts.json"
        names = (
            [str(n) for n in self.regions.names]
            if self.regions is not None
            else [f"region_{j:02d}" for j in range(NUM_REGIONS)]
        )
        write_text_atomically(
            counts,
            json.dumps(
                {
                    hand: dict(zip(names, map(int, self.region_steps[h])))
                    for h, hand in enumerate(HANDS)
                },
                indent=2,
            )
            + "\n",
        )
        return [picture, counts]


class TrainingScore(RunMetrics):
    """BabyBench's "training score" in our terms: the union, per hand, of the parts touched
    in the run's last ``episodes`` finished training episodes (the paper's 0.88).

    ``training_score`` = (left + right) / 68, where left (right) is the number of the 34
    side-free body parts (the evaluation's parts, :data:`~devlearn_self_touch.body_map`) that
    the left (right) hand's palm or fingers touched in at least one episode of the window.
    The window is global over the run: every environment, env worker and torchrun rank feeds
    it (the runner gathers their episodes in rank order after each PPO iteration), oldest
    episodes dropped first. Logged as ``metrics/training_score``,
    ``metrics/training_coverage_left`` / ``_right`` (parts of 34) and
    ``metrics/training_score_episodes`` (episodes in the window) every iteration once an
    episode has ended; saved in checkpoints, so ``--resume`` continues the same window.

    Where it differs from BabyBench's counter: BabyBench counts MIMo's geoms touched by each
    hand's palm only and credits a palm-to-palm contact to the right hand alone (capping its
    score at 60/68 = 0.88); here a hand is its palm and fingers, both hands are credited for
    a hand-to-hand contact, and a part counts whichever side's region of it was touched
    (the same rule as :class:`SelfTouchEvaluator`). Training episodes credit every step (no
    settle period) and start from the stage's pose (fixed, then random).

    Args:
        episodes: Window length in finished episodes (BabyBench: 10,000).
    """

    def __init__(self, episodes: int = 10_000) -> None:
        if episodes < 1:
            raise ValueError(
                f"the training score's window must be at least 1 episode, got {episodes}"
            )
        self.episodes = int(episodes)
        self.window = np.zeros((self.episodes, len(HANDS), NUM_PARTS), dtype=bool)
        """Ring buffer of the window's episodes, (episodes, 2, 34); slot ``n % episodes``
        holds the n-th episode added."""
        self.counts = np.zeros((len(HANDS), NUM_PARTS), dtype=np.int64)
        """Episodes of the window in which hand h touched part p, (2, 34)."""
        self.added = 0
        """Episodes added (since the run began, or since the checkpoint's window)."""

    def add(self, records: list[Any]) -> None:
        """Append finished episodes' touched parts ((2, 34) bool each), oldest first."""
        for parts in records:
            slot = self.added % self.episodes
            if self.added >= self.episodes:  # the window is full: the oldest episode leaves
                self.counts -= self.window[slot]
            self.window[slot] = np.asarray(parts, dtype=bool)
            self.counts += self.window[slot]
            self.added += 1

    def values(self) -> dict[str, float]:
        if not self.added:
            return {}
        left, right = (int(n) for n in (self.counts > 0).sum(axis=1))
        return {
            "training_score": (left + right) / (2 * NUM_PARTS),
            "training_coverage_left": float(left),
            "training_coverage_right": float(right),
            "training_score_episodes": float(min(self.added, self.episodes)),
        }

    def ordered(self) -> np.ndarray:
        """The window's episodes, oldest first: (min(added, episodes), 2, 34) bool."""
        if self.added <= self.episodes:
            return self.window[: self.added].copy()
        slot = self.added % self.episodes
        return np.concatenate([self.window[slot:], self.window[:slot]])

    def state_dict(self) -> dict[str, Any]:
        """The window's episodes as bits, oldest first: (episodes in it, 2, 5) uint8, a torch
        tensor (checkpoints hold tensors; a packed numpy array pickles through ``bytes``,
        which the checkpoint reader refuses)."""
        import torch

        return {"parts": torch.from_numpy(np.packbits(self.ordered(), axis=-1))}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore :meth:`state_dict`'s output; a shorter window keeps the newest episodes."""
        packed = np.asarray(state["parts"], dtype=np.uint8)
        parts = np.unpackbits(packed, axis=-1, count=NUM_PARTS).astype(bool)
        self.window[:] = False
        self.counts[:] = 0
        self.added = 0
        self.add(list(parts[-self.episodes :]))  # ``added`` restarts at the window's length


def draw_body_map_counts(region_steps: np.ndarray, regions: Any, out_dir: Path) -> Path:
    """Draw how often each hand touched each region: one panel per hand, parts x sides.

    Args:
        region_steps: (2, 68) steps on which hand h touched region j.
        regions: The infant's region table (``.parts``, ``.sides``, ``.part_names``), or None
            (then regions are drawn in index order, 34 per column).
        out_dir: Folder to write into.

    Returns:
        Path of the PNG written.
    """
    from matplotlib.figure import Figure  # no pyplot: no global backend state

    grids = np.zeros((len(HANDS), NUM_PARTS, 2))
    if regions is not None:
        parts, sides = np.asarray(regions.parts), np.asarray(regions.sides)
        labels = [str(n) for n in regions.part_names]
    else:
        parts = np.arange(NUM_REGIONS) % NUM_PARTS
        sides = np.where(np.arange(NUM_REGIONS) < NUM_PARTS, HANDS[0], HANDS[1])
        labels = [f"part_{p:02d}" for p in range(NUM_PARTS)]
    for j in range(NUM_REGIONS):
        grids[:, parts[j], 0 if sides[j] == HANDS[0] else 1] = region_steps[:, j]
    fig = Figure(figsize=(7.5, 10), constrained_layout=True)
    axes = fig.subplots(1, 2, sharey=True)
    vmax = max(1.0, float(np.log1p(grids).max()))
    for h, ax in enumerate(axes):
        image = ax.imshow(np.log1p(grids[h]), aspect="auto", cmap="YlOrRd", vmin=0, vmax=vmax)
        ax.set_title(f"{HANDS[h]} hand ({int((grids[h] > 0).any(axis=1).sum())}/34 parts)")
        ax.set_xticks([0, 1], ["left side", "right side"])
        ax.set_yticks(range(NUM_PARTS), labels, fontsize=7)
    fig.colorbar(image, ax=axes, label="log(1 + steps in contact)", shrink=0.6)
    fig.suptitle("Self-touch: where each hand touched the body")
    path = out_dir / "self_touch_body_map.png"
    write_atomically(path, lambda f: fig.savefig(f, format="png", dpi=110))
    return path
