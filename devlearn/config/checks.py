"""Start-up checks of a run: config values, a resumed run's seed and growth schedule, memory for
the envs, the output folder."""

from __future__ import annotations

import math
import os
import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

from devlearn.ages import check_age
from devlearn.api.errors import UsageError
from devlearn.config.growth import growth_schedule, keep_growth_on_resume
from devlearn.config.run_config import LR_SCHEDULES
from devlearn.files import unwritable
from devlearn.timing import EPISODE_STEPS, decision_rate_error

if TYPE_CHECKING:
    from devlearn.config.run_config import RunConfig

SEED_MAX = 2**32 - 1
"""Largest seed (numpy's global generator takes 32-bit seeds)."""
ENV_MEMORY_MB = 10
"""Memory one environment needs at least, in MB (a floor: measured 14 MB for self_touch and 46
MB for hand_regard, which renders the eyes); ``--envs`` beyond what is available is refused."""
WORKER_MEMORY_MB = 200
"""Memory one env worker process needs at least, in MB (Python, MuJoCo, numpy)."""
RUN_FILES = ("config.json", "metrics.jsonl", "checkpoint_latest.pt")
"""Files whose presence marks a folder as holding a run."""
_DEVICE = re.compile(r"^(cpu|cuda(:\d+)?)$")


def _positive(
    cfg: RunConfig, name: str, low: float = 0.0, high: float = math.inf, closed: bool = False
) -> None:
    value = getattr(cfg.ppo, name)
    inside = low <= value <= high if closed else low < value <= high
    if not (isinstance(value, (int, float)) and math.isfinite(value) and inside):
        lo = "[" if closed else "("
        hi = f"{high:g}]" if math.isfinite(high) else "inf)"
        raise UsageError(f"ppo.{name} must be a finite number in {lo}{low:g}, {hi}, got {value}")


STEPS_MAX = 10**12
"""Largest ``--steps`` (a million times the paper's 8M-step runs; beyond it counters and the
progress bar overflow)."""
ENVS_MAX = 1_000_000
"""Largest ``--envs`` per rank."""
WORKERS_MAX = 4_096
"""Largest ``--workers`` per rank."""
THREADS_MAX = 4_096
"""Largest ``torch_threads`` / ``update_threads``."""
INTERVAL_MAX = 10**9
"""Largest ``save_interval`` (iterations)."""
PPO_COUNT_MAX = 10**6
"""Largest rollout length, epochs and mini-batches per iteration."""
OVERSHOOT_MAX = 10
"""A run trains whole iterations, so a budget below one iteration trains one; beyond this many
times the budget (``env.action_repeat=1000`` with ``--steps 1024`` trained 128,000 steps) the
config is refused as a mistake."""


