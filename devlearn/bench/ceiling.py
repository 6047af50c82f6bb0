"""The physics ceiling of each scene, and where an environment's step time goes beside it.

Part of ``devlearn bench``: the ceiling is the bare infant stepping its physics with random
actions (no senses read); an environment's steps/s are reported as a fraction of it, and one
instrumented run of the environment's own step splits each step into its parts.
"""

from __future__ import annotations

import copy
import time
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from devlearn.api.behavior import Behavior

BREAKDOWN_PARTS = ("physics", "touch", "eyes", "facts", "observe", "rewards", "env")
"""Parts of an environment step: physics (``infant.step``); touch (the compiled contact routine:
sparse touch and hand contacts); eyes (both eye renders); facts (the behaviour's ``facts()`` of
the env as a batch of one, beyond those senses); observe (``observe()``, proprioception
included); rewards (every reward term and the reward
guard); env (action clipping, hooks, ``process_action``, the observation guard, per-term sums,
the evaluator, and the episode resets, spread over the steps)."""


def physics_ceiling(scene: str, steps: int, seed: int = 0) -> float:
    """Physics-only steps per second of one scene's infant: ``infant.step`` with random actions.

    Returns:
        Steps per second (the most any environment on this scene can reach in one process).
    """
    from devlearn.bench.speed import random_steps_per_s
    from devlearn.infant import build_infant

    infant = build_infant(scene, senses=("proprioception",))
    rng = np.random.default_rng(seed)
    infant.reset(rng, random_pose=scene == "crib")
    rate = random_steps_per_s(infant.step, rng, infant.action_dim, steps, warmup=100)
    infant.close()
    return rate


def env_breakdown(behavior: Behavior, steps: int, seed: int = 0) -> dict[str, float]:
    """Milliseconds per step of each part of one BehaviorEnv's step (:data:`BREAKDOWN_PARTS`).

    Runs the same calls as :meth:`devlearn.env.BehaviorEnv.step`, in the same order, with a
    clock between them; senses the behaviour reads are computed first so that their cost is
    not counted in ``facts``. Timers add about a microsecond per part.

    Returns:
        Part -> ms per step, and ``total``.
    """
    from devlearn.api.batching import EnvBatch
    from devlearn.api.rewards import StepContext
    from devlearn.env import BehaviorEnv
    from devlearn.env.behavior_env import term_values
    from devlearn.env.guards import check_observations

    env = BehaviorEnv(behavior, seed=seed)
    env.reset()
    infant, behavior, hooks = env.infant, env.behavior, env.hooks
    one = EnvBatch([infant], [behavior])
    senses = set(getattr(infant, "senses", ()))
    rng = np.random.default_rng(seed)
    actions = rng.uniform(-1, 1, (steps + 50, env.action_dim))
    for a in actions[:50]:
        env.step(a)
    spent = dict.fromkeys(BREAKDOWN_PARTS, 0.0)
    clock = time.perf_counter
    for a in actions[50:]:
        t0 = clock()
        action = np.clip(np.asarray(a, dtype=np.float64), -1.0, 1.0)
        hooks.before_step(infant, action)
        processed = hooks.process_action(action, env.stage)
        t1 = clock()
        infant.step(processed)
        t2 = clock()
        t3 = t2
        if "touch" in senses:
            infant.touch_sparse()
            t3 = clock()
        t4 = t3
        if "eyes" in senses:
            infant.eyes()
            t4 = clock()
        facts = behavior.facts(one)[0]
        t5 = clock()
        obs = {k: v[0] for k, v in behavior.observe(one, [facts]).items()}
        t6 = clock()
        check_observations(obs, env.index, env.episode_step + 1)
        last = env.episode_step == env.episode_steps - 1
        ctx = StepContext(infant, obs, facts, env.episode_step, last, env.stage)
        t7 = clock()
        values = term_values([env], [ctx])
        t8 = clock()
        env.finish(ctx, values[:, 0])
        t9 = clock()
        for part, dt in zip(
            BREAKDOWN_PARTS,
            (t2 - t1, t3 - t2, t4 - t3, t5 - t4, t6 - t5, t8 - t7, t9 - t8 + t7 - t6 + t1 - t0),
        ):
            spent[part] += dt
    env.close()
    result = {part: 1000.0 * total / steps for part, total in spent.items()}
    result["total"] = sum(result.values())
    return result


