"""The behaviour conformance check (:func:`check_behavior`): the class contract, reward terms,
curriculum, network, then the behaviour's real environment stepped with every term, observation
and evaluator checked (the instrumented wrappers are at the end of this module)."""

from __future__ import annotations

import copy
import dataclasses
import difflib
import json
import pickle
from collections.abc import Callable, Sequence
from typing import Any

import mujoco
import numpy as np
import torch

from devlearn.api.batching import EnvBatch
from devlearn.api.behavior import Behavior, Evaluator, evaluation_stage
from devlearn.api.capabilities import About, Artifacts, EpisodeHooks, EpisodeSpec, EvalProtocol
from devlearn.api.curriculum import Curriculum
from devlearn.api.network_spec import NetworkSpec
from devlearn.api.rewards import BatchedFromPerEnv, BatchedIntrinsicReward, IntrinsicReward
from devlearn.env.guards import TermError
from devlearn.infant import Infant
from devlearn.infant.starts import STARTS
from devlearn.testing.values import (
    ConformanceError,
    check_number,
    check_picklable,
    json_problem,
    pickle_problem,
    require,
)


def check_behavior_class(behavior_cls: type[Behavior]) -> None:
    """Check the class-level contract: name, scene, senses, config dataclass, docstrings, the
    composed capabilities of their declared types (:func:`check_contract_members`), a
    picklable instance and its declared evaluation start."""
    name = getattr(behavior_cls, "name", None)
    require(isinstance(name, str) and name.isidentifier(), "Behavior.name must be an identifier")
    require(
        behavior_cls.scene in ("crib", "sitting", "sitting_babybench"),
        "Behavior.scene must be crib, sitting or sitting_babybench",
    )
    require(dataclasses.is_dataclass(behavior_cls.config_class), "config_class: a dataclass")
    require(bool(behavior_cls.__doc__), f"{behavior_cls.__name__} needs a docstring")
    check_contract_members(behavior_cls)
    config = behavior_cls.config_class()
    behavior = behavior_cls(config)
    valid = {"touch", "proprioception", "vestibular", "eyes"}
    senses = behavior.episode().senses
    require(set(senses) <= valid, f"episode().senses must be within {sorted(valid)}")
    check_picklable(behavior, f"behavior '{name}'")  # travels to worker processes
    start = behavior.evaluation().start
    require(
        start is None or start in STARTS,
        f"evaluation().start must be None or one of {', '.join(STARTS)}, got {start!r}",
    )


def check_contract_members(behavior_cls: type[Behavior]) -> None:
    """Check that ``behavior_cls`` writes the members of the Behavior contract as declared:
    ``about`` an :class:`~devlearn.api.capabilities.About`, and ``episode()``,
    ``evaluation()`` and ``artifacts()`` methods returning an
    :class:`~devlearn.api.capabilities.EpisodeSpec`, an
    :class:`~devlearn.api.capabilities.EvalProtocol` and an
    :class:`~devlearn.api.capabilities.Artifacts`."""
    cls = behavior_cls.__name__
    require(
        isinstance(behavior_cls.about, About),
        f"{cls}.about must be a devlearn.About (description, headline_metric, presets...), "
        f"got {type(behavior_cls.about).__name__}",
    )
    for member in ("facts", "observe", "network", "reward_terms", "curriculum"):
        require(callable(getattr(behavior_cls, member)), f"{cls}.{member} must be a method")
    behavior = behavior_cls(behavior_cls.config_class())
    for member, kind in (
        ("episode", EpisodeSpec),
        ("evaluation", EvalProtocol),
        ("artifacts", Artifacts),
    ):
        method = getattr(behavior_cls, member)
        require(callable(method), f"{cls}.{member} must be a method, as Behavior declares it")
        got = getattr(behavior, member)()
        require(
            isinstance(got, kind),
            f"{cls}.{member}() must return a devlearn.{kind.__name__}, got {type(got).__name__}",
        )
    require(
        isinstance(behavior.episode().hooks, EpisodeHooks),
        f"{cls}.episode().hooks must be a devlearn.EpisodeHooks",
    )
    contract = contract_members()
    own = {
        name
        for klass in behavior_cls.__mro__[: behavior_cls.__mro__.index(Behavior)]
        for name, value in vars(klass).items()
        if not name.startswith("_") and callable(value) and name not in contract
    }
    for name in sorted(own):
        near = difflib.get_close_matches(name, contract, n=1, cutoff=0.85)
        require(
            not near,
            f"{cls}.{name} is no member of the Behavior contract: did you mean "
            f"{near[0] if near else ''}? (its default runs instead)",
        )


