"""rsl-rl's PPO with one optimiser entry per parameter (no double Adam steps on shared tensors)."""

from __future__ import annotations

import warnings
from itertools import chain
from typing import TYPE_CHECKING, Any

import torch
import torch.nn as nn
from rsl_rl.algorithms import PPO
from rsl_rl.utils import reduce_gradients_in_buckets

if TYPE_CHECKING:
    from rsl_rl.models import MLPModel
    from rsl_rl.storage import RolloutStorage


def unique_parameters(*modules: nn.Module) -> list[nn.Parameter]:
    """Parameters of all ``modules``, each tensor once, in first-seen order."""
    seen: set[int] = set()
    params = []
    for param in chain.from_iterable(m.parameters() for m in modules):
        if id(param) not in seen:
            seen.add(id(param))
            params.append(param)
    return params


class UniqueParamPPO(PPO):
    """PPO whose optimiser holds every parameter once.

    rsl-rl 5.5.1 builds its optimiser over ``chain(actor.parameters(), critic.parameters())``:
    a tensor shared by actor and critic would then get two Adam steps per mini-batch. In our
    shared layout the critic holds the actor's body without registering it (its
    ``parameters()`` are its head alone), so each tensor appears once anyway; but anything
    else that shares registered modules (rsl-rl's own ``share_cnn_encoders`` with its CNN
    models, a behaviour's own sharing) would hit the trap, so the optimiser is rebuilt here
    over unique parameters, and gradients are all-reduced once per tensor when distributed.
    Gradient clipping stays rsl-rl's, per network: the shared body is clipped with the
    policy head (its gradient holds both losses), the value head on its own. ``adam_eps`` is the
    optimiser's epsilon (``ppo.adam_eps``).
    """

    optimizer: torch.optim.Optimizer

    def __init__(
        self,
        actor: MLPModel,
        critic: MLPModel,
        storage: RolloutStorage,
        *args: Any,
        adam_eps: float = 1e-8,
        **kwargs: Any,
    ) -> None:
        with warnings.catch_warnings():  # the parent's optimiser, replaced below, may warn
            warnings.filterwarnings("ignore", message=".*duplicate parameters")
            super().__init__(actor, critic, storage, *args, **kwargs)
        # the parent's optimiser class (Adam...) takes lr; torch's Optimizer base does not
        self.optimizer = type(self.optimizer)(  # type: ignore[call-arg]
            unique_parameters(self.actor, self.critic), lr=self.learning_rate, eps=adam_eps
        )

    def reduce_parameters(self) -> None:
        """Average gradients across ranks, each tensor once."""
        modules = [self.actor, self.critic] + ([self.rnd] if self.rnd else [])
        reduce_gradients_in_buckets(
            unique_parameters(*modules), self.gpu_world_size, self.grad_reduce_bucket_mb
        )
