"""A recorded self_touch rollout: what a worker's envs returned, kept to catch any change.

``python plugins/self_touch/tests/recorded_rollout.py OUT.npz`` records it with the code on
the Python path; ``data/rollout_f17ca1c.npz`` was recorded on commit f17ca1c (before batched
facts and observations, the compiled proprioception and the compiled guards) with::

    git archive f17ca1c | tar -x -C BASE
    PYTHONPATH=BASE:BASE/plugins/self_touch/src python recorded_rollout.py OUT.npz

It was recorded through the core's ``make_envs`` and ``step_batch`` of that commit; today's
function plays the same batch (the same seeds, one copy of the behaviour per env) through
``devlearn.testing.Play``, a decision every physics step (``action_repeat=1``), so the test
also checks that K=1 is bit for bit the environment from before the decision rate (issue #28).
"""

from __future__ import annotations

import sys

import numpy as np

from devlearn.testing import EPISODE_RECORD

NUM_ENVS, STEPS, EPISODE_STEPS, SEED = 2, 120, 40, 3


def log1p_probe() -> np.ndarray:
    """np.log1p on fixed inputs: equal on machines whose numpy computes it the same way
    (the body map observation is log1p of the map; SIMD builds may differ in the last bit)."""
    return np.log1p(np.linspace(0.0, 50.0, 1001))


def record_rollout() -> dict[str, np.ndarray]:
    """Step ``NUM_ENVS`` real self_touch envs, sharing their batched terms as in a worker,
    from random poses, with random actions and a hand placed on the body every 10 steps.

    Returns:
        ``body_map`` (STEPS, NUM_ENVS, 68) and ``proprioception`` (STEPS, NUM_ENVS, P) float32
        observations, ``rewards`` (STEPS, NUM_ENVS) float64, ``dones`` bool, ``episode_info``
        (every finished episode's values, keys sorted, in order) with ``episode_keys``, and
        ``log1p_probe``.
    """
    from devlearn_self_touch import SelfTouch

    from devlearn.testing import Play, place_hand_on_body

    behavior = SelfTouch()
    # the memory f17ca1c had (each env its own); an unknown attribute there, so harmless
    behavior.config.lifetime_memory = "per_env"
    behavior.config.touch_count = "step"  # the paper's count, which f17ca1c had (issue #28)
    envs = Play(behavior, NUM_ENVS)
    rng = np.random.default_rng(SEED)
    out: dict[str, list] = {"body_map": [], "proprioception": [], "rewards": [], "dones": []}
    info_values: list[float] = []
    keys: list[str] = []
    try:
        envs.set_stage({"random_pose": True})
        envs.episode_steps = EPISODE_STEPS
        envs.reset()
        for t in range(STEPS):
            if t % 10 == 5:
                for infant in envs.infants:
                    place_hand_on_body(infant, rng)
            actions = rng.uniform(-1, 1, (NUM_ENVS, envs.action_dim))
            results = envs.step(actions)
            out["body_map"].append([obs["body_map"] for obs, *_ in results])
            out["proprioception"].append([obs["proprioception"] for obs, *_ in results])
            out["rewards"].append([reward for _, reward, *_ in results])
            out["dones"].append([done for _, _, done, *_ in results])
            for *_, info in results:
                if info is not None:
                    keys = sorted(k for k in info if k != EPISODE_RECORD)  # not a number
                    info_values.extend(info[k] for k in keys)
    finally:
        envs.close()
    return {
        "body_map": np.array(out["body_map"], dtype=np.float32),
        "proprioception": np.array(out["proprioception"], dtype=np.float32),
        "rewards": np.array(out["rewards"], dtype=np.float64),
        "dones": np.array(out["dones"], dtype=bool),
        "episode_info": np.array(info_values, dtype=np.float64),
        "episode_keys": np.array(keys),
        "log1p_probe": log1p_probe(),
    }


if __name__ == "__main__":
    np.savez_compressed(sys.argv[1], **record_rollout())
