"""Train a devlearn behaviour with Stable-Baselines3 (PPO or SAC) through devlearn's Gymnasium
vector env, then write a policy file that ``devlearn eval`` evaluates under devlearn's protocol.

    python examples/sb3/train.py --algo ppo --steps 2048000 --seed 1 --out runs/sb3_ppo/seed=1
    devlearn eval self_touch --checkpoint runs/sb3_ppo/seed=1/policy.pt --episodes 100 \\
        --out runs/sb3_ppo/seed=1/eval

Steps are counted as devlearn counts them: ``--steps`` is physics steps summed over the
environments, as ``devlearn run --steps`` is. One Gymnasium step of one env is one decision,
``env.action_repeat`` physics steps (5 by default), so SB3's ``total_timesteps`` (decisions,
summed over envs) is ``steps / action_repeat``. ``--seconds`` stops SB3's learning at a
wall-clock budget as well (SAC given the time our PPO run took). OUT gets ``policy.pt`` (the
scripted policy: the deterministic action, observation normalisation frozen inside),
``model.zip`` and ``vecnormalize.pkl`` (SB3's own, to continue or inspect) and ``train.json``
(steps and decisions taken, wall-clock seconds, seed, SB3's settings, the code's commit).
"""

from __future__ import annotations

import argparse
import json
import pickle
import platform
import subprocess
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import stable_baselines3
import torch
from sb3_vec_env import GymnasiumVecEnv
from stable_baselines3 import PPO, SAC
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env import VecMonitor, VecNormalize

import devlearn
import devlearn.gym

ALGORITHMS = {"ppo": PPO, "sac": SAC}
NET = [512, 256, 256]
"""Hidden layers of every network: the size of devlearn's self-touch actor (encoders of 128 and
256 per observation group, a fusion layer of 512, a trunk of 256 and 256), in SB3's form (the
groups flattened and concatenated, then one MLP)."""


class LinearRate:
    """SB3's learning-rate schedule: ``initial`` until the last ``decay_share`` of the run, then
    falling to 0 at its end (devlearn's ``ppo.schedule=linear`` with ``ppo.decay_share``). SB3
    calls it with the share of the run left (1 at the start). A class, not a lambda, so that
    ``model.zip`` pickles it."""

    def __init__(self, initial: float, decay_share: float = 1.0) -> None:
        self.initial = initial
        self.decay_share = decay_share

    def __call__(self, progress_remaining: float) -> float:
        return self.initial * min(1.0, progress_remaining / self.decay_share)

    def __repr__(self) -> str:
        if self.decay_share == 1.0:
            return f"linear({self.initial:g} -> 0)"
        return f"linear({self.initial:g} -> 0 over the last {self.decay_share:g})"


def ppo_settings(cfg: Any, net: list[int]) -> dict[str, Any]:
    """SB3 PPO with the values of devlearn's PPO (the resolved config's ``ppo`` section), so
    that the comparison is of learners, not of settings: rollouts of ``num_steps_per_env``
    decisions per env, the same mini-batches, epochs, step size, discount, GAE, clip (the value
    loss clipped too, as rsl-rl's), entropy and value weights and gradient clip; networks of
    ``net``. The step size is the run's (``ppo.learning_rate``, less for a run longer than
    ``ppo.full_rate_steps``); ``ppo.schedule=linear`` becomes SB3's linear schedule (as
    devlearn's, held until the last ``ppo.decay_share`` of the run); ``fixed`` and ``adaptive``
    a constant step size (SB3 has no KL-adaptive one)."""
    ppo = cfg.ppo
    step = ppo.run_rate(cfg.total_steps)
    rate: float | LinearRate = step
    if ppo.schedule == "linear":
        rate = LinearRate(step, ppo.decay_share)
    return {
        "n_steps": ppo.num_steps_per_env,
        "batch_size": cfg.num_envs * ppo.num_steps_per_env // ppo.num_mini_batches,
        "n_epochs": ppo.num_learning_epochs,
        "learning_rate": rate,
        "gamma": ppo.gamma,
        "gae_lambda": ppo.lam,
        "clip_range": ppo.clip_param,
        "clip_range_vf": ppo.clip_param,
        "ent_coef": ppo.entropy_coef,
        "vf_coef": ppo.value_loss_coef,
        "max_grad_norm": ppo.max_grad_norm,
        "policy_kwargs": {"net_arch": {"pi": net, "vf": net}},
    }


