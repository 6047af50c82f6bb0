"""The LearnedReward interface: an intrinsic reward that is a model trained on the rollouts."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

if TYPE_CHECKING:  # torch loads when a term is built (training), not when a plugin registers it
    import torch
    import torch.nn as nn


@dataclass
class LearnedRewardConfig:
    """Options every learned reward has; a term's ``config_class`` subclasses this."""

    weight: float = 0.1
    """Weight of the (normalised) term in the reward PPO maximises, added to the behaviour's
    own reward at every step."""
    final_weight: float | None = None
    """Weight at ``schedule_end`` (None: the weight stays ``weight``). Between
    ``schedule_start`` and ``schedule_end`` (env steps, all ranks) it moves linearly; equal
    start and end give a step change."""
    schedule_start: int = 0
    """Env step where the weight schedule starts moving from ``weight``."""
    schedule_end: int = 0
    """Env step where the weight schedule reaches ``final_weight``."""
    learning_rate: float = 1e-3
    """Adam step size of the term's own optimiser."""
    epochs: int = 1
    """Passes over each rollout batch per iteration."""
    mini_batches: int = 4
    """Mini-batches per pass."""
    normalize: bool = True
    """Divide the raw reward by its running standard deviation (over every transition seen so
    far), so the weight means the same whatever the model's error scale (Burda et al. 2018
    divide by a running std too; there of the intrinsic return)."""

    def __post_init__(self) -> None:
        if self.epochs < 1 or self.mini_batches < 1:
            raise ValueError(
                f"epochs and mini_batches must be at least 1, got "
                f"{self.epochs} and {self.mini_batches}"
            )
        if self.learning_rate <= 0:
            raise ValueError(f"learning_rate must be positive, got {self.learning_rate}")
        if self.final_weight is not None and self.schedule_end < self.schedule_start:
            raise ValueError(
                f"schedule_end ({self.schedule_end}) is before schedule_start "
                f"({self.schedule_start})"
            )


@dataclass
class Transitions:
    """A batch of transitions from one rollout, flattened over (steps, envs).

    Transitions whose episode ended at that step are left out: there the environment has
    already reset, so the "next" observation is the next episode's first one.

    Attributes:
        observations: Name -> (B, *shape) tensor, the observation the action was taken in.
        actions: (B, action_dim) float actions, as the policy sampled them.
        next_observations: Name -> (B, *shape) tensor, the observation after the action.
    """

    observations: dict[str, torch.Tensor]
    actions: torch.Tensor
    next_observations: dict[str, torch.Tensor]

    def __len__(self) -> int:
        return int(self.actions.shape[0])

    def select(self, index: torch.Tensor) -> Transitions:
        """Return the transitions at ``index`` (a (b,) long or (B,) bool tensor)."""
        return Transitions(
            {k: v[index] for k, v in self.observations.items()},
            self.actions[index],
            {k: v[index] for k, v in self.next_observations.items()},
        )


