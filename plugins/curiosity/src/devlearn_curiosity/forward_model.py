"""A forward self-model: predicts the next encoded observation; its error is the reward."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, cast

from devlearn import LearnedReward, LearnedRewardConfig, Transitions

if TYPE_CHECKING:  # torch and rsl-rl load when a run builds the term, not when it registers
    import torch
    import torch.nn as nn


@dataclass
class ForwardModelConfig(LearnedRewardConfig):
    """Options of ``forward_model`` (plus the common ones: weight, schedule, learning rate...)."""

    observations: list[str] = field(default_factory=list)
    """Observations whose consequences are predicted (empty: every image observation, e.g.
    hand regard's ``left_eye`` and ``right_eye``; every observation if there is no image)."""
    image_features: int = 64
    """Features per image from the fixed random CNN."""
    hidden_dims: list[int] = field(default_factory=lambda: [256, 256])
    """Hidden layers of the predictor."""


class ForwardModel(LearnedReward):
    """A self-model of the body's effect on the senses: reward is how wrong it was.

    Each chosen observation is encoded by a fixed map: images by
    :class:`~devlearn_curiosity.image_features.RandomImageFeatures`, vectors as they are; the
    concatenation φ is standardised by running statistics. An MLP predicts the change of φ over
    one step from (φ(s), a); the reward of a transition is the mean squared error of
    φ(s) + f(φ(s), a) against φ(s'). Consequences the model has learned (a still scene, a hand
    moved in plain view many times) stop paying; new visual consequences of motor actions pay,
    the self-model of the paper's future work (sec. IV).
    """

    name = "forward_model"
    description = "forward self-model: error predicting the next (eye) features from the action"
    config_class = ForwardModelConfig
    model: nn.ModuleDict  # encoders, normalizer, predictor (:meth:`build`)

    def build(self) -> nn.Module:
        import torch
        import torch.nn as nn
        from rsl_rl.modules import MLP, EmpiricalNormalization

        from devlearn_curiosity.image_features import RandomImageFeatures

        shapes = self.observation_shapes
        images = [k for k, s in shapes.items() if len(s) == 3]
        groups = list(self.config.observations) or images or list(shapes)
        encoders, size = nn.ModuleDict(), 0
        for group in groups:
            if group not in shapes:
                raise ValueError(f"unknown observation '{group}'; available: {', '.join(shapes)}")
            shape = shapes[group]
            if len(shape) == 3:
                encoders[group] = RandomImageFeatures(shape[-1], self.config.image_features)
                size += self.config.image_features
            else:
                encoders[group] = nn.Flatten()
                size += int(torch.Size(shape).numel())
        self.groups = groups
        return nn.ModuleDict(
            {
                "encoders": encoders,
                "normalizer": EmpiricalNormalization(size, until=int(1e8)),
                "predictor": MLP(
                    size + self.action_dim, size, list(self.config.hidden_dims), "elu"
                ),
            }
        )

    def _raw_features(self, observations: dict[str, torch.Tensor]) -> torch.Tensor:
        import torch

        encoders = cast("nn.ModuleDict", self.model["encoders"])
        with torch.no_grad():
            return torch.cat([encoders[g](observations[g].float()) for g in self.groups], dim=1)

    def encode(self, observations: dict[str, torch.Tensor]) -> torch.Tensor:
        """φ, the standardised encoding: (B, D)."""
        return self.model["normalizer"](self._raw_features(observations))

    def observe(self, batch: Transitions) -> None:
        """Update the encoding's running mean and std with the rollout."""
        if len(batch):
            cast(Any, self.model["normalizer"]).update(self._raw_features(batch.observations))

    def errors(self, batch: Transitions) -> torch.Tensor:
        """(B,) mean squared error of the predicted next encoding."""
        import torch

        now = self.encode(batch.observations)
        target = self.encode(batch.next_observations)
        actions = batch.actions.float()
        predicted = now + self.model["predictor"](torch.cat([now, actions], dim=1))
        return (predicted - target).square().mean(dim=1)

    def compute_reward(self, batch: Transitions) -> torch.Tensor:
        return self.errors(batch)

    def compute_loss(self, batch: Transitions) -> torch.Tensor:
        return self.errors(batch).mean()