def contract_members() -> list[str]:
    """The public members :class:`~devlearn.api.behavior.Behavior` itself defines (methods,
    class attributes and annotated attributes): the whole contract, read from the class."""
    names = set(vars(Behavior)) | set(Behavior.__annotations__)
    return sorted(name for name in names if not name.startswith("_"))


def check_evaluator_class(evaluator: Any, label: str) -> None:
    """Check that an evaluator is an :class:`~devlearn.api.behavior.Evaluator` whose
    ``mergeable`` says whether it implements ``merge`` (``devlearn eval --envs N`` trusts it)."""
    require(
        isinstance(evaluator, Evaluator),
        f"the {label} evaluator must be a devlearn.Evaluator, got {type(evaluator).__name__}",
    )
    implemented = type(evaluator).merge is not Evaluator.merge
    require(
        implemented == evaluator.mergeable,
        f"{type(evaluator).__name__}: mergeable is {evaluator.mergeable} but merge() is "
        + ("implemented: set mergeable = True" if implemented else "not implemented"),
    )


def check_reward_terms(terms: Sequence[IntrinsicReward | BatchedIntrinsicReward]) -> None:
    """Check reward terms: unique names, a docstring each, picklable state."""
    names = [t.name for t in terms]
    require(len(names) == len(set(names)), f"reward term names must be unique: {names}")
    for term in terms:
        batched = isinstance(term, BatchedIntrinsicReward)
        require(
            batched or isinstance(term, IntrinsicReward),
            f"{term!r} is not an IntrinsicReward or BatchedIntrinsicReward",
        )
        require(bool(type(term).__doc__), f"reward term '{term.name}' needs a docstring")
        if isinstance(term, BatchedIntrinsicReward):
            term.bind(1)
            state = term.state_dict(0)
        else:
            state = term.state_dict()
        require(isinstance(state, dict), f"reward term '{term.name}': state_dict() -> a dict")
        check_picklable(state, f"reward term '{term.name}' state_dict()", "state")
        if isinstance(term, BatchedIntrinsicReward):
            term.load_state_dict(0, pickle.loads(pickle.dumps(state)))
        else:
            term.load_state_dict(pickle.loads(pickle.dumps(state)))


def check_curriculum(curriculum: Curriculum) -> None:
    """Check that a curriculum's state survives a save/restore."""
    total = sum(s.steps or 0 for s in curriculum.stages)
    curriculum.update(total + 1)
    state = pickle.loads(pickle.dumps(curriculum.state_dict()))
    fresh = type(curriculum)(curriculum.stages)
    fresh.load_state_dict(state)
    require(fresh.index == curriculum.index, "curriculum stage lost on load_state_dict")


def check_network(spec: NetworkSpec, observations: dict[str, np.ndarray], groups: dict) -> None:
    """Check that every observation in the actor/critic groups has an encoder that runs."""
    for group in ("actor", "critic"):
        require(group in groups, f"obs_groups must have '{group}'")
        for name in groups[group]:
            require(name in spec.encoders, f"observation '{name}' has no encoder in network()")
    for name, encoder in spec.encoders.items():
        require(name in observations, f"encoder for unknown observation '{name}'")
        shape = tuple(observations[name].shape)
        module = encoder.build(shape)
        batch = torch.as_tensor(np.stack([observations[name]] * 2)).float()
        out = module(batch)
        require(
            tuple(out.shape) == (2, encoder.out_dim(shape)),
            f"encoder '{name}' returned {tuple(out.shape)}, expected (2, {encoder.out_dim(shape)})",
        )