def _whole(value: Any, option: str, low: int, high: int, low_note: str = "") -> None:
    """Raise UsageError unless ``value`` is an integer in ``[low, high]``."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise UsageError(f"{option} must be an integer, got {value!r}")
    if value < low:
        note = f" ({low_note})" if low_note else ""
        raise UsageError(f"{option} must be at least {low}{note}, got {value}")
    if value > high:
        raise UsageError(f"{option} must be at most {high:g}, got {value:g}")


def check_config(cfg: RunConfig) -> None:
    """Reject values that would fail later (or train on garbage) with a less clear error: every
    number within bounds (each message one line naming the option and its valid range), checked
    before anything is written."""
    _whole(cfg.total_steps, "--steps", 1, STEPS_MAX)
    _whole(cfg.num_envs, "--envs", 1, ENVS_MAX)
    _whole(cfg.workers, "--workers", -1, WORKERS_MAX, "-1: one per core, 0: in process")
    if not 0 <= cfg.seed <= SEED_MAX:
        raise UsageError(f"--seed must be an integer from 0 to {SEED_MAX}, got {cfg.seed:g}")
    _whole(cfg.torch_threads, "torch_threads", 0, THREADS_MAX, "0: automatic")
    _whole(cfg.update_threads, "update_threads", 0, THREADS_MAX, "0: automatic")
    _whole(cfg.save_interval, "save_interval", 1, INTERVAL_MAX)
    if not _DEVICE.match(cfg.device):
        raise UsageError(f"--device must be cpu, cuda or cuda:N, got '{cfg.device}'")
    if cfg.ppo.schedule not in LR_SCHEDULES:
        raise UsageError(
            f"ppo.schedule must be one of {', '.join(LR_SCHEDULES)}, got '{cfg.ppo.schedule}'"
        )
    if not 0 < cfg.ppo.decay_share <= 1:
        raise UsageError(
            f"ppo.decay_share must be above 0 and at most 1 (the share of the run at its end "
            f"over which ppo.schedule=linear falls), got {cfg.ppo.decay_share:g}"
        )
    _whole(cfg.ppo.full_rate_steps, "ppo.full_rate_steps", 0, STEPS_MAX, "0: any run's")
    for name in ("num_steps_per_env", "num_learning_epochs", "num_mini_batches"):
        _whole(getattr(cfg.ppo, name), f"ppo.{name}", 1, PPO_COUNT_MAX)
    _positive(cfg, "learning_rate", high=1.0)
    _positive(cfg, "clip_param", high=1.0)
    _positive(cfg, "gamma", high=1.0)
    _positive(cfg, "lam", high=1.0, closed=True)
    _positive(cfg, "max_grad_norm")
    _positive(cfg, "entropy_coef", closed=True)
    _positive(cfg, "value_loss_coef", closed=True)
    if cfg.ppo.desired_kl is not None:
        _positive(cfg, "desired_kl")
    _check_batches(cfg)
    _check_infant(cfg)  # the reward table: when its behaviour is built (check_reward_table)


def check_resumed(saved: RunConfig, resumed: RunConfig, run_dir: Path) -> str | None:
    """Check a resumed run's config against the one its run saved (``run_dir/config.json``):
    the seed stays the run's (its random states continue from the checkpoint) and so does its
    growth schedule, whose span is fixed in ``resumed`` where ``--steps`` changed
    (:func:`~devlearn.config.growth.keep_growth_on_resume`: the body's age never goes back).

    Returns:
        A note saying that the growth schedule's span was fixed (None otherwise).
    Raises:
        UsageError: Another seed or growth schedule (the saved and the new values named, and
            how to get them: a new run from the run's checkpoint).
    """
    note = keep_growth_on_resume(saved, resumed, str(run_dir))
    if resumed.seed != saved.seed:
        raise UsageError(
            f"run {run_dir} was trained with seed {saved.seed}, which a resumed run keeps "
            "(its random states continue from the checkpoint); for another seed start a new "
            f"run from its checkpoint: --from {run_dir / 'checkpoint_latest.pt'} "
            f"--seed {resumed.seed} --out NEW_DIR"
        )
    return note


def _check_infant(cfg: RunConfig) -> None:
    """The body's age and growth schedule (:mod:`devlearn.config.growth`)."""
    if cfg.infant.age_months is not None:
        try:
            check_age(cfg.infant.age_months)
        except ValueError as err:
            raise UsageError(str(err)) from None
    _whole(cfg.infant.growth_every, "infant.growth_every", 0, STEPS_MAX, "0: 24 pieces")
    _whole(cfg.infant.growth_steps, "infant.growth_steps", 0, STEPS_MAX, "0: total_steps")
    growth_schedule(cfg)


def _check_noise(cfg: RunConfig) -> None:
    """The noises' bounds (those of :func:`devlearn.env.motor_noise.check_noise`, which the envs
    and the policy's head apply again): ``env.action_noise_std`` from 0 to 1, and the spectral
    exponents of the motor noise (``env.action_noise_beta``) and of the policy's exploration
    (``network.exploration_beta``) from 0 to below 2."""
    std = cfg.env.action_noise_std
    if not 0.0 <= std <= 1.0:
        raise UsageError(
            f"env.action_noise_std must be from 0 (off) to 1 (action units), got {std:g}"
        )
    for key, beta in (
        ("env.action_noise_beta", cfg.env.action_noise_beta),
        ("network.exploration_beta", cfg.network.exploration_beta),
    ):
        if not 0.0 <= beta < 2.0:
            raise UsageError(f"{key} must be from 0 (white noise) to below 2, got {beta:g}")


def _check_batches(cfg: RunConfig) -> None:
    """The decision rate against the episode and the budget, and the mini-batches against the
    rollout: values that pass their own bounds but fail or hang together."""
    repeat = cfg.env.action_repeat
    _whole(repeat, "env.action_repeat", 1, EPISODE_STEPS)
    if error := decision_rate_error(repeat):
        raise UsageError(error)
    _check_noise(cfg)
    rollout = cfg.num_envs * cfg.ppo.num_steps_per_env
    iteration = rollout * repeat
    if iteration > OVERSHOOT_MAX * cfg.total_steps:
        raise UsageError(
            f"--steps {cfg.total_steps} is less than a tenth of one iteration ({cfg.num_envs} "
            f"envs x {cfg.ppo.num_steps_per_env} decisions x env.action_repeat {repeat} = "
            f"{iteration} physics steps), which a run trains whole; give more steps, fewer envs "
            "or a shorter rollout"
        )
    if rollout < 2:
        raise UsageError(
            f"a rollout of {rollout} sample ({cfg.num_envs} env x {cfg.ppo.num_steps_per_env} "
            "decision) cannot normalise advantages; give more envs or ppo.num_steps_per_env"
        )
    if rollout // cfg.ppo.num_mini_batches < 2:
        raise UsageError(
            f"ppo.num_mini_batches={cfg.ppo.num_mini_batches} leaves fewer than 2 samples per "
            f"mini-batch of a {rollout}-sample rollout ({cfg.num_envs} envs x "
            f"{cfg.ppo.num_steps_per_env} decisions; advantages are normalised per mini-batch); "
            f"at most {max(1, rollout // 2)}"
        )


def available_memory_mb() -> float | None:
    """``MemAvailable`` of /proc/meminfo in MB (None where unknown)."""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) / 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def check_memory(num_envs: int, workers: int, available_mb: float | None = None) -> None:
    """Refuse ``num_envs`` environments (and ``workers`` processes) per rank that cannot fit in
    the available memory, by the floors :data:`ENV_MEMORY_MB` and :data:`WORKER_MEMORY_MB`."""
    available = available_memory_mb() if available_mb is None else available_mb
    if available is None:
        return
    ranks = max(int(os.environ.get("LOCAL_WORLD_SIZE", "1")), 1)
    need = ranks * (num_envs * ENV_MEMORY_MB + max(workers, 0) * WORKER_MEMORY_MB)
    if need > available:
        fit = max(int((available / ranks - max(workers, 0) * WORKER_MEMORY_MB) / ENV_MEMORY_MB), 0)
        raise UsageError(
            f"--envs {num_envs} needs at least {need / 1024:.1f} GB of memory "
            f"({ENV_MEMORY_MB} MB per environment), but {available / 1024:.1f} GB is available; "
            f"use --envs {fit} or fewer"
        )


def check_out_dir(out_dir: str | Path) -> None:
    """Refuse an output folder that is a file, lies under a file or cannot be written to
    (tried by creating and deleting a file in the nearest existing folder)."""
    path = Path(out_dir)
    if path.exists() and not path.is_dir():
        raise UsageError(f"--out {path} is a file, not a folder")
    existing = path
    while not existing.exists():
        if existing.parent == existing:
            break
        existing = existing.parent
    if existing.exists() and not existing.is_dir():
        raise UsageError(f"--out {path} lies under {existing}, which is a file, not a folder")
    reason = unwritable(existing)
    if reason:
        raise UsageError(
            f"--out {path} is not writable: cannot create files in {existing} ({reason})"
        )


def holds_run(run_dir: Path) -> bool:
    """True if ``run_dir`` holds (part of) a devlearn run: a config, metrics or checkpoint."""
    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        return False
    return any((run_dir / n).exists() for n in RUN_FILES) or any(run_dir.glob("checkpoint_*.pt"))
