"""The physics ceiling of each scene, and where an environment's step time goes beside it.

Part of ``devlearn bench``: the ceiling is the bare infant stepping its physics with random
actions (no senses read); an environment's steps/s are reported as a fraction of it, and one
instrumented run of the environment's own step splits each step into its parts.
"""

from __future__ import annotations

import copy
import time
from typing import Any

import numpy as np

BREAKDOWN_PARTS = ("physics", "touch", "eyes", "facts", "observe", "rewards", "env")
"""Parts of an environment step: physics (``infant.step``); touch (the compiled contact routine:
sparse touch and hand contacts); eyes (both eye renders); facts (the behaviour's ``facts()``
beyond those senses); observe (``observe()``, proprioception included); rewards (every reward
term); env (action clipping, hooks, ``process_action``, per-term sums, the evaluator, and the
episode resets, spread over the steps)."""


def physics_ceiling(scene: str, steps: int, seed: int = 0) -> float:
    """Physics-only steps per second of one scene's infant: ``infant.step`` with random actions.

    Returns:
        Steps per second (the most any environment on this scene can reach in one process).
    """
    from devlearn.bench import random_steps_per_s
    from devlearn.infant import build_infant

    infant = build_infant(scene, senses=("proprioception",))
    rng = np.random.default_rng(seed)
    infant.reset(rng, random_pose=scene == "crib")
    rate = random_steps_per_s(infant.step, rng, infant.action_dim, steps, warmup=100)
    infant.close()
    return rate


def env_breakdown(behavior, steps: int, seed: int = 0) -> dict[str, float]:
    """Milliseconds per step of each part of one BehaviorEnv's step (:data:`BREAKDOWN_PARTS`).

    Runs the same calls as :meth:`devlearn.env.BehaviorEnv.step`, in the same order, with a
    clock between them; senses the behaviour reads are computed first so that their cost is
    not counted in ``facts``. Timers add about a microsecond per part.

    Returns:
        Part -> ms per step, and ``total``.
    """
    from devlearn.env import BehaviorEnv
    from devlearn.env.behavior_env import term_values
    from devlearn.rewards import StepContext

    env = BehaviorEnv(behavior, seed=seed)
    env.reset()
    infant, behavior = env.infant, env.behavior
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
        behavior.before_step(infant, action)
        processed = behavior.process_action(action, env.stage)
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
        facts = behavior.facts(infant)
        t5 = clock()
        obs = behavior.observe(infant, facts)
        t6 = clock()
        last = env.episode_step == env.episode_steps - 1
        ctx = StepContext(infant, obs, facts, env.episode_step, last, env.stage)
        values = term_values([env], [ctx])
        t7 = clock()
        env.finish(ctx, values[:, 0])
        t8 = clock()
        for part, dt in zip(
            BREAKDOWN_PARTS,
            (t2 - t1, t3 - t2, t4 - t3, t5 - t4, t6 - t5, t7 - t6, t8 - t7 + t1 - t0),
        ):
            spent[part] += dt
    env.close()
    result = {part: 1000.0 * total / steps for part, total in spent.items()}
    result["total"] = sum(result.values())
    return result


def reference_env_steps_per_s(behavior, steps: int) -> float:
    """Steps/s of the same environment on the previous code paths, in the same run: the numpy
    touch routine instead of the compiled one, and per-environment reward terms where the
    behaviour offers them (``per_env_reward_terms()``, as self_touch does)."""
    from devlearn.bench import bench_behavior_env

    behavior = copy.deepcopy(behavior)
    if hasattr(behavior, "per_env_reward_terms"):
        behavior.reward_terms = behavior.per_env_reward_terms
    return bench_behavior_env(behavior, steps, reference_touch=True)


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

    def reference_touch():
        contacts.sparse_touch_from_contacts(skin, reader.sides(data, True))

    def reference_both():
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