def check_behavior(
    behavior_cls: type[Behavior],
    steps: int = 20,
    seed: int = 0,
    *,
    episodes: int = 2,
    episode_steps: int = 200,
    contact_steps: int = 3,
    config: Any | None = None,
) -> dict[str, tuple[int, ...]]:
    """Run the full conformance check: what training and ``devlearn eval`` will exercise.

    In order: the class contract (name, scene, senses, documented config, picklable instance,
    naming the attribute that is not); reward terms (unique names, docstrings, picklable state);
    the curriculum's save/restore; then the behaviour's real environment:

    1. ``steps`` random actions from the first stage's initial pose;
    2. ``episodes`` episodes from random poses (cycling through the curriculum's stages, each
       cut to ``episode_steps`` steps so it ends quickly), so episode ends run too;
    3. ``contact_steps`` steps with a hand placed on the body (a scripted contact), so facts,
       observations and terms that depend on contacts run.

    On every step observations must keep their names and shapes and be finite float32 (or
    uint8) arrays; every reward term must return a finite Python float (the message names the
    term). A training and an evaluation evaluator (``evaluator(training=...)``) record every
    step; their ``end_episode()`` metrics must be finite numbers and their ``summary()``
    JSON-serialisable, and ``write_artifacts`` must return files that exist; both must be
    :class:`~devlearn.api.behavior.Evaluator` whose ``mergeable`` says whether ``merge`` is
    implemented (:func:`check_evaluator_class`); an evaluation
    evaluator that merges (``Evaluator.merge``, for ``devlearn eval --envs N``) must merge
    evaluators of single episodes into the summary of one that saw them all
    (:func:`check_evaluator_merge`). On the random-action steps a batch must give every
    environment exactly the facts and observations it gives alone
    (:func:`check_batched_observations`).

    Args:
        behavior_cls: The Behavior subclass.
        steps: Random-action steps of phase 1.
        seed: Seed of the environment and of the random actions.
        episodes: Random-pose episodes of phase 2 (at least 1).
        episode_steps: Length of each of those episodes (at most the infant's own).
        contact_steps: Steps with a hand on the body in phase 3.
        config: The behaviour's config (default ``config_class()``).
    Returns:
        The observations' shapes, name -> tuple.
    Raises:
        ConformanceError: The first broken part of the contract, by name.
    """
    import tempfile
    from pathlib import Path

    from devlearn.env import BehaviorEnv

    check_behavior_class(behavior_cls)
    behavior = behavior_cls(config if config is not None else behavior_cls.config_class())
    for training, label in ((True, "training"), (False, "evaluation")):
        check_evaluator_class(behavior.evaluation().evaluator(training), label)
    check_reward_terms(behavior.reward_terms())
    curriculum = behavior.curriculum()
    check_curriculum(curriculum)
    phase = ["after reset"]  # where the check is, for messages (CheckedTerm reads it)
    env = BehaviorEnv(behavior, seed=seed)
    try:
        env.terms = checked_terms(env.terms, phase)
        checked = CheckedEvaluator(
            env.evaluator,
            behavior.evaluation().evaluator(False),
            phase,
            fresh=lambda: behavior.evaluation().evaluator(False),
        )
        env.evaluator = checked  # records in both, and checks what they return
        env.episode_steps = max(1, min(env.episode_steps, episode_steps))
        first = env.reset()
        shapes = check_observations(first, None, "after reset")
        spec = behavior.network()
        check_network(spec, first, spec.obs_groups(list(shapes)))
        rng = np.random.default_rng(seed)
        batches = [steps]  # the random-action steps compare batched and lone observations

        def step(action: np.ndarray, where: str) -> bool:
            phase[0] = where
            try:
                obs, reward, done, _, info = env.step(action)
            except TermError as exc:  # a checked term's own finding: report it as such
                if isinstance(exc.__cause__, ConformanceError):
                    raise exc.__cause__ from None
                raise
            check_number(reward, "the summed reward", where)
            check_observations(obs, shapes, where)
            if batches[0] > 0:  # a batch of the env twice gives each row what it gives alone
                batches[0] -= 1
                check_batched_observations(env.behavior, [env.infant, env.infant], where)
            return done

        for _ in range(steps):
            step(rng.uniform(-1, 1, env.action_dim), "on random actions from the initial pose")
        for i in range(max(1, episodes)):
            stage = curriculum.stages[i % len(curriculum.stages)]
            env.set_stage({**stage.options, "random_pose": True})
            env.reset()
            where = f"in random-pose episode {i + 1} (stage '{stage.name}')"
            while not step(rng.uniform(-1, 1, env.action_dim), where):
                pass
        require(checked.episodes >= 1, "no episode ended: the evaluator was never closed")
        env.set_stage(evaluation_stage(behavior, 0))
        _scripted_contacts(env, rng, contact_steps, step)
        check_summaries(checked)
        with tempfile.TemporaryDirectory() as tmp:
            paths = checked.evaluation.write_artifacts(Path(tmp))
            require(isinstance(paths, list), "write_artifacts() must return a list of paths")
            missing = [str(p) for p in paths if not Path(p).exists()]
            require(not missing, f"write_artifacts() returned files that do not exist: {missing}")
    finally:
        env.close()
    return shapes