def sac_settings(cfg: Any, net: list[int], decisions: int) -> dict[str, Any]:
    """SB3 SAC's own defaults (step size, batch 256, tau, one gradient step per vector step,
    automatic entropy), devlearn's discount per decision, networks of ``net``, and a replay
    buffer no larger than the run (it keeps every decision of a 2M-step run)."""
    return {
        "gamma": cfg.ppo.gamma,
        "buffer_size": max(min(1_000_000, decisions), 1_000),
        "policy_kwargs": {"net_arch": {"pi": net, "qf": net}},
    }


class WallClock(BaseCallback):
    """Stops learning once ``seconds`` have passed (0: never), and times the rollouts:
    ``collect_s`` sums the seconds from each rollout's start to its end (policy, envs and
    buffer, as devlearn's ``collect_s``); the rest of ``learn()`` is the updates and SB3's
    bookkeeping (issue #54's split of the seconds of learning)."""

    def __init__(self, seconds: float) -> None:
        super().__init__()
        self.seconds = seconds
        self.start = time.perf_counter()
        self.stopped = False
        self.collect_s = 0.0
        self._rollout_start = 0.0

    def _on_training_start(self) -> None:
        self.start = time.perf_counter()

    def _on_rollout_start(self) -> None:
        self._rollout_start = time.perf_counter()

    def _on_rollout_end(self) -> None:
        self.collect_s += time.perf_counter() - self._rollout_start

    def _on_step(self) -> bool:
        self.stopped = 0 < self.seconds <= time.perf_counter() - self.start
        return not self.stopped


class DeterministicSb3Policy(torch.nn.Module):
    """The SB3 policy's deterministic action as ``devlearn eval`` takes it:
    ``forward(*observations)`` in ``names`` order -> (N, action_dim) in [-1, 1], with
    VecNormalize's observation statistics frozen inside (PPO: the Gaussian's mean; SAC: the
    squashed mean)."""

    def __init__(self, model: BaseAlgorithm, names: list[str], normalizer: VecNormalize) -> None:
        super().__init__()
        self.sac = isinstance(model, SAC)
        # SAC: its actor (the squashed Gaussian); PPO: the policy (actions, values, log-probs)
        self.acts = model.actor if isinstance(model, SAC) else model.policy
        self.names = names
        self.clip = float(normalizer.clip_obs)
        stats = normalizer.obs_rms if normalizer.norm_obs else {}
        assert isinstance(stats, dict)
        self.normalized = [n for n in names if n in stats]
        for name in self.normalized:
            std = (stats[name].var + normalizer.epsilon) ** 0.5
            self.register_buffer(f"mean_{name}", torch.as_tensor(stats[name].mean).float())
            self.register_buffer(f"std_{name}", torch.as_tensor(std).float())

    def forward(self, *observations: torch.Tensor) -> torch.Tensor:
        obs = {}
        for name, value in zip(self.names, observations):
            if name in self.normalized:
                mean, std = getattr(self, f"mean_{name}"), getattr(self, f"std_{name}")
                value = torch.clamp((value - mean) / std, -self.clip, self.clip)
            obs[name] = value
        actions = self.acts(obs, deterministic=True)
        return torch.clamp(actions if self.sac else actions[0], -1.0, 1.0)


