"""Motor noise with the infants' spectrum (issue #57): f^-beta, seeded per env, never reset,
added to the actions the env applies, saved with the env; off by default."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import welch

from devlearn import UsageError
from devlearn.config import run_config
from devlearn.env import BehaviorEnv, EnvSettings
from devlearn.env.motor_noise import PowerLawNoise, power_law_filters
from devlearn.testing.fake_infant import FakeInfant, TinyBehavior, TinyConfig

DT = 0.005  # BabyBench's physics step


class RecordingInfant(FakeInfant):
    """The fake infant, keeping every action its body got."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.applied: list[np.ndarray] = []

    def step(self, action: np.ndarray) -> None:
        self.applied.append(np.array(action))
        super().step(action)


def recording_factory(scene, senses=(), **options):
    return RecordingInfant(scene, senses=senses, episode_steps=10, **options)


def noisy_env(std: float = 0.2, beta: float = 0.88, seed: int = 3) -> BehaviorEnv:
    settings = EnvSettings(action_noise_std=std, action_noise_beta=beta)
    env = BehaviorEnv(
        TinyBehavior(TinyConfig(use_eyes=False)), seed, recording_factory, settings=settings
    )
    env.reset()
    return env


def spectral_slope(x: np.ndarray, low: float = 0.1, high: float = 20.0) -> float:
    """-slope of log power against log frequency (Welch, 82 s segments) in [low, high] Hz."""
    freq, power = welch(x, fs=1.0 / DT, nperseg=2**14)
    band = (freq >= low) & (freq <= high)
    return -float(np.polyfit(np.log(freq[band]), np.log(power[band]), 1)[0])


@pytest.mark.slow
@pytest.mark.parametrize("beta", [0.69, 0.88, 0.0, 1.5])
def test_the_noise_spectrum_falls_as_f_to_the_minus_beta(beta):
    # 2^17 physics steps (11 simulated minutes) of 2 streams: the fitted slope is beta
    # (white noise at 0, a steeper one at 1.5); the streams' spread is the std asked (for
    # beta >= 1 the slowest processes, 100 s, hold most of the variance: too few of them here)
    noise = PowerLawNoise(2, 0.3, beta, DT, seed=1)
    x = noise.sample(2**17)
    for k in range(2):
        assert spectral_slope(x[:, k]) == pytest.approx(beta, abs=0.04), (beta, k)
    if beta < 1:
        assert x.std(axis=0) == pytest.approx([0.3, 0.3], rel=0.1)
    # the two streams are independent (their steps: the slow parts have few samples)
    steps = np.diff(x, axis=0)
    assert abs(np.corrcoef(steps[:, 0], steps[:, 1])[0, 1]) < 0.02
    # the infants' 0.69 and 0.88 are told apart: a white or 1/f stream would not pass above
    assert abs(spectral_slope(x[:, 0]) - beta) < abs(spectral_slope(x[:, 0]) - (beta + 0.19))


def test_the_noise_is_correlated_in_time_as_pink_noise_is():
    # white noise forgets at once; f^-0.88 noise is still correlated 50 ms (10 steps) later
    pink = PowerLawNoise(1, 1.0, 0.88, DT, seed=0).sample(40_000)[:, 0]
    white = PowerLawNoise(1, 1.0, 0.0, DT, seed=0).sample(40_000)[:, 0]

    def lag_correlation(x, lag):
        return float(np.corrcoef(x[:-lag], x[lag:])[0, 1])

    assert lag_correlation(pink, 10) > 0.3
    assert abs(lag_correlation(white, 10)) < 0.05


def test_the_filters_are_fitted_at_the_bodys_physics_step():
    a, variance = power_law_filters(0.88, DT)
    assert variance.sum() == pytest.approx(1.0) and (variance > 0).all()
    assert ((a >= 0) & (a < 1)).all()
    # at 400 Hz an octave more: a process per octave of corners up to the Nyquist frequency
    assert len(power_law_filters(0.0, DT / 2)[0]) <= len(a) + 1
    slope = spectral_slope(PowerLawNoise(1, 1.0, 0.88, DT / 2, seed=0).sample(2**17)[:, 0], 0.1)
    assert slope == pytest.approx(0.88, abs=0.06)


def test_the_noise_is_seeded_per_env_and_independent_of_the_initial_poses():
    same = [PowerLawNoise(3, 0.2, 0.88, DT, seed=5).sample(50) for _ in range(2)]
    np.testing.assert_array_equal(same[0], same[1])
    other = PowerLawNoise(3, 0.2, 0.88, DT, seed=6).sample(50)
    assert not np.allclose(same[0], other)
    # the env's pose generator (seeded with the seed alone) is not the noise's
    assert not np.allclose(np.random.default_rng(5).standard_normal(9), same[0][:3].ravel())


