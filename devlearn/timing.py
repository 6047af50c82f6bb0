"""The simulated infant's clock, in a module that imports nothing, so that config checks
(``devlearn config --set``) can read it without loading MuJoCo: BabyBench's 5 ms physics step
and its 5-second episode (``../shared/reference/infant-and-benchmark-facts.md``, sec. 1)."""

PHYSICS_TIMESTEP = 0.005
"""Seconds per physics step (200 Hz)."""
EPISODE_STEPS = 1000
"""Physics steps per episode (5 simulated seconds)."""
