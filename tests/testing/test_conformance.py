"""devlearn.testing.check_behavior reports each runtime fault by name (on the real infant)."""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest

import devlearn
from devlearn.testing import ConformanceError, check_behavior

# The faulty behaviours' episodes are short so each check takes well under a second.
FAST = {"steps": 5, "episodes": 1, "episode_steps": 30, "contact_steps": 2}


@dataclass
class ProbeConfig:
    """Options of the probe behaviour."""

    scale: float = 1.0
    """Unused; a config needs a field."""


class Touching(devlearn.IntrinsicReward):
    """1.0 on steps where a hand touches the body (fact ``contact``)."""

    name = "touching"

    def __call__(self, ctx):
        return 1.0 if ctx.facts["contact"] else 0.0


class CountEvaluator(devlearn.Evaluator):
    """Counts contact steps."""

    def __init__(self) -> None:
        self.contacts = 0
        self.episodes = 0

    def record(self, ctx) -> None:
        self.contacts += int(ctx.facts["contact"])

    def end_episode(self) -> dict[str, float]:
        self.episodes += 1
        return {"contact_steps": float(self.contacts)}

    def summary(self) -> dict[str, Any]:
        return {"episodes": self.episodes, "contacts": self.contacts}


class Probe(devlearn.Behavior):
    """A correct crib behaviour; the tests below break one part of it at a time."""

    name = "probe"
    scene = "crib"
    config_class = ProbeConfig

    @devlearn.per_env
    def facts(self, infant):
        return {"contact": bool(infant.hand_contacts().any())}

    @devlearn.per_env
    def observe(self, infant, facts):
        return {"proprioception": infant.proprioception().astype(np.float32)}

    def network(self):
        return devlearn.NetworkSpec({"proprioception": devlearn.MLPEncoder((16,))}, (16,), (16,))

    def reward_terms(self):
        return [Touching()]

    def episode(self):
        return devlearn.EpisodeSpec(senses=("proprioception",))

    def evaluation(self):
        return devlearn.EvalProtocol(evaluator=lambda training: CountEvaluator())


# Each broken behaviour is a module-level class (so it pickles, as a plugin's would), named after
# the fault it carries.


class Broken(devlearn.IntrinsicReward):
    """Returns ``bad`` on steps with a hand contact (or always, with ``always``)."""

    name = "broken_term"

    def __init__(self, bad: Any, always: bool = False) -> None:
        super().__init__()
        self.bad, self.always = bad, always

    def __call__(self, ctx):
        return self.bad if (self.always or ctx.facts["contact"]) else 0.0


class NanOnContact(Probe):
    """Its second term is NaN only on contact steps."""

    def reward_terms(self):
        return [Touching(), Broken(float("nan"))]


BAD_VALUES = {"array": np.ones((2, 2)), "none": None, "text": "1.0", "bool": True}


@dataclass
class BadValueConfig:
    """Which bad value the term returns."""

    kind: str = "array"
    """A key of BAD_VALUES."""


class BadTermValue(Probe):
    """Its second term returns a non-float (``config.kind``) on every step."""

    config_class = BadValueConfig

    def reward_terms(self):
        return [Touching(), Broken(BAD_VALUES[self.config.kind], always=True)]


class ContactShapedObservation(Probe):
    """Observation ``x`` has 4 entries on contact steps, 3 otherwise."""

    @devlearn.per_env
    def observe(self, infant, facts):
        return {
            "proprioception": infant.proprioception().astype(np.float32),
            "x": np.zeros(4 if facts["contact"] else 3, np.float32),
        }

    def network(self):
        encoders = {"proprioception": devlearn.MLPEncoder((16,)), "x": devlearn.MLPEncoder((4,))}
        return devlearn.NetworkSpec(encoders, (16,), (16,))


@dataclass
class DtypeConfig:
    """The dtype of the observation."""

    dtype: str = "float64"
    """A numpy dtype name."""


class WrongDtype(Probe):
    """Its observation has dtype ``config.dtype``."""

    config_class = DtypeConfig

    @devlearn.per_env
    def observe(self, infant, facts):
        return {"proprioception": infant.proprioception().astype(self.config.dtype)}


class ArraySummary(CountEvaluator):
    """Its summary holds a numpy array."""

    def summary(self):
        return {"episodes": self.episodes, "per_region": np.zeros(68)}


class ArraySummaryBehavior(Probe):
    """Its evaluator's summary() is not JSON-serialisable."""

    def evaluation(self):
        return devlearn.EvalProtocol(evaluator=lambda training: ArraySummary())


class TextMetric(CountEvaluator):
    """end_episode returns a string."""

    def end_episode(self):
        return {"reached": "yes"}