def test_the_env_applies_the_action_plus_the_noise_clipped():
    env = noisy_env(std=0.2, seed=3)
    reference = PowerLawNoise(env.action_dim, 0.2, 0.88, DT, seed=3)
    action = np.array([0.5, -0.95, 0.0])
    for _ in range(30):
        env.step(action)
    applied = np.array(env.infant.applied)
    expected = np.clip(action + reference.sample(30), -1, 1)
    np.testing.assert_allclose(applied, expected)
    assert not np.allclose(applied, action)  # the body got noise
    assert (applied[:, 1] >= -1).all() and (applied[:, 1] == -1).any()  # clipped at the bound


def test_the_noise_runs_on_through_episode_resets():
    # 10-step episodes: 30 steps are three episodes, and the noise does not start again
    env = noisy_env(std=0.2, seed=4)
    for _ in range(30):
        env.step(np.zeros(env.action_dim))
    applied = np.array(env.infant.applied)
    np.testing.assert_allclose(
        applied, np.clip(PowerLawNoise(3, 0.2, 0.88, DT, seed=4).sample(30), -1, 1)
    )
    assert not np.allclose(applied[:10], applied[10:20])


def test_a_saved_env_continues_the_same_noise():
    env = noisy_env(seed=2)
    for _ in range(7):
        env.step(np.zeros(env.action_dim))
    state = env.state_dict()
    later = [env.motor_command(np.zeros(env.action_dim)) for _ in range(5)]
    resumed = noisy_env(seed=99)  # another seed: the saved stream wins
    resumed.load_state_dict(state)
    again = [resumed.motor_command(np.zeros(env.action_dim)) for _ in range(5)]
    np.testing.assert_array_equal(np.array(later), np.array(again))


def test_no_noise_by_default_the_action_itself():
    env = BehaviorEnv(TinyBehavior(TinyConfig(use_eyes=False)), 0, recording_factory)
    env.reset()
    action = np.array([0.3, -0.2, 0.1])
    for _ in range(3):
        env.step(action)
    assert env.motor_noise is None and "motor_noise" not in env.state_dict()
    assert all(np.array_equal(a, action) for a in env.infant.applied)
    cfg = run_config.RunConfig()
    assert (cfg.env.action_noise_std, EnvSettings.of(cfg.env).action_noise_std) == (0.0, 0.0)


def test_the_run_config_gives_the_envs_their_noise_and_checks_it():
    cfg = run_config.RunConfig()
    cfg.env.action_noise_std, cfg.env.action_noise_beta = 0.1, 0.69
    settings = EnvSettings.of(cfg.env, 300.0)
    assert (settings.action_noise_std, settings.action_noise_beta) == (0.1, 0.69)
    assert (settings.action_repeat, settings.episode_seconds) == (cfg.env.action_repeat, 300.0)
    with pytest.raises(ValueError, match="action_noise_std must be from 0"):
        EnvSettings(action_noise_std=-0.1)
    with pytest.raises(ValueError, match=r"action_noise_beta must be from 0 .* below 2"):
        EnvSettings(action_noise_std=0.1, action_noise_beta=2.0)


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("env.action_noise_std", "1.5", "env.action_noise_std must be from 0"),
        ("env.action_noise_beta", "-0.5", "env.action_noise_beta must be from 0"),
    ],
)
def test_a_run_refuses_noise_out_of_range(key, value, message):
    from devlearn.config.checks import check_config
    from devlearn.config.values import apply_overrides

    cfg = run_config.RunConfig()
    apply_overrides(cfg, {key: value})
    with pytest.raises(UsageError, match=message):
        check_config(cfg)


def test_an_evaluation_plays_with_the_policys_motor_noise():
    # the noise is the body's: devlearn eval's envs take it from the checkpoint's config
    from devlearn.evaluation.evaluate import EvalRequest, EvalSubject, evaluation_conditions
    from devlearn.evaluation.policy import Baseline

    cfg = run_config.RunConfig()
    cfg.env.action_noise_std, cfg.env.action_noise_beta = 0.2, 0.69
    policy = Baseline("zero", cfg, TinyBehavior(TinyConfig(use_eyes=False)))
    subject = EvalSubject(policy, None)
    request = EvalRequest("tiny", policy="zero", episodes=2, session=300.0)
    settings = evaluation_conditions(request, subject).settings
    assert (settings.action_noise_std, settings.action_noise_beta) == (0.2, 0.69)
    assert settings.episode_seconds == 300.0
    cfg.env.action_noise_std = 0.0
    assert evaluation_conditions(request, subject).settings.action_noise_std == 0.0
