"""A run's learned rewards in the training loop: reward and train after each rollout, log, save."""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any

import torch

from devlearn.api.errors import UsageError
from devlearn.api.learned import LearnedReward, Transitions
from devlearn.config.run_config import RunConfig
from devlearn.config.values import convert, field_types
from devlearn.env.guards import GuardError

if TYPE_CHECKING:
    from rsl_rl.storage import RolloutStorage
    from tensordict import TensorDict
    from torch.utils.tensorboard import SummaryWriter

    from devlearn.plugins import PluginRegistry


class LearnedRewards:
    """The learned intrinsic rewards of one run (``RunConfig.curiosity``), in the learner.

    After each rollout, before PPO computes returns, :meth:`apply` builds the batch of
    transitions from rsl-rl's rollout storage, lets every term reward it and train on it
    (:meth:`devlearn.LearnedReward.update`), and adds the weighted rewards to the storage's
    rewards, which PPO then maximises with the behaviour's own. Per iteration it keeps
    ``reward/<name>/step`` (mean weighted reward added per step), ``reward/<name>/raw``
    (mean raw reward: the model's error), ``reward/<name>/loss`` and ``reward/<name>/weight``
    for metrics.jsonl and TensorBoard. Environment worker processes are not involved: the
    models live in the training process and see the batch the workers filled.

    Under ``torchrun`` the ranks **share** their models, as PPO's networks are shared: rank 0's
    initial parameters are broadcast (:meth:`broadcast`), each rank rewards its own rollout,
    and every optimiser step averages the gradients over ranks (as does the reward scale), so
    the models stay identical and rank 0's checkpoint holds them for every rank.

    Args:
        terms: Name -> (class, resolved config).
    """

    def __init__(self, terms: dict[str, tuple[type[LearnedReward], Any]] | None = None) -> None:
        self.specs = dict(terms or {})
        self.terms: dict[str, LearnedReward] = {}
        self.last: dict[str, float] = {}

    @classmethod
    def from_config(cls, cfg: RunConfig, registry: PluginRegistry) -> LearnedRewards:
        """Look up ``cfg.curiosity``'s names and build their configs from ``cfg.learned``.

        Writes every term's resolved options back into ``cfg.learned`` (so config.json
        records them). Call it before the slow set-up: a typo fails at once.

        Raises:
            UsageError: An unknown or repeated name (the installed ones are listed), options
                for a term the run does not use, or an unknown or ill-typed option.
        """
        names = list(cfg.curiosity)
        if len(set(names)) != len(names):
            raise UsageError(f"curiosity names a learned reward twice: {','.join(names)}")
        terms = {name: registry.learned_reward(name) for name in names}
        extra = sorted(set(cfg.learned) - set(names))
        if extra:
            raise UsageError(
                f"options for learned reward(s) {', '.join(extra)} not in curiosity "
                f"({','.join(names) or 'empty'}); add them with --set curiosity=..."
            )
        specs = {}
        for name, term in terms.items():
            specs[name] = (term, _term_config(name, term, cfg.learned.get(name) or {}))
        cfg.learned = {name: dataclasses.asdict(c) for name, (_, c) in specs.items()}
        return cls(specs)

    def __bool__(self) -> bool:
        return bool(self.specs)

    def build(
        self, observation_shapes: dict[str, tuple[int, ...]], action_dim: int, device: str
    ) -> LearnedRewards:
        """Create every term's model and optimiser; return self.

        Raises:
            UsageError: A term rejects these observations (e.g. an unknown group).
        """
        for name, (term, config) in self.specs.items():
            try:
                self.terms[name] = term(config, observation_shapes, action_dim, device)
            except (ValueError, TypeError, KeyError) as exc:
                raise UsageError(f"learned reward '{name}': {exc}") from exc
        return self

    # --- the training loop ----------------------------------------------------------------
    def apply(
        self, storage: RolloutStorage, last_obs: TensorDict, env_steps: int
    ) -> dict[str, float]:
        """Reward the rollout in ``storage``, add it to its rewards and train every term.

        Args:
            storage: rsl-rl's RolloutStorage, full: observations (T, N, ...), actions
                (T, N, A), rewards (T, N, 1), dones (T, N, 1).
            last_obs: The observations after the rollout's last step (TensorDict, (N, ...)).
            env_steps: Environment steps done before this rollout (all ranks).
        Returns:
            This iteration's ``reward/<name>/...`` values (also kept in :attr:`last`).
        """
        if not self.terms:
            return {}
        row: dict[str, float] = {}
        # The rollout ran under inference mode; the models need gradients and normal tensors.
        with torch.inference_mode(False), torch.enable_grad():
            batch, valid = transitions(storage, last_obs)
            for name, term in self.terms.items():
                reward, log = term.update(batch, env_steps)
                _guard(name, reward, valid, storage.actions.shape[1])
                added = torch.zeros(valid.shape, device=storage.rewards.device)
                added[valid] = reward.to(added.device)
                storage.rewards += added.view(storage.rewards.shape)
                row[f"reward/{name}/step"] = float(added.mean())
                row.update({f"reward/{name}/{key}": float(v) for key, v in log.items()})
        self.last = row
        return row

    def write(self, writer: SummaryWriter | None, iteration: int) -> None:
        """Add the last iteration's values to TensorBoard (``writer`` may be None)."""
        if writer is None:
            return
        for key, value in self.last.items():
            writer.add_scalar(key, value, iteration)

    def broadcast(self) -> None:
        """Give every rank rank 0's parameters and buffers (call on all ranks together)."""
        for term in self.terms.values():
            for tensor in list(term.model.state_dict().values()) + [*term.scale.buffers()]:
                torch.distributed.broadcast(tensor, src=0)

    # --- checkpoints ----------------------------------------------------------------------
    def state_dict(self) -> dict[str, Any]:
        """Name -> the term's state (model, optimiser, reward scale, updates)."""
        return {name: term.state_dict() for name, term in self.terms.items()}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore :meth:`state_dict`; the names must be this run's.

        Raises:
            UsageError: The checkpoint holds other learned rewards than ``curiosity`` names.
        """
        if sorted(state) != sorted(self.terms):
            saved = ",".join(sorted(state))
            raise UsageError(
                f"the checkpoint's learned rewards ({saved or 'none'}) differ from this run's "
                f"curiosity ({','.join(sorted(self.terms)) or 'none'}); resume with "
                f"--set curiosity={saved}"
            )
        for name, term in self.terms.items():
            term.load_state_dict(state[name])


class LearnedRewardGuardError(GuardError):
    """A learned reward gave a NaN or infinite value (the run stops at the last good state)."""

    def __init__(self, name: str, value: float, env_index: int, rollout_step: int) -> None:
        self.kind, self.name, self.value = "learned reward", name, float(value)
        self.env_index, self.step = int(env_index), int(rollout_step)
        UsageError.__init__(
            self,
            f"learned reward '{name}' gave {self.value!r} for env {self.env_index} at step "
            f"{self.step} of the rollout (values must be finite)",
        )


def _guard(name: str, reward: torch.Tensor, valid: torch.Tensor, envs: int) -> None:
    """Raise :class:`LearnedRewardGuardError` at the first non-finite reward."""
    bad = ~torch.isfinite(reward)
    if bad.any():
        first = int(bad.nonzero()[0, 0])
        flat = int(valid.nonzero()[first, 0])  # back to the (step, env) of the rollout
        raise LearnedRewardGuardError(name, float(reward[first]), flat % envs, flat // envs)


def transitions(storage: RolloutStorage, last_obs: TensorDict) -> tuple[Transitions, torch.Tensor]:
    """The rollout as (observation, action, next observation) triples, finished ones left out.

    Returns:
        ``(batch, valid)``: the B transitions whose episode went on, and ``valid``, (T * N,)
        bool, which of the flattened (step, env) pairs they are.
    """
    steps, envs = storage.actions.shape[:2]
    observations, following = {}, {}
    for key in storage.observations.keys():
        now = storage.observations[key]
        later = torch.cat([now[1:], last_obs[key].to(now.device).unsqueeze(0)])
        observations[key] = now.reshape(steps * envs, *now.shape[2:]).clone()
        following[key] = later.reshape(steps * envs, *now.shape[2:]).clone()
    actions = storage.actions.reshape(steps * envs, -1).clone()
    valid = storage.dones.reshape(-1) == 0
    return Transitions(observations, actions, following).select(valid), valid


def _term_config(name: str, term: type[LearnedReward], options: dict[str, Any]) -> Any:
    """Build ``term.config_class`` from ``options`` (strings from --set, or saved values)."""
    config = term.config_class()
    fields = [f.name for f in dataclasses.fields(config)]
    hints = field_types(config)
    for key, value in options.items():
        if key not in fields:
            raise UsageError(
                f"unknown option 'learned.{name}.{key}'; valid options: {', '.join(fields)}"
            )
        setattr(config, key, convert(value, hints.get(key, Any), f"learned.{name}.{key}"))
    try:
        config = dataclasses.replace(config)  # runs the config's own checks (__post_init__)
    except (ValueError, TypeError) as exc:
        raise UsageError(f"invalid options for learned reward '{name}': {exc}") from exc
    return config