def reference_env_steps_per_s(behavior: Behavior, steps: int) -> float:
    """Steps/s of the same environment on the previous touch path, in the same run: the numpy
    touch routine instead of the compiled one (reward terms are the behaviour's own; the
    per-environment twins of self_touch's terms are test oracles since issue #31)."""
    from devlearn.bench.speed import bench_behavior_env

    return bench_behavior_env(copy.deepcopy(behavior), steps, reference_touch=True)


def with_per_env_observations(behavior: Behavior) -> Behavior:
    """A copy of ``behavior`` on the per-environment path: its ``facts`` and ``observe`` called
    for each env of a batch alone, as a batch of one (the path before batched observations;
    in-process use only: the copy's class is made here and does not pickle)."""
    from devlearn.api.batching import EnvBatch

    cls = type(behavior)

    def facts(self: Behavior, batch: EnvBatch) -> list[dict[str, Any]]:
        return [cls.facts(self, batch.one(i))[0] for i in range(len(batch))]

    def observe(self: Behavior, batch: EnvBatch, facts: Any) -> dict[str, np.ndarray]:
        rows = [cls.observe(self, batch.one(i), [facts[i]]) for i in range(len(batch))]
        return {name: np.concatenate([row[name] for row in rows]) for name in rows[0]}

    per_env = type(f"PerEnv{cls.__name__}", (cls,), {"facts": facts, "observe": observe})
    clone = copy.deepcopy(behavior)
    clone.__class__ = per_env
    return clone


def touch_old_and_new(steps: int, seed: int = 0) -> dict[str, Any]:
    """Per-step ms of touch on the same crib steps: compiled (sparse touch and hand contacts
    in one call) and the numpy reference (sparse touch alone, and with hand contacts)."""
    from devlearn.infant import build_infant, contacts

    crib = build_infant("crib", senses=("touch", "proprioception"))
    rng = np.random.default_rng(seed)
    crib.reset(rng, random_pose=True)
    reader, data, skin = crib._contacts, crib.data, crib.skin
    for a in rng.uniform(-1, 1, (200, crib.action_dim)):  # warm-up (and compile)
        crib.step(a)
        reader.touch_and_hands(data, crib.hand_of_body)

    def reference_touch() -> None:
        contacts.sparse_touch_from_contacts(skin, reader.sides(data, True))

    def reference_both() -> None:
        sides = reader.sides(data, True)
        contacts.sparse_touch_from_contacts(skin, sides)
        contacts.hand_contacts(skin, sides, crib.hand_of_body)

    timed = {
        "touch_compiled_ms_per_step": lambda: reader.touch_and_hands(data, crib.hand_of_body),
        "touch_reference_ms_per_step": reference_touch,
        "touch_and_hands_reference_ms_per_step": reference_both,
    }
    spent = dict.fromkeys(timed, 0.0)
    for a in rng.uniform(-1, 1, (steps, crib.action_dim)):
        crib.step(a)
        for key, fn in timed.items():  # the same physics state for all three
            start = time.perf_counter()
            fn()
            spent[key] += time.perf_counter() - start
    crib.close()
    return {key: 1000.0 * total / steps for key, total in spent.items()}


def observations_old_and_new(behavior: Behavior, steps: int, vec_steps: int) -> dict[str, Any]:
    """Steps/s of a behaviour's batched facts and observations against the same behaviour on
    the per-environment path (:func:`with_per_env_observations`), same run.

    One process, one env (``<name>_steps_per_s[_per_env_observations]``) and 16 envs stepped
    as one batch (``<name>_vec_steps_per_s_in_process[_per_env_observations]``); each figure
    is the better of two runs, old and new alternating, so that a burst of other work on the
    machine does not favour either. Also the per-env path's breakdown
    (``<name>_breakdown_per_env_observations_ms``).
    """
    from devlearn.bench.speed import bench_behavior_env, bench_vec_env

    name, old = behavior.name, with_per_env_observations(behavior)
    figures: dict[str, list[float]] = {}
    for _ in range(2):
        for suffix, b in (("", behavior), ("_per_env_observations", old)):
            one = bench_behavior_env(b, steps)
            many = bench_vec_env(b, num_envs=16, workers=0, steps=vec_steps)
            figures.setdefault(f"{name}_steps_per_s{suffix}", []).append(one)
            figures.setdefault(f"{name}_vec_steps_per_s_in_process{suffix}", []).append(many)
    result: dict[str, Any] = {key: max(values) for key, values in figures.items()}
    result[f"{name}_breakdown_per_env_observations_ms"] = env_breakdown(old, steps)
    return result
