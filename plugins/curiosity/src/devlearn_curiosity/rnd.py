"""Random network distillation (Burda et al. 2018) as a devlearn learned reward, on rsl-rl's RND."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from devlearn import LearnedReward, LearnedRewardConfig, Transitions

if TYPE_CHECKING:  # torch and rsl-rl load when a run builds the term, not when it registers
    import torch
    import torch.nn as nn
    from rsl_rl.extensions import RandomNetworkDistillation


@dataclass
class RNDConfig(LearnedRewardConfig):
    """Options of ``rnd`` (plus the common ones: weight, schedule, learning rate...)."""

    observations: list[str] = field(default_factory=list)
    """Observations whose novelty is measured, concatenated (1-D ones only, as rsl-rl's RND;
    empty: every 1-D observation, e.g. hand regard's ``proprioception``)."""
    embedding_dim: int = 32
    """Output size of the target and predictor networks."""
    predictor_dims: list[int] = field(default_factory=lambda: [128, 128])
    """Hidden layers of the trained predictor."""
    target_dims: list[int] = field(default_factory=lambda: [128, 128])
    """Hidden layers of the fixed random target."""
    normalize_observations: bool = True
    """Standardise the input by its running mean and std (rsl-rl's EmpiricalNormalization);
    without it, joint velocities and torques of mixed scales dominate the novelty."""


class RND(LearnedReward):
    """Novelty as the error of a predictor trained to match a fixed random network.

    A target network with random, frozen weights embeds the *next* observation; a predictor
    learns to reproduce that embedding on every rollout. States seen often are predicted well
    (low reward), new ones badly (high reward): r = ||target(s') - predictor(s')||.

    The networks, input normaliser, loss and optimiser are rsl-rl's own
    ``RandomNetworkDistillation`` (built with weight 1 and no reward normalisation, so it
    returns the plain distance). Its per-step reward path is not used: rsl-rl calls it on
    every env step with a weight schedule counted in calls, a discounted-return normaliser fed
    one step at a time, and a weight scaled by ``step_dt``; a devlearn learned reward instead
    rewards and trains on the whole rollout batch, normalises by the running std of the raw
    reward, and schedules its weight in environment steps. rsl-rl's RND takes only 1-D
    observations, so images are refused here (``forward_model`` handles the eyes).
    """

    name = "rnd"
    model: RandomNetworkDistillation  # rsl-rl's RND (:meth:`build`)
    description = "random network distillation: a predictor chasing a fixed random net"
    config_class = RNDConfig

    def build(self) -> nn.Module:
        from rsl_rl.extensions import RandomNetworkDistillation

        shapes = self.observation_shapes
        groups = list(self.config.observations) or [k for k, s in shapes.items() if len(s) == 1]
        for group in groups:
            if group not in shapes:
                raise ValueError(f"unknown observation '{group}'; available: {', '.join(shapes)}")
            if len(shapes[group]) != 1:
                raise ValueError(
                    f"rnd works on 1-D observations (rsl-rl's RND); '{group}' has shape "
                    f"{shapes[group]}: use forward_model for images"
                )
        if not groups:
            raise ValueError(f"no 1-D observation to measure novelty on; have {dict(shapes)}")
        self.groups = groups
        cfg = self.config
        rnd = RandomNetworkDistillation(
            num_states=sum(shapes[g][0] for g in groups),
            obs_groups={"rnd_state": groups},
            num_outputs=cfg.embedding_dim,
            predictor_hidden_dims=list(cfg.predictor_dims),
            target_hidden_dims=list(cfg.target_dims),
            state_normalization=cfg.normalize_observations,
            reward_normalization=False,
            weight=1.0,
            learning_rate=cfg.learning_rate,
            device=self.device,
        )
        rnd.target.requires_grad_(False)  # fixed: rsl-rl only detaches its output
        return rnd

    def make_optimizer(self) -> torch.optim.Optimizer:
        """rsl-rl's RND optimiser: Adam over the predictor."""
        return self.model.optimizer

    def _states(self, batch: Transitions) -> dict[str, torch.Tensor]:
        return {g: batch.next_observations[g].float() for g in self.groups}

    def observe(self, batch: Transitions) -> None:
        """Update the input normaliser with the rollout's next observations."""
        if len(batch):
            self.model.update_normalization(self._states(batch))

    def compute_reward(self, batch: Transitions) -> torch.Tensor:
        """(B,) distance between target and predictor embeddings of the next observation."""
        return self.model.get_intrinsic_reward(self._states(batch))

    def compute_loss(self, batch: Transitions) -> torch.Tensor:
        """Mean squared error between predictor and target embeddings."""
        return self.model.compute_loss(self._states(batch))