class LearnedReward(ABC):
    """An intrinsic reward computed from a model that learns: prediction error, novelty...

    Unlike an :class:`~devlearn.IntrinsicReward`, which lives inside one environment and sees
    one step, a learned reward lives in the learner (one instance per training process, on the
    networks' device). After every rollout the runner gives it the whole batch of
    :class:`Transitions`; it computes each transition's raw reward with the current model
    (:meth:`compute_reward`, no gradient), then trains the model on the same batch with its
    own optimiser (:meth:`compute_loss`, ``epochs`` x ``mini_batches`` Adam steps). The raw
    reward is divided by its running std (``normalize``), multiplied by the scheduled weight
    and added to every step's reward before PPO computes returns. Behaviours do not change:
    a run adds terms by config (``--set curiosity=rnd,forward_model``); plugins register
    them with the ``register_learned_rewards`` hook.

    Subclasses set ``name`` (and ``config_class``, a :class:`LearnedRewardConfig` subclass)
    and implement :meth:`build`, :meth:`compute_reward` and :meth:`compute_loss`. Parameters of
    :attr:`model` with ``requires_grad`` are trained (freeze a fixed target with
    ``requires_grad_(False)``). :meth:`state_dict` holds the model, optimiser and reward
    scale (tensors, numbers, strings, lists and dicts only: checkpoints load with
    ``weights_only``).

    Args:
        config: The term's options (an instance of ``config_class``).
        observation_shapes: Observation name -> shape without batch (e.g. ``(64, 64, 3)``).
        action_dim: Size of the action vector.
        device: Torch device of the model.
    """

    name: ClassVar[str]
    """Unique name used in config (``curiosity=NAME``) and logs (``reward/NAME/...``)."""
    description: ClassVar[str] = ""
    """One line for ``devlearn plugins``."""
    config_class: ClassVar[type] = LearnedRewardConfig
    """Dataclass of the term's options (subclass of :class:`LearnedRewardConfig`)."""

    def __init__(
        self,
        config: Any,
        observation_shapes: dict[str, tuple[int, ...]],
        action_dim: int,
        device: str = "cpu",
    ) -> None:
        from devlearn.api.learned_update import RunningScale

        self.config = config
        self.observation_shapes = {k: tuple(v) for k, v in observation_shapes.items()}
        self.action_dim = int(action_dim)
        self.device = device
        self.model = self.build().to(device)
        self.optimizer = self.make_optimizer()
        self.scale = RunningScale()
        self.updates = 0

    @abstractmethod
    def build(self) -> nn.Module:
        """Return the term's networks (read ``self.config``, ``self.observation_shapes``)."""

    @abstractmethod
    def compute_reward(self, batch: Transitions) -> torch.Tensor:
        """Return each transition's raw (unweighted, unnormalised) reward, (B,) float.

        Called under ``torch.no_grad()`` before the model trains on the batch.
        """

    @abstractmethod
    def compute_loss(self, batch: Transitions) -> torch.Tensor:
        """Return the model's training loss on a mini-batch, a scalar with gradient."""

    def make_optimizer(self) -> torch.optim.Optimizer:
        """The term's optimiser: Adam over :attr:`model`'s trainable parameters."""
        import torch

        params = [p for p in self.model.parameters() if p.requires_grad]
        return torch.optim.Adam(params, lr=self.config.learning_rate)

    def observe(self, batch: Transitions) -> None:
        """Update running statistics of the inputs (e.g. an observation normaliser) with a
        rollout batch; called once per iteration before :meth:`compute_reward`."""

    def weight_at(self, env_steps: int) -> float:
        """The scheduled weight after ``env_steps`` environment steps (all ranks)."""
        cfg = self.config
        if cfg.final_weight is None or env_steps < cfg.schedule_start:
            return float(cfg.weight)
        if env_steps >= cfg.schedule_end:
            return float(cfg.final_weight)
        progress = (env_steps - cfg.schedule_start) / (cfg.schedule_end - cfg.schedule_start)
        return float(cfg.weight + (cfg.final_weight - cfg.weight) * progress)

    def update(self, batch: Transitions, env_steps: int) -> tuple[torch.Tensor, dict[str, float]]:
        """Reward a rollout batch, then train on it (the runner calls this once an iteration).

        Every rank calls it together when distributed: gradients and the reward scale are
        averaged over ranks, so all ranks keep the same model.

        Args:
            batch: The rollout's transitions (B of them, on the model's device).
            env_steps: Environment steps done before this rollout (all ranks).
        Returns:
            ``(reward, log)``: the weighted, normalised reward, (B,); and ``raw`` (mean raw
            reward), ``loss`` (mean training loss), ``weight`` (the scheduled weight).
        """
        import torch

        from devlearn.api.learned_update import average_gradients, distributed

        cfg = self.config
        self.model.train()
        self.observe(batch)
        with torch.no_grad():
            raw = (
                self.compute_reward(batch).float().reshape(-1)
                if len(batch)
                else torch.zeros(0, device=self.device)
            )
        if cfg.normalize:
            self.scale.update(raw)
            reward = self.scale(raw)
        else:
            reward = raw
        weight = self.weight_at(env_steps)
        params = [p for group in self.optimizer.param_groups for p in group["params"]]
        losses = []
        for _ in range(cfg.epochs):
            order = torch.randperm(len(batch), device=raw.device)
            for index in torch.tensor_split(order, cfg.mini_batches):
                if not len(index) and not distributed():
                    continue
                self.optimizer.zero_grad(set_to_none=False)
                if len(index):  # an empty chunk still joins the ranks' gradient average
                    loss = self.compute_loss(batch.select(index))
                    loss.backward()
                    losses.append(float(loss.detach()))
                average_gradients(params)
                self.optimizer.step()
        self.updates += 1
        mean_raw = float(raw.mean()) if raw.numel() else 0.0
        mean_loss = sum(losses) / len(losses) if losses else 0.0
        return weight * reward, {"raw": mean_raw, "loss": mean_loss, "weight": weight}

    def state_dict(self) -> dict[str, Any]:
        """Model parameters and buffers, optimiser state, reward scale and update count."""
        return {
            "model": self.model.state_dict(),
            "optimizer": self.optimizer.state_dict(),
            "scale": self.scale.state_dict(),
            "updates": self.updates,
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`state_dict` returned (resume continues training the model)."""
        self.model.load_state_dict(state["model"])
        self.optimizer.load_state_dict(state["optimizer"])
        self.scale.load_state_dict(state["scale"])
        self.updates = int(state["updates"])
