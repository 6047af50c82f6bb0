"""Speed of the bare infant: what ``devlearn bench`` reports of physics, each sense and the eye
renders (:func:`bench_infant`), and a longer printout with medians and 90th percentiles
(``python -m devlearn.bench.infant``). Figures, no asserts."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

from devlearn.infant import build_infant


def _per_call_ms(
    fn: Callable[[], Any], calls: int, before: Callable[[], Any] | None = None
) -> float:
    """Mean milliseconds of ``fn`` over ``calls`` calls (``before`` runs untimed each time)."""
    total = 0.0
    for _ in range(calls):
        if before is not None:
            before()
        start = time.perf_counter()
        fn()
        total += time.perf_counter() - start
    return 1000.0 * total / calls


def bench_infant(steps: int = 2000, frames: int = 100) -> dict[str, float]:
    """Physics, touch, proprioception and eye-render cost on the bare infant.

    Returns:
        ``build_s`` (crib build), ``physics_ms_per_step``, ``touch_ms_per_step`` (the dense
        (N, 3) vector), ``touch_sparse_ms_per_step`` (only the sensors that feel a force),
        ``proprioception_ms_per_step``, ``render_ms_per_frame`` (one 64x64 eye),
        ``touch_sensors``, ``contacts_per_step``.
    """
    rng = np.random.default_rng(0)
    start = time.perf_counter()
    crib = build_infant("crib", senses=("touch", "proprioception", "vestibular"))
    build_s = time.perf_counter() - start
    crib.reset(rng, random_pose=True)
    actions = rng.uniform(-1, 1, (steps, crib.action_dim))
    for a in actions[:200]:  # warm-up (the compiled touch loads), reach a state with contacts
        crib.step(a)
        crib.touch()
    it = iter(actions)
    physics = _per_call_ms(lambda: crib.step(next(it)), steps)
    it = iter(actions)
    contacts = []

    def step_and_count() -> None:
        crib.step(next(it))
        contacts.append(int(crib.physics.data.ncon))

    touch = _per_call_ms(crib.touch, steps, before=step_and_count)
    it = iter(actions)
    sparse = _per_call_ms(crib.touch_sparse, steps, before=lambda: crib.step(next(it)))
    it = iter(actions)
    proprio = _per_call_ms(crib.proprioception, steps, before=lambda: crib.step(next(it)))
    crib.close()

    sitting = build_infant("sitting", senses=("proprioception", "eyes"))
    sitting.reset(rng)
    acts = rng.uniform(-1, 1, (frames + 10, sitting.action_dim))
    for a in acts[:10]:
        sitting.step(a)
        sitting.eyes()
    it = iter(acts[10:])
    render = _per_call_ms(sitting.eyes, frames, before=lambda: sitting.step(next(it))) / 2.0
    sitting.close()
    return {
        "build_s": build_s,
        "physics_ms_per_step": physics,
        "touch_ms_per_step": touch,
        "touch_sparse_ms_per_step": sparse,
        "proprioception_ms_per_step": proprio,
        "render_ms_per_frame": render,
        "touch_sensors": int(crib.skin.num_sensors),
        "contacts_per_step": float(np.mean(contacts)),
    }


def _ms(samples: list[float]) -> str:
    x = 1e3 * np.asarray(samples)
    return (
        f"mean {x.mean():.3f} ms, median {np.median(x):.3f} ms, p90 {np.percentile(x, 90):.3f} ms"
    )


def main(steps: int = 10_000, frames: int = 300) -> None:
    """Time building, the crib's per-step senses and the sitting infant's eyes."""
    rng = np.random.default_rng(0)
    start = time.perf_counter()
    crib = build_infant("crib", senses=("touch", "proprioception", "vestibular"))
    print(f"build crib: {time.perf_counter() - start:.3f} s, {crib.skin.num_sensors} sensors")
    actions = rng.uniform(-1, 1, (steps, crib.action_dim))
    timings: dict[str, list[float]] = {"step": [], "touch": [], "hand_contacts": [], "rest": []}
    contacts = []
    start = time.perf_counter()
    for t, action in enumerate(actions):
        if t % crib.episode_steps == 0:
            crib.reset(rng, random_pose=True)
        t0 = time.perf_counter()
        crib.step(action)
        t1 = time.perf_counter()
        crib.touch()
        t2 = time.perf_counter()
        crib.hand_contacts()
        t3 = time.perf_counter()
        crib.proprioception()
        crib.vestibular()
        t4 = time.perf_counter()
        for key, dt in zip(timings, (t1 - t0, t2 - t1, t3 - t2, t4 - t3)):
            timings[key].append(dt)
        contacts.append(crib.data.ncon)
    total = time.perf_counter() - start
    print(f"crib, all senses but eyes: {steps / total:.0f} steps/s ({1e3 * total / steps:.3f} ms)")
    for key, samples in timings.items():
        print(f"  {key:14s} {_ms(samples)}")
    print(f"  contacts per step: mean {np.mean(contacts):.1f}, max {max(contacts)}")
    crib.close()

    sitting = build_infant("sitting", senses=("proprioception", "eyes"))
    sitting.reset(rng, random_pose=True)
    eyes, segmentation = [], []
    for action in rng.uniform(-1, 1, (frames, sitting.action_dim)):
        sitting.step(action)
        t0 = time.perf_counter()
        sitting.eyes()
        t1 = time.perf_counter()
        sitting.hand_visibility()
        eyes.append(t1 - t0)
        segmentation.append(time.perf_counter() - t1)
    print(f"sitting eyes (two 64x64 RGB frames): {_ms(eyes)}")
    print(f"sitting hand_visibility (two segmentation frames): {_ms(segmentation)}")
    sitting.close()


if __name__ == "__main__":
    main()