def _scripted_contacts(
    env: Any, rng: np.random.Generator, count: int, step: Callable[[np.ndarray, str], bool]
) -> None:
    """Take ``count`` steps on which a hand touches the body (placed there before each step)."""
    infant = env.infant
    if count <= 0 or not isinstance(infant, Infant):  # a stand-in: no body to place
        return
    done = 0
    for _ in range(20 * count):
        if env.episode_step >= env.episode_steps - 1:
            env.reset()  # keep the placed pose clear of an automatic reset
        if not place_hand_on_body(infant, rng):
            continue
        step(np.zeros(env.action_dim), "on a step with a hand placed on the body")
        done += bool(infant.hand_contacts().any())
        if done >= count:
            return
    raise RuntimeError(f"devlearn.testing could not script a hand contact in {infant.scene}")


# --- the checks run on every step, and the instrumented terms and evaluator -------------------

OBS_DTYPES = (np.float32, np.uint8)
"""Observation dtypes the networks accept (float32 features, uint8 images)."""


def check_observations(
    obs: Any, shapes: dict[str, tuple] | None, where: str
) -> dict[str, tuple[int, ...]]:
    """Check one step's observations: a dict of fixed-shape, finite float32/uint8 arrays.

    Args:
        obs: What ``Behavior.observe`` returned.
        shapes: The first step's shapes (None on the first step: they are recorded).
        where: Which phase of the check this is, for messages.
    Returns:
        Name -> shape.
    """
    require(isinstance(obs, dict), f"observe() must return a dict, got {type(obs).__name__}")
    if shapes is not None:
        require(
            set(obs) == set(shapes),
            f"observation names changed {where}: {sorted(shapes)} -> {sorted(obs)}",
        )
    out = {}
    for key, value in obs.items():
        require(
            isinstance(value, np.ndarray),
            f"observation '{key}' is a {type(value).__name__}, not a numpy array {where}",
        )
        require(
            value.dtype in OBS_DTYPES,
            f"observation '{key}' has dtype {value.dtype}; use float32 (or uint8 images) {where}",
        )
        if shapes is not None:
            require(
                value.shape == shapes[key],
                f"observation '{key}' changed shape from {shapes[key]} to {value.shape} {where}",
            )
        require(bool(np.all(np.isfinite(value))), f"observation '{key}' has NaN or inf {where}")
        out[key] = tuple(value.shape)
    return out


def check_batched_observations(behavior: Any, infants: list[Any], where: str = "") -> None:
    """Require a batch of environments to give every environment exactly (bit for bit) the
    facts and observations it gives alone, as a batch of one: what a worker of several envs
    computes must not depend on its other envs or on how runs split envs over workers.

    Each environment gets its own copy of ``behavior`` (as each env owns its behaviour), the
    same copies' state for both, so the check leaves ``behavior`` as it was.

    Args:
        behavior: The behaviour (in the state of the step to compare).
        infants: Infants in the states to compare (after a step or a reset).
        where: Which phase of the check this is, for messages.
    """
    n = len(infants)
    alone = [copy.deepcopy(behavior) for _ in infants]
    want_facts = [b.facts(EnvBatch([i], [b]))[0] for b, i in zip(alone, infants)]
    alone = [copy.deepcopy(behavior) for _ in infants]
    want_obs = [b.observe(EnvBatch([i], [b]), [f]) for b, i, f in zip(alone, infants, want_facts)]
    together = [copy.deepcopy(behavior) for _ in infants]
    batch = EnvBatch(list(infants), together)
    batched = together[0].facts(batch)
    require(
        isinstance(batched, list) and len(batched) == n,
        f"facts() must return a list of {n} facts dicts, one per environment {where}",
    )
    for i, (got, want) in enumerate(zip(batched, want_facts)):
        require(
            set(got) == set(want),
            f"facts()[{i}] has facts {sorted(got)}, environment {i} alone {sorted(want)} {where}",
        )
        for key, value in want.items():
            require(
                _identical(got[key], value),
                f"facts()[{i}]['{key}'] of a batch differs from environment {i}'s alone {where}",
            )
    together = [copy.deepcopy(behavior) for _ in infants]
    observed = together[0].observe(EnvBatch(list(infants), together), want_facts)
    for i, want in enumerate(want_obs):
        require(
            set(observed) == set(want),
            f"observe() gives {sorted(observed)}, environment {i} alone {sorted(want)} {where}",
        )
        for key, value in want.items():
            row = np.asarray(value)[0]
            require(
                np.shape(observed[key]) == (n, *np.shape(row))
                and _identical(np.asarray(observed[key])[i], row),
                f"observe()['{key}'][{i}] of a batch differs from environment {i}'s alone {where}",
            )


