"""One environment: an infant body driven by a behaviour's observations, rewards and metrics."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from devlearn.api.errors import UsageError
from devlearn.api.rewards import (
    BatchContext,
    BatchedFromPerEnv,
    BatchedIntrinsicReward,
    StepContext,
    as_batched,
)
from devlearn.env.batch_advance import (
    advance_batch,
    apply_action,
    clipped_actions,
    facts_and_observations,
)
from devlearn.env.guards import (
    REWARD_BOUND,
    check_observations,
    check_reward,
    reward_within_bound,
)
from devlearn.env.motor_noise import PowerLawNoise
from devlearn.env.rendering import check_senses_render
from devlearn.env.settings import EnvSettings
from devlearn.timing import decision_rate_error, physics_steps

if TYPE_CHECKING:
    from devlearn.api.behavior import Behavior
    from devlearn.api.capabilities import EpisodeSpec

EPISODE_RECORD = "episode_record"
"""Key of an episode summary holding :meth:`~devlearn.api.behavior.Evaluator.episode_record`
(not a float: the runner hands it to the behaviour's :class:`~devlearn.api.behavior.RunMetrics`)."""

InfantFactory = Callable[..., Any]
"""``factory(scene, senses=..., **episode.infant_options) -> Infant``; defaults to
:func:`devlearn.infant.build_infant`."""


def build_default_infant(scene: str, senses: tuple[str, ...], **options: Any) -> Any:
    """Build the real infant (imported lazily so this module imports without it).

    ``options`` are the behaviour's ``episode().infant_options``.

    Raises:
        UsageError: ``senses`` include the eyes and ``MUJOCO_GL`` names no backend.
    """
    check_senses_render(senses, "the infant")
    from devlearn.infant import build_infant

    return build_infant(scene, senses=senses, **options)


def batched_reward_terms(behavior: Behavior) -> list[BatchedIntrinsicReward]:
    """The behaviour's fresh reward terms in the one form the core runs: batched, a
    per-environment :class:`~devlearn.api.rewards.IntrinsicReward` wrapped in
    :class:`~devlearn.api.rewards.BatchedFromPerEnv` (the only place terms are wrapped)."""
    return [as_batched(term) for term in behavior.reward_terms()]


class BehaviorEnv:
    """A single sub-environment: one infant, one behaviour's reward terms and one evaluator.

    The environment resets itself: after :attr:`episode_steps` steps the episode times out,
    its summary is returned as ``episode_info`` and a new episode begins (random initial pose
    when the stage options say ``random_pose``).

    Its reward terms are batched (:func:`batched_reward_terms`) and bound to this env alone,
    unless :func:`share_batched_terms` makes several envs share them (a worker's envs, stepped
    together by :func:`step_batch`); this env is row :attr:`batch_index` of their arrays.

    Args:
        behavior: The behaviour (this env's own instance; it may keep per-env state).
        seed: Seed of this env's numpy Generator (initial poses).
        infant_factory: ``factory(scene, senses=..., **episode.infant_options) -> Infant``;
            tests pass a fake one.
        training: Passed to the behaviour's evaluator factory (False for ``devlearn eval``).
        index: This env's index on its rank (named by the reward and observation guards).
        action_repeat: Shorthand for ``settings=EnvSettings(action_repeat)``; not with
            ``settings``.
        age_months: The body's age (``infant.age_months``; None: the default body), passed to
            the factory only when set, so factories that know no ages keep working.
        settings: The run's settled env settings (default ``EnvSettings()``); its
            ``action_repeat`` must divide the episode length, so every episode ends on a
            decision's last physics step.
    """

    def __init__(
        self,
        behavior: Behavior,
        seed: int,
        infant_factory: InfantFactory | None = None,
        training: bool = True,
        index: int = 0,
        action_repeat: int | None = None,
        age_months: float | None = None,
        settings: EnvSettings | None = None,
    ) -> None:
        self.settings = env_settings(settings, action_repeat)
        """The run's settled env settings (the decision rate)."""
        self.behavior = behavior
        self.episode = behavior.episode()
        """The behaviour's :class:`~devlearn.api.capabilities.EpisodeSpec`, read once."""
        self.hooks = self.episode.hooks
        self.index = index
        self._factory = infant_factory or build_default_infant
        self.age_months = age_months
        """The body's age (months; None: the default body); :meth:`set_age` changes it."""
        self.infant = self._build_infant()
        self.rng = np.random.default_rng(seed)
        self.terms = batched_reward_terms(behavior)
        """Reward terms in the behaviour's order, batched; may be shared with other envs."""
        for term in self.terms:
            term.bind(1)
        self.batch_index = 0
        """This env's index in its batched terms' arrays."""
        self.evaluator = behavior.evaluation().evaluator(training)
        self.stage: dict[str, Any] = dict(behavior.curriculum().stage.options)
        self.action_dim = int(self.infant.action_dim)
        self.episode_steps = episode_length(self.infant, self.episode, self.settings, behavior.name)
        """Physics steps per episode (:func:`episode_length`)."""
        self.step_dt = float(self.infant.control_timestep)
        self.motor_noise: PowerLawNoise | None = None
        """The body's motor noise (``settings.action_noise_std`` above 0), or None: one
        stream per actuator, seeded by this env's seed, never reset."""
        if self.settings.action_noise_std > 0:
            self.motor_noise = PowerLawNoise(
                self.action_dim,
                self.settings.action_noise_std,
                self.settings.action_noise_beta,
                float(self.infant.physics_timestep),
                seed,
            )
        self.episode_step = 0
        self._sums = {term.name: 0.0 for term in self.terms}
        self.decision_rewards = [0.0] * len(self.terms)
        """Each term's weighted reward in the last decision (:func:`step_batch`), term order:
        summed over its physics steps as the decision's reward is (what
        :mod:`devlearn.gym` reports per step)."""
        self.final_observation: dict[str, np.ndarray] | None = None
        """A copy of the last observation of the latest episode that ended (the env has reset
        since, so :meth:`step` returned the next episode's first); None before any ended."""
        if error := decision_rate_error(self.action_repeat, self.episode_steps):
            raise ValueError(error)  # checked before any worker starts too (check_config)

    def motor_command(self, action: np.ndarray) -> np.ndarray:
        """What the body gets for the policy's ``action`` (action_dim,), clipped: the action
        itself, or with :attr:`motor_noise` on, the action plus the noise's next sample,
        clipped to [-1, 1] again. Called once per physics step."""
        if self.motor_noise is None:
            return action
        return np.minimum(np.maximum(action + self.motor_noise(), -1.0), 1.0)

    @property
    def action_repeat(self) -> int:
        """Physics steps per decision (:attr:`settings`)."""
        return self.settings.action_repeat

    def _build_infant(self) -> Any:
        options = dict(self.episode.infant_options)
        if self.age_months is not None:
            options["age_months"] = self.age_months
        return self._factory(self.behavior.scene, senses=tuple(self.episode.senses), **options)

    def set_age(self, age_months: float | None) -> None:
        """Rebuild the infant's physics at ``age_months`` without ending the episode: the new
        body takes the old one's joint angles, velocities and controls (the infant's
        ``continue_from``), reward terms, evaluator and episode go on. The next decision acts
        on the observation the old body gave of the same pose."""
        if age_months == self.age_months:
            return
        old = self.infant
        self.age_months = age_months
        self.infant = self._build_infant()
        self.infant.continue_from(old)
        old.close()

    def reset(self) -> dict[str, np.ndarray]:
        """Start a new episode; return its first observations (name -> array)."""
        self.infant.reset(self.rng, random_pose=bool(self.stage.get("random_pose", False)))
        self.hooks.on_episode_start(self.infant, self.rng)
        for term in self.terms:
            term.reset(self.batch_index)
        self.episode_step = 0
        self._sums = {term.name: 0.0 for term in self.terms}
        _, batch = facts_and_observations([self])
        obs = {name: array[0] for name, array in batch.items()}
        check_observations(obs, self.index, 0)
        return obs

    def step(
        self, action: np.ndarray
    ) -> tuple[dict[str, np.ndarray], float, bool, bool, dict[str, float] | None]:
        """Advance one decision: ``action_repeat`` physics steps (:func:`step_batch`).

        Args:
            action: (action_dim,) policy action; clipped to [-1, 1].
        Returns:
            ``(obs, reward, done, time_out, episode_info)``. On the episode's last step ``done``
            and ``time_out`` are True, ``obs`` is the first observation of the next episode and
            ``episode_info`` holds ``reward/<term>`` (weighted per-episode sums) and
            ``metrics/<name>`` (evaluator), and under :data:`EPISODE_RECORD` the evaluator's
            ``episode_record()`` when it has one; otherwise ``episode_info`` is None.
        Raises:
            GuardError: A term's value or an observation is NaN, infinite or beyond its bound
                (:mod:`devlearn.env.guards`).
        """
        return step_batch([self], [action])[0]

    def advance(self, action: np.ndarray) -> StepContext:
        """First half of a step: hooks, physics, facts and observations; no rewards yet."""
        return advance_batch([self], [action])[0][0]

    def finish(
        self, ctx: StepContext, weighted: np.ndarray | list[float], steps: int = 1
    ) -> tuple[dict[str, np.ndarray], float, bool, bool, dict[str, float] | None]:
        """Second half of a step: sum the weighted term values (T,) (an array or its
        ``tolist()``), each paid ``steps`` times (a decision whose facts ran once), record,
        maybe reset."""
        reward = 0.0
        decision = self.decision_rewards
        values = weighted.tolist() if isinstance(weighted, np.ndarray) else weighted
        for k, (term, value) in enumerate(zip(self.terms, values)):
            value *= steps
            self._sums[term.name] += value
            decision[k] += value
            reward += value
        self.evaluator.record(ctx)
        self.episode_step += 1
        if not ctx.last_step:
            return ctx.observations, reward, False, False, None
        # copied: a batched behaviour's observations are views of arrays it may reuse
        self.final_observation = {k: np.array(v) for k, v in ctx.observations.items()}
        info = {f"reward/{name}": total for name, total in self._sums.items()}
        info.update({f"metrics/{k}": float(v) for k, v in self.evaluator.end_episode().items()})
        record = self.evaluator.episode_record()
        if record is not None:  # for the runner's RunMetrics, not a logged value
            info[EPISODE_RECORD] = record
        return self.reset(), reward, True, True, info

    def set_stage(self, options: dict[str, Any]) -> None:
        """Use a curriculum stage's options from now on (``random_pose`` from the next reset)."""
        self.stage = dict(options)

    def state_dict(self) -> dict[str, Any]:
        """Return the resumable state: every reward term's state, the rng, the stage and the
        motor noise's stream where it has one (the body's age is the run's: its config's,
        which the runner records in checkpoints)."""
        terms = {term.name: term.state_dict(self.batch_index) for term in self.terms}
        state = {"terms": terms, "rng": self.rng.bit_generator.state, "stage": dict(self.stage)}
        if self.motor_noise is not None:
            state["motor_noise"] = self.motor_noise.state_dict()
        return state

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore :meth:`state_dict`'s output (call :meth:`reset` afterwards)."""
        for term in self.terms:
            if term.name in state["terms"]:
                term.load_state_dict(self.batch_index, state["terms"][term.name])
        self.rng.bit_generator.state = state["rng"]
        self.stage = dict(state["stage"])
        if self.motor_noise is not None and "motor_noise" in state:
            self.motor_noise.load_state_dict(state["motor_noise"])

    def close(self) -> None:
        """Release the infant's resources."""
        self.infant.close()


def share_batched_terms(envs: list[BehaviorEnv]) -> None:
    """Make ``envs`` share the first env's terms, bound to ``len(envs)`` envs.

    Call before the envs' first reset. A wrapped per-environment term
    (:class:`~devlearn.api.rewards.BatchedFromPerEnv`) then holds one instance per env.
    """
    lead = envs[0].terms
    for term in lead:
        term.bind(len(envs))
    for i, env in enumerate(envs):
        env.terms = lead
        env.batch_index = i


def run_memories(envs: list[BehaviorEnv]) -> dict[str, dict[str, np.ndarray]]:
    """The run-wide memory of the batched terms ``envs`` share, term name -> memory (terms
    keeping none are left out; see :class:`~devlearn.api.rewards.BatchedIntrinsicReward`)."""
    return {term.name: memory for term in envs[0].terms if (memory := term.run_memory())}


def load_run_memories(envs: list[BehaviorEnv], memories: dict[str, dict[str, np.ndarray]]) -> None:
    """Give the batched terms ``envs`` share the merged run-wide memories (term name -> memory)."""
    for term in envs[0].terms:
        if term.name in memories:
            term.load_run_memory(memories[term.name])


def merge_run_memories(
    terms: list[BatchedIntrinsicReward], copies: list[dict[str, dict[str, np.ndarray]]]
) -> dict[str, dict[str, np.ndarray]]:
    """Merge copies of :func:`run_memories` (one per worker or rank, in order) term by term
    with each term's ``merge_run_memory``; ``terms`` are instances of the same terms."""
    return {
        term.name: term.merge_run_memory([c[term.name] for c in copies])
        for term in terms
        if term.name in copies[0]
    }


def term_values(envs: list[BehaviorEnv], contexts: list[StepContext]) -> np.ndarray:
    """Every reward term's weighted value for every env: the one place terms are evaluated.

    Each term (batched: :attr:`BehaviorEnv.terms`) is called once for the batch. Every
    unweighted value passes the reward guard (:func:`devlearn.env.guards.check_reward`:
    finite, within its bound) first. ``envs`` must share their terms (see
    :func:`share_batched_terms`) and be in their batch order.

    Returns:
        (num_terms, num_envs) float64, rows in the behaviour's term order.
    """
    terms = envs[0].terms
    n = len(envs)
    raw = np.empty((len(terms), n))
    batch = BatchContext(contexts)
    for k, term in enumerate(terms):
        try:
            value = term(batch)
        except Exception as exc:  # named, and the run stops as on a NaN (guards.py)
            from devlearn.env.guards import TermError

            failed = term.failed_env if isinstance(term, BatchedFromPerEnv) else None
            env, step = (
                (-1, contexts[0].step)
                if failed is None
                else (
                    envs[failed].index,
                    contexts[failed].step,
                )
            )
            raise TermError.wrap(term.name, exc, env, step) from exc
        shape = value.shape if isinstance(value, np.ndarray) else np.shape(value)
        if shape != (n,):
            raise ValueError(
                f"batched reward term '{term.name}' returned shape {shape}; "
                f"expected ({n},), one value per environment"
            )
        raw[k] = value
    if not reward_within_bound(raw):  # name the first bad value: term order, then env
        for k, i in np.argwhere(~(np.abs(raw) <= REWARD_BOUND)):  # also NaN
            check_reward(terms[k].name, float(raw[k, i]), envs[i].index, contexts[i].step)
    weights = np.array([term.weight for term in terms])[:, None]
    return weights * raw


def episode_length(infant: Any, episode: EpisodeSpec, settings: EnvSettings, name: str) -> int:
    """Physics steps per episode: ``settings.episode_seconds`` (an evaluation's session), else
    the behaviour's ``episode().seconds`` (:class:`~devlearn.api.capabilities.EpisodeSpec`),
    converted with the body's physics step, else the infant's own ``episode_steps`` (5 s).

    Raises:
        UsageError: The seconds are not a whole number of physics steps (one line).
    """
    seconds, whose = settings.episode_seconds, "the evaluation's session"
    if seconds is None:
        seconds, whose = episode.seconds, f"{name}'s episode().seconds"
    if seconds is None:
        return int(infant.episode_steps)
    try:
        return physics_steps(seconds, float(infant.physics_timestep))
    except ValueError as err:
        raise UsageError(f"{whose}: {err}") from None


def env_settings(settings: EnvSettings | None, action_repeat: int | None = None) -> EnvSettings:
    """``settings``, or the settings ``action_repeat`` gives (the shorthand of
    :class:`BehaviorEnv` and :class:`~devlearn.env.vec_env.DevVecEnv`), or the defaults.

    Raises:
        TypeError: Both were given (two sources of one value).
    """
    if settings is not None and action_repeat is not None:
        raise TypeError("give settings or action_repeat, not both")
    if settings is not None:
        return settings
    return EnvSettings() if action_repeat is None else EnvSettings(int(action_repeat))


def step_batch(
    envs: list[BehaviorEnv],
    actions: Sequence[np.ndarray] | np.ndarray,
    obs_out: dict[str, np.ndarray] | None = None,
) -> list[tuple]:
    """One decision of ``envs``: ``action_repeat`` physics steps with ``actions[i]`` held.

    With ``episode().facts_every_physics_step`` (the default) this is :func:`step_physics`
    ``action_repeat`` times, the rewards summed; otherwise physics runs ``action_repeat - 1``
    times bare, then one :func:`step_physics` computes facts, observations, rewards (paid
    ``action_repeat`` times) and the evaluator's record. Envs step in lockstep (their episodes
    have one length that the repeat divides), so an episode can end only on a decision's last
    physics step. With ``action_repeat`` 1 both are exactly :func:`step_physics`.

    Returns:
        One ``(obs, reward, done, time_out, episode_info)`` per env, as :meth:`BehaviorEnv.step`.
    """
    for env in envs:
        env.decision_rewards = [0.0] * len(env.terms)
    repeat = envs[0].action_repeat
    if repeat == 1:
        return step_physics(envs, actions, obs_out)
    if not envs[0].episode.facts_every_physics_step:
        for _ in range(repeat - 1):
            for env, action in zip(envs, clipped_actions(actions)):
                apply_action(env, action)
                env.episode_step += 1
        return step_physics(envs, actions, obs_out, paid=repeat)
    totals = np.zeros(len(envs))
    for k in range(repeat):  # the policy observes the decision's last physics step only
        results = step_physics(envs, actions, obs_out, observe=k == repeat - 1)
        totals += [reward for _, reward, _, _, _ in results]
    return [(obs, float(total), *rest) for (obs, _, *rest), total in zip(results, totals)]


def step_physics(
    envs: list[BehaviorEnv],
    actions: Sequence[np.ndarray] | np.ndarray,
    obs_out: dict[str, np.ndarray] | None = None,
    paid: int = 1,
    observe: bool = True,
) -> list[tuple]:
    """Step ``envs`` one physics step with ``actions[i]`` each: physics per env, facts and
    observations (once for the batch), every reward term (batched ones
    once for all, each value paid ``paid`` times), then each env's bookkeeping and auto-reset.

    Args:
        envs: The envs of one batch, sharing their batched terms, in batch order.
        actions: (num_envs, action_dim), or one (action_dim,) action per env.
        obs_out: Optional name -> (num_envs, *shape) arrays that receive every env's
            returned observation (the next episode's first one after an auto-reset).
        observe: False inside a decision (:func:`step_batch`): observations only if read
            (:func:`~devlearn.env.batch_advance.advance_batch`), ``obs_out`` untouched
            but for envs that reset.
    Returns:
        One ``(obs, reward, done, time_out, episode_info)`` per env, as :meth:`BehaviorEnv.step`.
    """
    contexts, batch = advance_batch(envs, actions, observe)
    values = term_values(envs, contexts)
    if obs_out is not None and batch is not None:
        for name, array in batch.items():  # the whole batch at once; resets overwrite rows
            obs_out[name][...] = array
    # every env's column as Python floats in one call (not a view and tolist() per env)
    columns = values.T.tolist()
    results = [env.finish(ctx, column, paid) for env, ctx, column in zip(envs, contexts, columns)]
    if obs_out is not None:
        for i, (obs, _, done, _, _) in enumerate(results):
            if done:
                for name, value in obs.items():
                    obs_out[name][i] = value
    return results
