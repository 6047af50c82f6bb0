"""The learner's speed: the PPO update's cost per rollout sample and the rollout inference's
per step, on random observations (``devlearn bench``; figures, never asserted)."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from devlearn.bench.speed import bench_training, without_user_warnings

if TYPE_CHECKING:
    from tensordict import TensorDict

    from devlearn.api.behavior import Behavior
    from devlearn.config.run_config import RunConfig
    from devlearn.plugins import PluginRegistry
    from devlearn.training.ppo import UniqueParamPPO


def run_config(
    behavior: Behavior, overrides: list[str], registry: PluginRegistry | None = None
) -> RunConfig:
    """The config ``devlearn run BEHAVIOR --set OVERRIDES`` trains with, resolved and checked
    as the run's (:func:`~devlearn.config.resolve.resolve_config`); ``registry``: where the
    behaviour is registered (default: the installed plugins)."""
    from devlearn.config.resolve import RunRequest, resolve_config
    from devlearn.plugins import PluginRegistry

    return resolve_config(RunRequest(behavior.name, overrides), registry or PluginRegistry())


def build_learner(
    behavior: Behavior,
    layout: str,
    num_envs: int,
    num_steps: int,
    seed: int = 0,
    registry: PluginRegistry | None = None,
) -> tuple[UniqueParamPPO, Callable[[], TensorDict]]:
    """The PPO algorithm a run of ``behavior`` would train, on random observations.

    Observation shapes and dtypes come from one real environment reset; the networks, optimiser
    and rollout storage are built exactly as ``devlearn run`` builds them, with the run
    config's defaults, ``network.layout=layout`` and a storage of ``num_steps`` steps per
    environment (``ppo.num_steps_per_env``: the rollout the benchmark collects). Returns
    ``(alg, observations)``: the algorithm and a function that draws a fresh
    (num_envs, *shape) observation batch.
    """
    from types import SimpleNamespace

    import torch
    from tensordict import TensorDict

    from devlearn.config.run_config import to_rsl_rl
    from devlearn.env import BehaviorEnv
    from devlearn.training.ppo import UniqueParamPPO
    from devlearn.training.process import quiet

    env = BehaviorEnv(behavior, seed=seed)
    first = env.reset()
    dt = SimpleNamespace(step_dt=env.step_dt)
    fake_env = SimpleNamespace(num_envs=num_envs, num_actions=env.action_dim, unwrapped=dt)
    env.close()
    overrides = [f"network.layout={layout}", f"ppo.num_steps_per_env={num_steps}"]
    cfg = run_config(behavior, overrides, registry)
    train_cfg = to_rsl_rl(cfg, behavior, list(first))
    train_cfg["multi_gpu"] = None
    gen = torch.Generator().manual_seed(seed)

    def observations() -> TensorDict:
        groups = {}
        for name, value in first.items():
            shape = (num_envs, *np.shape(value))
            if np.asarray(value).dtype == np.uint8:
                groups[name] = torch.randint(0, 256, shape, generator=gen, dtype=torch.uint8)
            else:
                groups[name] = torch.randn(shape, generator=gen)
        return TensorDict(groups, batch_size=[num_envs])

    torch.manual_seed(seed)
    with quiet():
        alg = UniqueParamPPO.construct_algorithm(observations(), fake_env, train_cfg, "cpu")
    alg.train_mode()
    return alg, observations


def collect_random(
    alg: UniqueParamPPO, observations: Callable[[], TensorDict], num_steps: int
) -> float:
    """Fill the rollout storage with ``num_steps`` random steps; return ms of inference/step."""
    import torch

    spent = 0.0
    with torch.inference_mode():
        obs = observations()
        n = obs.batch_size[0]
        for _ in range(num_steps):
            start = time.perf_counter()
            alg.act(obs)
            spent += time.perf_counter() - start
            obs = observations()
            extras = {"time_outs": torch.zeros(n)}
            alg.process_env_step(obs, torch.randn(n), torch.zeros(n, dtype=torch.long), extras)
        alg.compute_returns(obs)
    return 1000.0 * spent / num_steps


@without_user_warnings
def bench_update(
    behavior: Behavior,
    layout: str,
    num_envs: int,
    num_steps: int,
    repeats: int = 2,
    threads: int = 0,
    registry: PluginRegistry | None = None,
) -> dict[str, Any]:
    """The PPO update's cost per rollout sample, and the rollout inference's per step.

    One update is ``ppo.num_learning_epochs`` passes of ``ppo.num_mini_batches`` mini-batches
    over a rollout of ``num_envs x num_steps`` samples (here random ones), as in training.

    Args:
        behavior: The behaviour whose networks are measured.
        layout: ``shared`` or ``separate`` (``network.layout``).
        num_envs: Environments of the rollout.
        num_steps: Steps per environment.
        repeats: Timed updates after one warm-up; the best is kept (least disturbed).
        threads: torch threads during the update and inference (0: the training default, all
            cores this process may use, see :func:`devlearn.training.process.rank_cores`).
        registry: Where the behaviour is registered (default: the installed plugins).

    Returns:
        ``update_us_per_sample`` (seconds of one update / rollout samples, in microseconds),
        ``inference_ms_per_step`` (actor and critic forward on ``num_envs`` observations),
        ``parameters`` (unique trainable parameters) and ``threads``.
    """
    import torch

    from devlearn.training.ppo import unique_parameters
    from devlearn.training.process import rank_cores, update_threads

    threads = threads or rank_cores()
    alg, observations = build_learner(behavior, layout, num_envs, num_steps, registry=registry)
    best, inference = float("inf"), float("inf")
    with update_threads(threads):
        for k in range(repeats + 1):
            ms = collect_random(alg, observations, num_steps)
            start = time.perf_counter()
            alg.update()
            took = time.perf_counter() - start
            if k > 0:  # the first is a warm-up
                best, inference = min(best, took), min(inference, ms)
    params = sum(p.numel() for p in unique_parameters(alg.actor, alg.critic))
    return {
        "update_us_per_sample": 1e6 * best / (num_envs * num_steps),
        "inference_ms_per_step": inference,
        "parameters": float(params),
        "threads": float(threads),
        "torch_version": torch.__version__,
    }


@without_user_warnings
def bench_sb3_update(
    behavior: Behavior,
    num_envs: int,
    num_steps: int,
    repeats: int = 2,
    threads: int = 1,
    registry: PluginRegistry | None = None,
) -> dict[str, Any] | None:
    """Stable-Baselines3's PPO update on a rollout of the same size and settings, per sample:
    the comparison of issue #54 (``examples/sb3/train.py``'s learner: one flat MLP per network
    over the concatenated observations, hidden layers the behaviour's fusion and trunk sizes,
    devlearn's PPO values). Random observations and rewards, as :func:`bench_update`.

    Returns:
        ``update_us_per_sample`` and ``parameters``; None where SB3 is not installed
        (``pip install devlearn[sb3]``).
    """
    try:
        import gymnasium as gym
        from stable_baselines3 import PPO
        from stable_baselines3.common.vec_env import DummyVecEnv
    except ImportError:
        return None
    import torch

    from devlearn.env import BehaviorEnv
    from devlearn.training.process import update_threads

    env = BehaviorEnv(behavior, seed=0)
    first = env.reset()
    action_dim = env.action_dim
    env.close()
    cfg = run_config(behavior, [], registry)
    spec = behavior.network()
    net = [*spec.fusion_dims, *spec.trunk_dims]
    obs_space = gym.spaces.Dict(
        {
            k: gym.spaces.Box(-np.inf, np.inf, np.shape(v), np.float32)
            for k, v in first.items()
            if np.asarray(v).dtype != np.uint8
        }
    )
    act_space = gym.spaces.Box(-1.0, 1.0, (action_dim,), np.float32)

    class Blank(gym.Env):  # spaces only: the rollout is filled by hand below
        observation_space, action_space = obs_space, act_space

        def reset(self, *, seed: int | None = None, options: Any = None) -> Any:
            return obs_space.sample(), {}

        def step(self, action: Any) -> Any:
            return obs_space.sample(), 0.0, False, False, {}

    ppo = cfg.ppo
    model = PPO(
        "MultiInputPolicy",
        DummyVecEnv([Blank] * num_envs),
        n_steps=num_steps,
        batch_size=num_envs * num_steps // ppo.num_mini_batches,
        n_epochs=ppo.num_learning_epochs,
        learning_rate=ppo.learning_rate,
        gamma=ppo.gamma,
        gae_lambda=ppo.lam,
        clip_range=ppo.clip_param,
        clip_range_vf=ppo.clip_param,
        ent_coef=ppo.entropy_coef,
        vf_coef=ppo.value_loss_coef,
        max_grad_norm=ppo.max_grad_norm,
        policy_kwargs={"net_arch": {"pi": net, "vf": net}},
        device="cpu",
        seed=0,
    )
    model._setup_learn(num_envs * num_steps)  # noqa: SLF001 (the logger train() writes to)
    gen = torch.Generator().manual_seed(0)
    buffer = model.rollout_buffer
    best = float("inf")
    with update_threads(threads):
        for k in range(repeats + 1):
            buffer.reset()
            for _ in range(num_steps):
                obs: Any = {
                    name: torch.randn((num_envs, *(space.shape or ())), generator=gen).numpy()
                    for name, space in obs_space.spaces.items()
                }
                with torch.no_grad():
                    actions, values, log_prob = model.policy(model.policy.obs_to_tensor(obs)[0])
                rewards = torch.randn(num_envs, generator=gen).numpy()
                starts = np.zeros(num_envs, dtype=np.float32)
                buffer.add(obs, actions.numpy(), rewards, starts, values, log_prob)
            buffer.compute_returns_and_advantage(values, np.zeros(num_envs, dtype=bool))
            start = time.perf_counter()
            model.train()
            took = time.perf_counter() - start
            if k > 0:
                best = min(best, took)
    params = sum(p.numel() for p in model.policy.parameters() if p.requires_grad)
    return {
        "update_us_per_sample": 1e6 * best / (num_envs * num_steps),
        "parameters": float(params),
    }


OLD_LEARNER = ["network.layout=separate", "torch_threads=1", "update_threads=1"]
"""``--set`` options that train as before the shared layout and automatic threads."""


def bench_learner(registry: PluginRegistry, quick: bool, progress: Callable[[str], None]) -> dict:
    """PPO update cost per sample and training steps/s, old learner against new, one session.

    Old: separate actor and critic, one torch thread (the defaults before the shared layout).
    New: ``devlearn run`` defaults (shared body, automatic threads; the update benchmark uses
    all cores). Keys ``<behavior>_update_us_per_sample[_old]`` and
    ``<behavior>_train_steps_per_s[_old]``; for self-touch also the run's defaults and
    Stable-Baselines3's PPO on the same rollout, one thread each
    (``self_touch_update_us_per_sample[_sb3]_1thread``, issue #54); hand regard trains with 8
    envs and a short babbling (speed does not depend on the detector's quality).
    """
    from devlearn.training.process import rank_cores

    behaviors = registry.behaviors()
    result: dict[str, Any] = {}
    rollouts = {"self_touch": (16, 32 if quick else 128), "hand_regard": (8, 8 if quick else 32)}
    for name, (envs, steps) in rollouts.items():
        if name not in behaviors:
            continue
        for suffix, layout, threads in (("_old", "separate", 1), ("", "shared", rank_cores())):
            progress(f"{name}: PPO update, {layout} networks, {threads} thread(s)")
            behavior, repeats = behaviors[name](), 1 if quick else 2
            figures = bench_update(behavior, layout, envs, steps, repeats, threads, registry)
            result[f"{name}_update_us_per_sample{suffix}"] = figures["update_us_per_sample"]
            result[f"{name}_inference_ms_per_step{suffix}"] = figures["inference_ms_per_step"]
    if "self_touch" in behaviors:  # the same rollout's update in SB3's PPO (issue #54)
        envs, steps = rollouts["self_touch"]
        progress("self_touch: PPO update, Stable-Baselines3 (the same rollout), 1 thread")
        behavior, repeats = behaviors["self_touch"](), 1 if quick else 2
        for threads_used, suffix in ((1, "_1thread"),):
            mine = bench_update(behavior, "separate", envs, steps, repeats, threads_used, registry)
            result[f"self_touch_update_us_per_sample{suffix}"] = mine["update_us_per_sample"]
            sb3 = bench_sb3_update(behavior, envs, steps, repeats, threads_used, registry)
            if sb3 is not None:
                result[f"self_touch_update_us_per_sample_sb3{suffix}"] = sb3["update_us_per_sample"]
                result["self_touch_parameters_sb3"] = sb3["parameters"]
            result["self_touch_parameters"] = mine["parameters"]
    old = [arg for kv in OLD_LEARNER for arg in ("--set", kv)]
    if "self_touch" in behaviors:
        progress("self_touch: end-to-end training, old learner (separate networks, 1 thread)")
        result["self_touch_train_steps_per_s_old"] = bench_training(
            "self_touch", 8192 if quick else 32768, old, progress
        )
    if "hand_regard" in behaviors:
        progress("hand_regard: end-to-end training, old learner (separate networks, 1 thread)")
        short = ["behavior.babbling_steps=300", "behavior.correlation_threshold=0"]
        result["hand_regard_train_steps_per_s_old"] = bench_training(
            "hand_regard",
            1024 if quick else 4096,
            ["--envs", "8", *(arg for kv in short for arg in ("--set", kv)), *old],
            progress,
        )
    return result
