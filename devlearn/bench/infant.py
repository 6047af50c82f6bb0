"""Speed of the bare infant: ``python -m devlearn.bench.infant`` prints figures (no asserts)."""

from __future__ import annotations

import time

import numpy as np

from devlearn.infant import build_infant


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
