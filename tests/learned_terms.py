"""Small learned rewards for core tests (the core's tests never import devlearn-curiosity)."""

from __future__ import annotations

from dataclasses import dataclass

import torch
import torch.nn as nn

from devlearn.api.learned import LearnedReward, LearnedRewardConfig, Transitions


@dataclass
class LinearConfig(LearnedRewardConfig):
    """Options of the linear next-state predictor."""

    group: str = "proprioception"
    """The (D,) observation predicted."""


class LinearPredictor(LearnedReward):
    """Predicts the next value of one vector observation linearly; reward = squared error."""

    name = "linear"
    config_class = LinearConfig

    def build(self) -> nn.Module:
        size = self.observation_shapes[self.config.group][0]
        return nn.Linear(size + self.action_dim, size)

    def errors(self, batch: Transitions) -> torch.Tensor:
        group = self.config.group
        x = torch.cat([batch.observations[group].float(), batch.actions], dim=1)
        return (self.model(x) - batch.next_observations[group].float()).square().sum(dim=1)

    def compute_reward(self, batch: Transitions) -> torch.Tensor:
        return self.errors(batch)

    def compute_loss(self, batch: Transitions) -> torch.Tensor:
        return self.errors(batch).mean()


class ForgetfulPredictor(LinearPredictor):
    """A broken term: its state leaves out the optimiser."""

    name = "forgetful"

    def state_dict(self):
        state = super().state_dict()
        state["optimizer"] = type(self)(
            self.config, self.observation_shapes, self.action_dim
        ).optimizer.state_dict()
        return state
