"""hand_to_mouth: reward the infant for touching its face's target parts with either hand.

Written only against devlearn's public API (``devlearn``, with its Infant).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

import devlearn
from devlearn import RewardTermCfg, StepContext

if TYPE_CHECKING:
    from devlearn import Infant


class MouthContact(devlearn.IntrinsicReward):
    """``contact_reward`` for every step a hand touches a target part, plus a one-off bonus.

    Reads the fact ``mouth_contact`` (bool). The bonus memory is per episode (no lifetime state).
    """

    name = "mouth_contact"

    def __init__(
        self, weight: float = 1.0, contact_reward: float = 1.0, first_bonus: float = 5.0
    ) -> None:
        super().__init__(weight)
        self.contact_reward = contact_reward
        self.first_bonus = first_bonus
        self.reached = False

    def reset(self) -> None:
        self.reached = False

    def __call__(self, ctx: StepContext) -> float:
        if not ctx.facts["mouth_contact"]:
            return 0.0
        bonus = 0.0 if self.reached else self.first_bonus
        self.reached = True
        return self.contact_reward + bonus


class ActionCost(devlearn.IntrinsicReward):
    """Minus ``weight`` times the mean squared action of this step (fact ``action_energy``)."""

    name = "action_cost"

    def __call__(self, ctx: StepContext) -> float:
        return -float(ctx.facts["action_energy"])


def hand_to_mouth_rewards() -> dict[str, RewardTermCfg]:
    """A reward for every step a hand touches the mouth (plus a first-contact bonus) and a
    small cost on the action."""
    return {
        "mouth_contact": RewardTermCfg(
            MouthContact, 1.0, {"contact_reward": 1.0, "first_bonus": 5.0}
        ),
        "action_cost": RewardTermCfg(ActionCost, 0.01),
    }


@dataclass
class HandToMouthConfig(devlearn.BehaviorConfig):
    """Options of the hand_to_mouth behaviour (a ``BehaviorConfig``: it declares the fields
    configs saved before issue #31 held, ``LEGACY_REWARD_KEYS``)."""

    LEGACY_REWARD_KEYS: ClassVar[dict[str, str]] = {
        "contact_reward": "mouth_contact.params.contact_reward",
        "first_contact_bonus": "mouth_contact.params.first_bonus",
        "action_cost": "action_cost.weight",
    }
    """Fields of configs saved before issue #31, now in :attr:`rewards`."""

    target_parts: tuple[str, ...] = ("mouth",)
    """Side-free body-map part names that count as the mouth (see docs/body_map.md)."""
    rewards: dict[str, RewardTermCfg] = field(default_factory=hand_to_mouth_rewards)
    """Term name -> (class, weight, params): ``mouth_contact`` (``contact_reward`` per step a
    hand touches a target part, ``first_bonus`` the first time in an episode) and
    ``action_cost`` (its weight times the mean squared action, subtracted)."""
    stages: list[int] = field(default_factory=lambda: [100_000])
    """Steps of the fixed-pose stage before random initial poses begin."""


class MouthEvaluator(devlearn.Evaluator):
    """Share of steps and of episodes in which a hand touched the mouth."""

    mergeable = True  # merge() below: devlearn eval may play its episodes in several envs

    def __init__(self) -> None:
        self.steps = self.contact_steps = 0
        self.episode_contact_steps = 0
        self.episodes = self.episodes_with_contact = 0

    def record(self, ctx: StepContext) -> None:
        self.steps += 1
        self.episode_contact_steps += int(ctx.facts["mouth_contact"])

    def end_episode(self) -> dict[str, float]:
        self.episodes += 1
        self.contact_steps += self.episode_contact_steps
        self.episodes_with_contact += int(self.episode_contact_steps > 0)
        result = {"reached": float(self.episode_contact_steps > 0)}
        self.episode_contact_steps = 0
        return result

    def summary(self) -> dict[str, Any]:
        return {
            "episodes": self.episodes,
            "steps": self.steps,
            "reached": self.episodes_with_contact / max(self.episodes, 1),
            "contact_fraction": self.contact_steps / max(self.steps, 1),
        }

    def merge(self, later: devlearn.Evaluator) -> None:
        """Add the counts of ``later``'s episodes (``devlearn eval --envs N``)."""
        assert isinstance(later, MouthEvaluator)
        self.steps += later.steps
        self.contact_steps += later.contact_steps
        self.episodes += later.episodes
        self.episodes_with_contact += later.episodes_with_contact


class LastAction(devlearn.EpisodeHooks):
    """One environment's action of the step being taken, for its action cost (its hooks keep
    it; none yet in a new episode, so the first facts pay no action cost)."""

    def __init__(self) -> None:
        self.action = np.zeros(0)

    def on_episode_start(self, infant: Infant, rng: np.random.Generator) -> None:
        self.action = np.zeros(0)

    def before_step(self, infant: Infant, action: np.ndarray) -> None:
        self.action = action


class HandToMouth(devlearn.Behavior):
    """Bring a hand to the mouth, in the crib, from proprioception and touch contacts."""

    name = "hand_to_mouth"
    scene = "crib"
    config_class = HandToMouthConfig
    about = devlearn.About(
        description="example plugin: bring either hand to the mouth", headline_metric="reached"
    )

    def __init__(self, config: HandToMouthConfig | None = None) -> None:
        super().__init__(config)
        self._target: np.ndarray | None = None  # (68,) bool, built from the infant's regions
        self.last_action = LastAction()

    def _target_regions(self, infant: Infant) -> np.ndarray:
        if self._target is None:
            names = list(infant.regions.part_names)
            unknown = [p for p in self.config.target_parts if p not in names]
            if unknown:
                raise ValueError(f"unknown body part(s) {unknown}; valid parts: {names}")
            wanted = [names.index(p) for p in self.config.target_parts]
            self._target = np.isin(np.asarray(infant.regions.parts), wanted)
        return self._target

    # facts and observations for one environment at a time: per_env runs them batched
    @devlearn.per_env
    def facts(self, infant: Infant) -> dict[str, Any]:
        contacts = infant.hand_contacts()  # (2 hands, 68) bool
        action = self.last_action.action
        energy = float(np.mean(np.square(action))) if action.size else 0.0
        return {
            "mouth_contact": bool(np.any(contacts[:, self._target_regions(infant)])),
            "action_energy": energy,
        }

    @devlearn.per_env
    def observe(self, infant: Infant, facts: dict[str, Any]) -> dict[str, np.ndarray]:
        return {"proprioception": infant.proprioception().astype(np.float32)}

    def network(self) -> devlearn.NetworkSpec:
        return devlearn.NetworkSpec(
            encoders={"proprioception": devlearn.MLPEncoder((256,))},
            fusion_dims=(256,),
            trunk_dims=(128, 128),
        )

    def curriculum(self) -> devlearn.Curriculum:
        return devlearn.Curriculum(
            [
                devlearn.Stage("fixed_pose", self.config.stages[0], {"random_pose": False}),
                devlearn.Stage("random_pose", None, {"random_pose": True}),
            ]
        )

    def episode(self) -> devlearn.EpisodeSpec:
        return devlearn.EpisodeSpec(senses=("touch", "proprioception"), hooks=self.last_action)

    def evaluation(self) -> devlearn.EvalProtocol:
        return devlearn.EvalProtocol(evaluator=lambda training: MouthEvaluator())