class TextMetricBehavior(Probe):
    """Its evaluator's episode metric is a string."""

    def evaluation(self):
        return devlearn.EvalProtocol(evaluator=lambda training: TextMetric())


class HoldsALock(Probe):
    """Keeps a lock (unpicklable) in a dict attribute."""

    def __init__(self, config=None):
        super().__init__(config)
        self.cache = {"lock": threading.Lock()}


class LambdaState(Touching):
    """Keeps a lambda in its state."""

    def state_dict(self):
        return {"fn": lambda x: x}


class UnpicklableTermState(Probe):
    """Its term's state_dict() holds a lambda."""

    def reward_terms(self):
        return [LambdaState()]


class Recording(Touching):
    """Counts the steps it sees, and those with a contact (class-level, for the test)."""

    steps = 0
    contact_steps = 0

    def __call__(self, ctx):
        Recording.steps += 1
        Recording.contact_steps += int(ctx.facts["contact"])
        return super().__call__(ctx)


class RecordingProbe(Probe):
    """A correct behaviour whose term records what it saw."""

    def reward_terms(self):
        return [Recording()]


def test_a_correct_behavior_passes_and_reaches_contacts():
    shapes = check_behavior(RecordingProbe, **FAST)
    assert shapes == {"proprioception": (180,)}
    assert Recording.contact_steps >= FAST["contact_steps"]  # the scripted contact ran
    assert Recording.steps >= FAST["steps"] + FAST["episode_steps"]


def test_nan_only_on_contact_names_the_term():
    with pytest.raises(ConformanceError, match=r"reward term 'broken_term'.*nan.*hand placed"):
        check_behavior(NanOnContact, **FAST)


@pytest.mark.parametrize(
    "kind, shown", [("array", "ndarray"), ("none", "NoneType"), ("text", "str"), ("bool", "bool")]
)
def test_non_float_term_values_name_the_term(kind, shown):
    with pytest.raises(ConformanceError, match=rf"reward term 'broken_term'.*\(a {shown}\)"):
        check_behavior(BadTermValue, config=BadValueConfig(kind), **FAST)


def test_observation_shape_depending_on_contacts_names_the_observation():
    with pytest.raises(
        ConformanceError, match=r"observation 'x' changed shape from \(3,\) to \(4,\)"
    ):
        check_behavior(ContactShapedObservation, **FAST)


@pytest.mark.parametrize("dtype", ["float64", "bool"])
def test_observation_dtype_names_the_observation(dtype):
    with pytest.raises(ConformanceError, match=rf"observation 'proprioception' has dtype {dtype}"):
        check_behavior(WrongDtype, config=DtypeConfig(dtype), **FAST)


def test_summary_that_is_not_json_names_the_key():
    with pytest.raises(ConformanceError, match=r"summary\(\) is not JSON.*'per_region'.*ndarray"):
        check_behavior(ArraySummaryBehavior, **FAST)


def test_bad_episode_metric_names_the_metric():
    with pytest.raises(ConformanceError, match=r"metric 'reached'"):
        check_behavior(TextMetricBehavior, **FAST)


def test_unpicklable_behavior_names_the_attribute():
    match = r"behavior 'probe' cannot be pickled.*self\.cache\['lock'\]"
    with pytest.raises(ConformanceError, match=match):
        check_behavior(HoldsALock, **FAST)


def test_unpicklable_term_state_names_the_term():
    with pytest.raises(ConformanceError, match=r"reward term 'touching' state_dict\(\).*\['fn'\]"):
        check_behavior(UnpicklableTermState, **FAST)


class BatchedNanOnContact(devlearn.BatchedIntrinsicReward):
    """Batched: NaN for an environment whose hand touches the body, else 0."""

    name = "batched_broken"

    def __call__(self, batch):
        contact = np.array([bool(c.facts["contact"]) for c in batch.contexts])
        return np.where(contact, np.nan, 0.0)


class BatchedNanProbe(Probe):
    """A behaviour whose only term is batched and breaks on contact."""

    def reward_terms(self):
        return [BatchedNanOnContact()]


def test_batched_term_nan_on_contact_names_the_term():
    with pytest.raises(ConformanceError, match=r"batched reward term 'batched_broken'.*hand placed"):
        check_behavior(BatchedNanProbe, **FAST)


def test_the_gymnasium_check_passes_a_correct_behaviour_and_names_a_broken_one():
    from devlearn.testing import TinyBehavior, check_gymnasium, fake_infant_factory

    check_gymnasium(TinyBehavior, infant_factory=fake_infant_factory)

    class Jittery(TinyBehavior):
        """Observes noise that no seed governs: the same seed and action differ."""

        name = "jittery"

        @devlearn.per_env
        def observe(self, infant, facts):
            noise = np.random.default_rng().normal(size=3).astype(np.float32)
            return {"proprioception": infant.proprioception() + noise}

    with pytest.raises(ConformanceError, match="gymnasium check_env on devlearn-check/Jittery"):
        check_gymnasium(Jittery, infant_factory=fake_infant_factory)
    import gymnasium

    assert "devlearn-check/Jittery-v0" not in gymnasium.registry  # the temporary id is gone