def git_commit() -> str | None:
    """The commit of the code that runs (None outside a git checkout)."""
    try:
        done = subprocess.run(
            ["git", "rev-parse", "HEAD"],
            cwd=Path(__file__).resolve().parent,
            capture_output=True,
            text=True,
            timeout=10,
            check=True,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return done.stdout.strip()


def parse(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--algo", choices=sorted(ALGORITHMS), required=True)
    p.add_argument("--behavior", default="self_touch", help="a devlearn behaviour")
    p.add_argument("--steps", type=float, required=True, help="physics steps, as devlearn run")
    p.add_argument("--seconds", type=float, default=0.0, help="wall-clock budget (0: none)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--envs", type=int, default=16, help="environments (devlearn's default)")
    p.add_argument("--workers", type=int, default=-1, help="worker processes (-1: per core)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    p.add_argument("--net", default=",".join(map(str, NET)), help="hidden layers of every network")
    p.add_argument(
        "--threads",
        type=int,
        default=1,
        help="torch threads (default 1: more wait for cores the env workers hold; 0: torch's)",
    )
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--verbose", action="store_true", help="SB3's progress tables")
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Train, write OUT's files; return what train.json holds."""
    args = parse(argv)
    started = time.perf_counter()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    settings = [*args.overrides, f"seed={args.seed}", f"total_steps={int(args.steps)}"]
    envs = devlearn.gym.make_vec(
        devlearn.gym.env_id(args.behavior), args.envs, args.workers, overrides=settings
    )
    try:
        base = devlearn.gym.devlearn_env(envs)
        cfg = base.setup.config
        decisions = int(args.steps) // cfg.env.action_repeat
        normalized = list(base.setup.behavior.network().normalize)
        venv = VecNormalize(
            VecMonitor(GymnasiumVecEnv(envs)),
            norm_obs=bool(normalized),
            norm_obs_keys=normalized or None,
            norm_reward=cfg.ppo.normalize_rewards,
            clip_reward=cfg.ppo.reward_clip,
            gamma=cfg.ppo.gamma,
        )
        net = [int(n) for n in args.net.split(",")]
        if args.algo == "ppo":
            hyper = ppo_settings(cfg, net)
        else:
            hyper = sac_settings(cfg, net, decisions)
        if args.threads:
            torch.set_num_threads(args.threads)
        model = ALGORITHMS[args.algo](
            "MultiInputPolicy",
            venv,
            seed=args.seed,
            device="cpu",
            verbose=int(args.verbose),
            **hyper,
        )
        clock = WallClock(args.seconds)
        learn_start = time.perf_counter()
        model.learn(total_timesteps=decisions, callback=clock)
        learn_s = time.perf_counter() - learn_start
        policy = DeterministicSb3Policy(model, devlearn.gym.observation_names(envs), venv)
        steps = base.clock.physics_steps  # every decision SB3 took, in physics steps
        with warnings.catch_warnings():  # torch.distributions' argument checks: constant here
            warnings.simplefilter("ignore", torch.jit.TracerWarning)
            devlearn.gym.save_policy(
                policy, envs, out / "policy.pt", learner=f"sb3_{args.algo}", env_steps=steps
            )
        # every file through devlearn's atomic writer: a kill leaves the old file or the new one
        devlearn.write_atomically(out / "model.zip", model.save)
        devlearn.write_atomically(out / "vecnormalize.pkl", lambda f: pickle.dump(venv, f))
        record = {
            "algo": args.algo,
            "learner": f"sb3_{args.algo}",
            "behavior": args.behavior,
            "seed": args.seed,
            "steps_requested": int(args.steps),
            "env_steps": steps,
            "decisions": steps // cfg.env.action_repeat,
            "action_repeat": cfg.env.action_repeat,
            "num_envs": cfg.num_envs,
            "workers": args.workers,
            "seconds_budget": args.seconds,
            "stopped_by": "seconds" if clock.stopped else "steps",
            "learn_s": learn_s,
            "collect_s": clock.collect_s,
            "wall_clock_s": time.perf_counter() - started,
            "settings": json.loads(json.dumps(hyper, default=repr)),
            "overrides": args.overrides,
            "stable_baselines3": stable_baselines3.__version__,
            "torch_threads": torch.get_num_threads(),
            "machine": f"{platform.processor() or platform.machine()}",
            "commit": git_commit(),
            "command": [Path(sys.argv[0]).name, *(argv if argv is not None else sys.argv[1:])],
            "out": str(out),
        }
        devlearn.write_text_atomically(out / "train.json", json.dumps(record, indent=2) + "\n")
        return record
    finally:
        envs.close()


if __name__ == "__main__":
    done = main()
    print(
        f"{done['learner']}: {done['env_steps']:,} physics steps ({done['decisions']:,} "
        f"decisions) in {done['learn_s']:.0f} s of learning; wrote {done['out']}"
    )
