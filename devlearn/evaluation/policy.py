"""What ``devlearn eval`` evaluates, as one type: a :class:`Policy` is a devlearn checkpoint (or
policy file), another learner's scripted policy
(:class:`~devlearn.evaluation.scripted_policy.ScriptedPolicy`) or a baseline (zero, random,
held_random), and every kind answers the same few questions; its :class:`Actions` choose each
decision's action in one evaluation, with their own randomness."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

import numpy as np
import torch

from devlearn.config.run_config import to_dict
from devlearn.training.checkpoint import Checkpoint
from devlearn.training.health import SATURATED

if TYPE_CHECKING:
    from devlearn.api.behavior import Behavior
    from devlearn.config.run_config import RunConfig
    from devlearn.training.networks import MultiSenseModel

BASELINES = ("zero", "random", "held_random")
"""The baselines: zero action; actions uniform in [-1, 1] drawn afresh every decision (i.i.d.);
``held_random``: uniform actions each held for :data:`HOLD_STEPS` physics steps on average."""
HOLD_STEPS = 8
"""Mean physics steps a ``held_random`` baseline action is held (40 ms at 200 Hz)."""

Observations = dict[str, np.ndarray]
"""A batch of observations: group name -> (N, *shape) array, one row per env."""


class Policy(Protocol):
    """What an evaluation needs of the policy it plays: what it is, what it trained for, the
    behaviour and config it acts under, and its actions.

    Implemented by :class:`CheckpointPolicy` (a devlearn checkpoint or policy file),
    :class:`~devlearn.evaluation.scripted_policy.ScriptedPolicy` (another learner's policy
    file) and :class:`Baseline` (zero, random, held_random).
    """

    @property
    def name(self) -> str:
        """What eval.json's ``policy`` says: ``checkpoint`` for any policy file (devlearn's or
        another learner's), else the baseline's name (:data:`BASELINES`)."""
        ...

    @property
    def path(self) -> Path | None:
        """The file it was read from (eval.json's ``checkpoint``); None: a baseline."""
        ...

    @property
    def learner(self) -> str | None:
        """Who trained it where not devlearn (``sb3_ppo``...; eval.json's ``learner``, which
        ``devlearn report`` tells learners apart by); None: devlearn, or a baseline."""
        ...

    @property
    def env_steps(self) -> int | None:
        """Physics steps it trained for, summed over its environments (devlearn's count: a
        decision of ``env.action_repeat`` K counts K); None: a baseline, or a file that does
        not say."""
        ...

    @property
    def config(self) -> RunConfig:
        """The config it acts under: the one it trained with, or a baseline's."""
        ...

    @property
    def saved_config(self) -> dict[str, Any]:
        """Its config as eval.json records it: as its file saved it (keys a newer devlearn
        added left out, so ``devlearn report`` groups it as saved), a baseline's as
        :func:`~devlearn.config.run_config.to_dict` writes it."""
        ...

    @property
    def age_months(self) -> float | None:
        """The body's age it acts in unless the evaluation sets another: where it last
        trained, a baseline's config's (None: the default body)."""
        ...

    def behavior(self) -> Behavior:
        """Its behaviour under :attr:`config`, with the artifacts it carries (hand regard's
        detector calibration); built once."""
        ...

    def actions(self, obs: Observations, action_dim: int, seed: int, action: str) -> Actions:
        """Its actions in one evaluation, in their initial state, for batches of ``obs``'s
        size (the first observation of its envs, which a network is built for).

        Args:
            obs: The envs' first observations, (N, *shape) per group.
            action_dim: Number of actions.
            seed: The evaluation seed (a baseline's draws; a checkpoint samples from torch's
                global generator, seeded with it before the network is built).
            action: One of :data:`~devlearn.evaluation.evaluate.ACTIONS`: ``mean``, or (a
                devlearn checkpoint's; the others act as they are) ``sample`` (drawn from the
                policy's distribution) or ``expected_clipped`` (the action the env applies
                on average when the policy samples).
        """
        ...


# --- actions: how each decision's action is chosen, with their own randomness ---------------


class Actions:
    """A policy's actions in one evaluation: ``act(obs) -> (N, action_dim)``.

    A slot starting at episode k first calls :meth:`skip` with k episodes' decisions, so that
    its randomness is where the reference's (one env, every episode in order) is then.

    Args:
        rows: The batch size it acts on (N).
        action_dim: Number of actions.
    """

    def __init__(self, rows: int, action_dim: int) -> None:
        self.rows = rows
        self.action_dim = action_dim

    def act(self, obs: Observations) -> np.ndarray:
        """The actions for a batch of observations ((N, *shape) per group): (N, action_dim)."""
        raise NotImplementedError

    def skip(self, decisions: int) -> None:
        """Draw what ``decisions`` decisions would draw, without acting (nothing by default)."""

    def rng_state(self) -> Any:
        """The state of the actions' own randomness (None: they have none)."""
        return None

    def for_slot(self) -> Actions:
        """A copy in this initial state for one slot."""
        return copy.deepcopy(self)

    def episode_figures(self) -> dict[str, float]:
        """Figures of the policy itself over the episode just ended, counted afresh for the
        next (none by default; a network's: :class:`ActorActions`)."""
        return {}


class ZeroActions(Actions):
    """The zero action."""

    def act(self, obs: Observations) -> np.ndarray:
        return np.zeros((self.rows, self.action_dim))


class SeededActions(Actions):
    """A baseline's actions drawn from its own generator (``self.rng``), whatever it sees."""

    rng: np.random.Generator

    def skip(self, decisions: int) -> None:
        """Baselines do not read the observation: the same draws, without one."""
        for _ in range(decisions):
            self.act({})

    def rng_state(self) -> Any:
        return self.rng.bit_generator.state


class UniformActions(SeededActions):
    """Actions uniform in [-1, 1], drawn afresh every decision from the evaluation seed's
    stream ``[seed, 1]`` (apart from the env's)."""

    def __init__(self, rows: int, action_dim: int, seed: int) -> None:
        super().__init__(rows, action_dim)
        self.rng = np.random.default_rng([seed, 1])

    def act(self, obs: Observations) -> np.ndarray:
        return self.rng.uniform(-1.0, 1.0, (self.rows, self.action_dim))


class HeldActions(SeededActions):
    """Uniform actions each held for :data:`HOLD_STEPS` physics steps on average: every
    actuator redraws with probability ``repeat / HOLD_STEPS`` per decision (stream
    ``[seed, 2]``)."""

    def __init__(self, rows: int, action_dim: int, seed: int, repeat: int) -> None:
        super().__init__(rows, action_dim)
        self.rng = np.random.default_rng([seed, 2])
        self.held = self.rng.uniform(-1.0, 1.0, (rows, action_dim))
        self.redraw = min(1.0, repeat / HOLD_STEPS)

    def act(self, obs: Observations) -> np.ndarray:
        redraw = self.rng.random((self.rows, self.action_dim)) < self.redraw
        self.held[redraw] = self.rng.uniform(-1.0, 1.0, int(redraw.sum()))
        return self.held.copy()


class ActorActions(Actions):
    """A checkpoint's policy network: its mean action, or (``sample``) an action drawn from its
    distribution with torch's generator in ``generator_state`` (the state torch's global
    generator had after the network was built, as in one env evaluating in order), kept per
    slot."""

    def __init__(
        self,
        actor: MultiSenseModel,
        rows: int,
        action_dim: int,
        sample: bool,
        generator_state: torch.Tensor,
        expected: bool = False,
    ) -> None:
        super().__init__(rows, action_dim)
        self.actor = actor
        self.sample = sample
        self.expected = expected
        self.state = generator_state.clone()
        self.noise: Any = None  # this slot's coloured exploration (network.exploration_beta)
        self.at_bound = 0  # mean components at or past the bounds, this episode
        self.components = 0

    def _coloured(self) -> bool:
        """Whether the head samples with coloured noise (its streams are then this slot's)."""
        return bool(self.sample and getattr(self.actor.distribution, "noise_beta", 0.0))

    def act(self, obs: Observations) -> np.ndarray:
        from tensordict import TensorDict

        batch = TensorDict({k: torch.from_numpy(v) for k, v in obs.items()}, [self.rows])
        if self.sample:
            torch.set_rng_state(self.state)
        if self._coloured():  # the shared network draws from this slot's streams
            self.actor.distribution.noise_streams = self.noise
        with torch.inference_mode():
            if self.expected:  # one pass: the head's mean as played, and its distribution
                dist = self.actor.distribution
                out = self.actor.mlp(self.actor.get_latent(batch))
                mean = dist.deterministic_output(out).numpy()
                dist.update(out)
                action = expected_clipped(dist.mean, dist.std).numpy()
            else:
                action = self.actor(batch, stochastic_output=self.sample).numpy()
                # the mean as the head plays it (clipped, or squashed); no draw from the generator
                mean = self.actor(batch).numpy() if self.sample else action
        if self.sample:
            self.state = torch.get_rng_state()
        if self._coloured():
            self.noise = self.actor.distribution.noise_streams
        self.at_bound += int((np.abs(mean) >= SATURATED).sum())
        self.components += mean.size
        return action

    def episode_figures(self) -> dict[str, float]:
        """``mean_at_bound``: the share of the mean action's components at the action
        bounds over the episode's decisions: the deterministic action (the mean clipped to
        [-1, 1] as the env applies it, or squashed by the head) at magnitude >=
        :data:`~devlearn.training.health.SATURATED` (the threshold of training's
        ``health/saturated``). A mean at or past a bound plays the bound, and a sample past
        it is clipped to the same action (issue #54). Counted with sampled actions too (the
        mean beside the samples)."""
        share = self.at_bound / self.components if self.components else 0.0
        self.at_bound = self.components = 0
        return {"mean_at_bound": share}

    def skip(self, decisions: int) -> None:
        """A sampled action is ``torch.normal(mean, std)`` of shape (N, action_dim): one
        standard normal fill of that shape per decision, whatever the mean and spread. With
        coloured exploration it is mean + std * the slot's streams' next value
        (:class:`~devlearn.training.distribution.ColoredNoise`), made on the first decision:
        the streams advance as acting would advance them."""
        if not self.sample or not decisions:
            return
        torch.set_rng_state(self.state)
        if self._coloured():
            dist = self.actor.distribution
            dist.noise_streams = self.noise
            for _ in range(decisions):
                dist.next_noise((self.rows, self.action_dim))
            self.noise = dist.noise_streams
        else:
            noise = torch.empty(self.rows, self.action_dim)
            for _ in range(decisions):
                noise.normal_()
        self.state = torch.get_rng_state()

    def rng_state(self) -> Any:
        return self.state.numpy().tobytes() if self.sample else None

    def for_slot(self) -> Actions:
        return copy.deepcopy(self, {id(self.actor): self.actor})  # one network, shared


def expected_clipped(mu: torch.Tensor, sigma: torch.Tensor) -> torch.Tensor:
    """``E[clip(X, -1, 1)]`` for ``X ~ N(mu, sigma)``, per component: the action the env
    applies on average when a policy with a linear-mean Gaussian head samples (its samples are
    clipped to the action bounds). A mean past a bound plays the bound; this action instead
    gives the bound only in the share of samples past it, as training saw them.

    With ``a = (-1 - mu) / sigma`` and ``b = (1 - mu) / sigma``:
    ``-P(X < -1) + P(X > 1) + mu (Phi(b) - Phi(a)) + sigma (phi(a) - phi(b))``."""
    a, b = (-1.0 - mu) / sigma, (1.0 - mu) / sigma
    unit = torch.distributions.Normal(0.0, 1.0)
    cdf_a, cdf_b = unit.cdf(a), unit.cdf(b)
    pdf_a, pdf_b = unit.log_prob(a).exp(), unit.log_prob(b).exp()
    inside = mu * (cdf_b - cdf_a) + sigma * (pdf_a - pdf_b)
    return (-cdf_a + (1.0 - cdf_b) + inside).clamp(-1.0, 1.0)


def batch_of_one(obs: dict[str, Any]) -> Observations:
    """One env's observation (name -> unbatched array) as a batch of one, copied: (1, *shape)
    per group."""
    return {k: np.array(v)[None] for k, v in obs.items()}


def batch_rows(obs: Observations) -> int:
    """The number of rows (N) of a batch of observations."""
    return len(next(iter(obs.values())))


# --- the kinds of policy ---------------------------------------------------------------------


class CheckpointPolicy(Checkpoint):
    """A devlearn checkpoint or policy file (:class:`~devlearn.training.checkpoint.Checkpoint`,
    opened with :meth:`~devlearn.training.checkpoint.Checkpoint.open`) as a :class:`Policy`:
    its network's mean action, or one sampled from its distribution."""

    name: ClassVar[str] = "checkpoint"
    learner: ClassVar[str | None] = None

    def actions(self, obs: Observations, action_dim: int, seed: int, action: str) -> Actions:
        """Its network, built for ``obs`` (torch's global generator draws its initialisation
        and then, with ``sample``, its actions).

        Raises:
            UsageError: ``expected_clipped`` with a head whose samples the env never clips
                (``squashed``: its deterministic action is already the squashed mean).
        """
        from devlearn.api.errors import UsageError
        from devlearn.training.distribution import SquashedGaussian

        actor = self.actor({k: v[0] for k, v in obs.items()}, action_dim)
        if action == "expected_clipped" and isinstance(actor.distribution, SquashedGaussian):
            raise UsageError(
                "--action expected_clipped: this policy's head is squashed (network.head="
                "squashed), whose samples never reach the env's clip; valid: mean, sample"
            )
        return ActorActions(
            actor,
            batch_rows(obs),
            action_dim,
            action == "sample",
            torch.get_rng_state(),
            expected=action == "expected_clipped",
        )


class Baseline:
    """A baseline (:data:`BASELINES`) as a :class:`Policy`: no file, no training, its
    behaviour under a config resolved for it.

    Args:
        name: One of :data:`BASELINES`.
        config: Its config (:func:`~devlearn.evaluation.evaluate.baseline_config`).
        behavior: Its behaviour, built under ``config``.
    """

    path = None
    learner = None
    env_steps = None

    def __init__(self, name: str, config: RunConfig, behavior: Behavior) -> None:
        if name not in BASELINES:
            raise ValueError(f"unknown baseline '{name}'; valid: {', '.join(BASELINES)}")
        self.name = name
        self.config = config
        self._behavior = behavior

    @property
    def saved_config(self) -> dict[str, Any]:
        return to_dict(self.config)

    @property
    def age_months(self) -> float | None:
        return self.config.infant.age_months

    def behavior(self) -> Behavior:
        return self._behavior

    def actions(self, obs: Observations, action_dim: int, seed: int, action: str) -> Actions:
        """Zero, uniform or held-uniform actions seeded by ``seed`` (``action`` is not a
        baseline's: it acts as it is named)."""
        rows = batch_rows(obs)
        if self.name == "zero":
            return ZeroActions(rows, action_dim)
        if self.name == "random":
            return UniformActions(rows, action_dim, seed)
        return HeldActions(rows, action_dim, seed, self.config.env.action_repeat)