class MergingCount(CountEvaluator):
    """Counts contact steps and merges (``devlearn eval --envs N``)."""

    mergeable = True

    def merge(self, later):
        self.contacts += later.contacts
        self.episodes += later.episodes


class ForgetfulMerge(MergingCount):
    """Its merge forgets the later evaluator's episodes."""

    def merge(self, later):
        self.contacts += later.contacts


class MergingProbe(Probe):
    """Its evaluator merges."""

    def evaluation(self):
        return devlearn.EvalProtocol(evaluator=lambda training: MergingCount())


class ForgetfulMergeProbe(Probe):
    """Its evaluator's merge forgets episodes."""

    def evaluation(self):
        return devlearn.EvalProtocol(evaluator=lambda training: ForgetfulMerge())


def test_an_evaluator_that_merges_must_merge_into_the_whole_summary():
    check_behavior(MergingProbe, **{**FAST, "episodes": 2})
    with pytest.raises(ConformanceError, match=r"merge\(\) of 2 runs of episodes summarises"):
        check_behavior(ForgetfulMergeProbe, **{**FAST, "episodes": 2})


class UndeclaredMerge(CountEvaluator):
    """Merges, but does not say so (``mergeable`` keeps its default, False)."""

    def merge(self, later):
        self.contacts += later.contacts
        self.episodes += later.episodes


class UndeclaredMergeProbe(Probe):
    """Its evaluator merges without declaring it."""

    def evaluation(self):
        return devlearn.EvalProtocol(evaluator=lambda training: UndeclaredMerge())


class ClaimedMerge(CountEvaluator):
    """Says it merges, but keeps the contract's merge (which cannot)."""

    mergeable = True


class ClaimedMergeProbe(Probe):
    """Its evaluator claims a merge it does not have."""

    def evaluation(self):
        return devlearn.EvalProtocol(evaluator=lambda training: ClaimedMerge())


class LooseEvaluator:
    """Records like an evaluator without being one."""

    def record(self, ctx):
        pass

    def end_episode(self):
        return {}

    def summary(self):
        return {}


class LooseEvaluatorProbe(Probe):
    """Its evaluator is not a devlearn.Evaluator."""

    def evaluation(self):
        return devlearn.EvalProtocol(evaluator=lambda training: LooseEvaluator())


class SidewaysStart(Probe):
    """Declares an evaluation start the infant does not have."""

    def evaluation(self):
        return devlearn.EvalProtocol(evaluator=lambda training: CountEvaluator(), start="sideways")


class MisspelledHook(Probe):
    """Writes ``evaluations``: the contract's ``evaluation`` default would run instead."""

    def evaluations(self):
        return devlearn.EvalProtocol(start="babybench")


class EvaluationAsValue(Probe):
    """Gives ``evaluation`` as a value, where the contract declares a method."""

    evaluation = devlearn.EvalProtocol(start="babybench")


class AboutAsDict(Probe):
    """Gives ``about`` as a dict of its fields, where the contract declares an About."""

    about = {"presets": {"paper": {"total_steps": 320}}}


class EpisodeAsDict(Probe):
    """Returns the episode's settings as a dict, where the contract declares an EpisodeSpec."""

    def episode(self):
        return {"senses": ("proprioception",)}


@pytest.mark.parametrize(
    "probe, message",
    [
        (AboutAsDict, "AboutAsDict.about must be a devlearn.About"),
        (EpisodeAsDict, "EpisodeAsDict.episode\\(\\) must return a devlearn.EpisodeSpec, got dict"),
        (MisspelledHook, "MisspelledHook.evaluations is no member .* did you mean evaluation"),
        (EvaluationAsValue, "EvaluationAsValue.evaluation must be a method"),
        (UndeclaredMergeProbe, "mergeable is False but merge\\(\\) is implemented"),
        (ClaimedMergeProbe, "mergeable is True but merge\\(\\) is not implemented"),
        (LooseEvaluatorProbe, "must be a devlearn.Evaluator, got LooseEvaluator"),
        (SidewaysStart, "evaluation\\(\\).start must be None or one of .*got 'sideways'"),
    ],
)
def test_the_declared_evaluation_extras_must_match_what_is_written(probe, message):
    with pytest.raises(ConformanceError, match=message):
        check_behavior(probe, **FAST)