def _identical(a: Any, b: Any) -> bool:
    """Equal values; arrays of the same dtype and shape with the same bytes."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
    return bool(a == b)


class CheckedTerm:
    """A reward term whose every value is checked (finite Python float), naming the term."""

    def __init__(self, term: Any, phase: list[str]) -> None:
        self.term = term
        self.phase = phase

    def __getattr__(self, name: str) -> Any:
        return getattr(self.term, name)

    def __call__(self, ctx: Any) -> float:
        value = self.term(ctx)
        return check_number(value, f"reward term '{self.term.name}'", self.phase[0])


class CheckedBatchedTerm(BatchedIntrinsicReward):
    """A batched reward term whose every step is checked: a (num_envs,) array of finite real
    numbers, naming the term."""

    def __init__(self, term: BatchedIntrinsicReward, phase: list[str]) -> None:
        self.term = term
        self.phase = phase
        self.name = term.name
        self.weight = term.weight
        self.num_envs = term.num_envs

    def bind(self, num_envs: int) -> None:
        self.term.bind(num_envs)
        self.num_envs = self.term.num_envs

    def __call__(self, batch: Any) -> np.ndarray:
        values = self.term(batch)
        what = f"batched reward term '{self.term.name}'"
        shape = np.shape(values)
        require(
            shape == (len(batch.contexts),),
            f"{what} returned shape {shape} {self.phase[0]}; "
            f"it must return ({len(batch.contexts)},), one value per environment",
        )
        array = np.asarray(values)
        require(
            array.dtype.kind in "fiu" and bool(np.isfinite(array).all()),
            f"{what} returned {' '.join(repr(values).split())[:60]} {self.phase[0]}; "
            "it must return finite real numbers",
        )
        return array

    def reset(self, env: int) -> None:
        self.term.reset(env)

    def state_dict(self, env: int) -> dict[str, Any]:
        return self.term.state_dict(env)

    def load_state_dict(self, env: int, state: dict[str, Any]) -> None:
        self.term.load_state_dict(env, state)

    def run_memory(self) -> dict[str, np.ndarray]:
        return self.term.run_memory()

    def merge_run_memory(self, copies: list[dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
        return self.term.merge_run_memory(copies)

    def load_run_memory(self, memory: dict[str, np.ndarray]) -> None:
        self.term.load_run_memory(memory)


def checked_terms(terms: list[BatchedIntrinsicReward], phase: list[str]) -> list[Any]:
    """Wrap every term of an env so each value it returns is checked: a batched term as a
    whole, a wrapped per-environment one (:class:`~devlearn.api.rewards.BatchedFromPerEnv`)
    in each environment, before its value is made a float."""
    for term in terms:
        if isinstance(term, BatchedFromPerEnv):
            term.terms = [CheckedTerm(t, phase) for t in term.terms]  # type: ignore[misc]
    return [t if isinstance(t, BatchedFromPerEnv) else CheckedBatchedTerm(t, phase) for t in terms]


class CheckedEvaluator(Evaluator):
    """Feeds a training and an evaluation evaluator the same steps; checks what they return.

    With ``fresh`` (a new evaluation evaluator) and an evaluator that merges, every episode is
    also recorded by an evaluator of its own, and after each episode they must merge (pickled,
    as from env workers) into the summary of the evaluator that saw every episode
    (:func:`check_evaluator_merge`).
    """

    def __init__(
        self,
        training: Any,
        evaluation: Any,
        phase: list[str],
        fresh: Callable[[], Any] | None = None,
    ) -> None:
        self.training = training
        self.evaluation = evaluation
        self.phase = phase
        self.episodes = 0
        self.fresh = fresh if fresh is not None and evaluation.mergeable else None
        self.parts = [] if self.fresh is None else [self.fresh()]

    def record(self, ctx: Any) -> None:
        self.training.record(ctx)
        self.evaluation.record(ctx)
        if self.parts:
            self.parts[-1].record(ctx)

    def end_episode(self) -> dict[str, float]:
        self.episodes += 1
        out = {}
        for label, evaluator in (("training", self.training), ("evaluation", self.evaluation)):
            metrics = evaluator.end_episode()
            what = f"{label} evaluator's end_episode()"
            require(isinstance(metrics, dict), f"{what} must return a dict, got {metrics!r}")
            for key, value in metrics.items():
                require(isinstance(key, str), f"{what} has a non-string key {key!r}")
                value = check_number(value, f"{what} metric '{key}'", self.phase[0])
                if label == "training":
                    out[key] = value
        if self.fresh is not None:
            self.parts[-1].end_episode()
            check_evaluator_merge(self.parts, self.evaluation, self.phase[0])
            self.parts.append(self.fresh())
        return out

    def episode_record(self) -> Any:
        """The training evaluator's record of the episode just ended (checked to pickle: it
        crosses from env workers to the runner)."""
        record = self.training.episode_record()
        if record is not None:
            problem = pickle_problem(record, "training evaluator's episode_record()")
            require(problem is None, f"{problem} (it crosses from env workers to the runner)")
        return record

    def summary(self) -> dict[str, Any]:
        return self.training.summary()


def check_evaluator_merge(parts: list[Any], whole: Any, where: str = "") -> None:
    """Require evaluators that each recorded a run of episodes, merged in order
    (``Evaluator.merge``, each pickled first as from an env worker), to summarise exactly as
    ``whole``, which recorded every episode in order (``devlearn eval --envs N`` relies on it).

    Args:
        parts: Evaluators of consecutive runs of episodes, none with an episode open.
        whole: The evaluator of all of them.
        where: Which phase of the check this is, for messages.
    """
    merged = pickle.loads(pickle.dumps(parts[0]))
    for part in parts[1:]:
        merged.merge(pickle.loads(pickle.dumps(part)))
    got = json.dumps(merged.summary(), sort_keys=True, default=float)
    want = json.dumps(whole.summary(), sort_keys=True, default=float)
    require(
        got == want,
        f"the evaluation evaluator's merge() of {len(parts)} runs of episodes summarises "
        f"otherwise than one evaluator recording them all {where}",
    )


def check_summaries(checked: CheckedEvaluator) -> dict[str, Any]:
    """Check both evaluators' ``summary()`` is a JSON-serialisable dict; return the eval one."""
    result: dict[str, Any] = {}
    for label, evaluator in (("training", checked.training), ("evaluation", checked.evaluation)):
        summary = evaluator.summary()
        what = f"{label} evaluator's summary()"
        require(isinstance(summary, dict), f"{what} must return a dict, got {type(summary)}")
        problem = json_problem(summary, "summary()")
        require(problem is None, f"{what} is not JSON-serialisable: {problem}")
        result = summary
    return result


def place_hand_on_body(infant: Any, rng: np.random.Generator, tries: int = 200) -> bool:
    """Put the infant in a random pose where a hand touches its body (a scripted contact).

    Joint angles are drawn uniformly within their ranges until a hand (palm or fingers) is in
    contact with a body-map region and nothing penetrates deeper than 1 cm (so the next physics
    step does not fling the limbs apart).

    Returns:
        True if such a pose was found (the infant is left in it), else False.
    """
    index, ranges = infant._qpos_index, infant._ranges
    for _ in range(tries):
        infant.data.qpos[index] = rng.uniform(ranges[:, 0], ranges[:, 1])
        infant.data.qvel[:] = 0.0
        mujoco.mj_forward(infant.model, infant.data)
        infant._cache.clear()
        ncon = infant.data.ncon
        depth = float(-infant.data.contact.dist[:ncon].min()) if ncon else 0.0
        if depth < 0.01 and infant.hand_contacts().any():
            return True
    return False
