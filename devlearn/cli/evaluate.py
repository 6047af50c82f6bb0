"""``devlearn eval BEHAVIOR --checkpoint PATH | --policy zero|random|held_random``: evaluate."""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from devlearn.api.errors import UsageError
from devlearn.api.json_files import read_json
from devlearn.cli.folders import removed_on_failure

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry


EPISODES_MAX = 1_000_000
"""Largest ``--episodes``."""
ENVS_MAX = 1024
"""Largest ``--envs`` and ``--workers``."""


EPISODE_SECONDS = 5.0
"""A behaviour's usual episode (BabyBench's 5 s), the unit :func:`paying_workers` counts."""
SESSION_MAX = 86_400.0
"""Longest ``--session``: a simulated day (seconds)."""


def _seconds(text: str, option: str, maximum: float) -> float:
    try:
        value = float(text)
    except ValueError:
        raise UsageError(f"{option} must be a number of seconds, got '{text}'") from None
    if not 0 < value <= maximum:
        raise UsageError(f"{option} must be above 0 and at most {maximum:g} seconds, got {text}")
    return value


def _count(text: str, option: str, minimum: int, maximum: int) -> int:
    try:
        value = int(text)
    except ValueError:
        raise UsageError(f"{option} must be an integer, got '{text}'") from None
    if value < minimum:
        raise UsageError(f"{option} must be at least {minimum}, got {value}")
    if value > maximum:
        raise UsageError(f"{option} must be at most {maximum}, got {value}")
    return value


BOOKKEEPING = {
    "episodes", "steps", "behavior", "policy", "checkpoint", "checkpoint_env_steps",
    "training_seed", "start", "protocol", "config", "written", "settle_steps", "execution",
    "episode_metrics",
}  # fmt: skip
"""Summary keys the human summary's header says in words (or leaves to --json)."""
MEAN_AT_BOUND_NOTED = 0.5
"""A mean action at the bounds in more than this share of components is called out (training's
``health/saturated`` warns past the same share)."""
SHOWN_MAX = 8
"""Further figures the human summary shows after the headline (the JSON has all)."""


def _figure(value: Any) -> str:
    return f"{value:.4g}" if isinstance(value, float) else json.dumps(value, default=float)


def human_summary(
    summary: dict, behavior_headline: str, baselines: dict[str, dict], json_path: Path | None
) -> list[str]:
    """A few lines for a reader: what was evaluated and how, the headline with its interval,
    the baselines' headline under the same start, the next few figures, where the JSON is."""
    from devlearn.evaluation.report import headline_of

    protocol = summary.get("protocol") or {}
    who = summary.get("checkpoint") or f"{summary.get('policy')} actions (baseline)"
    trained = summary.get("checkpoint_env_steps")
    learner = f" by {summary['learner']}" if summary.get("learner") else ""  # a scripted policy
    lines = [
        f"{summary.get('behavior')}: {who}"
        + (f" ({trained:,} training steps{learner})" if summary.get("checkpoint") else ""),
        f"  {protocol.get('episodes', summary.get('episodes'))} "
        + (f"sessions of {protocol['session_s']:g} s" if protocol.get("session_s") else "episodes")
        + " from "
        f"{summary.get('start')} starts, eval seed {protocol.get('seed')}, "
        f"{protocol.get('action', '')} action",
    ]
    head = headline_of(summary, behavior_headline)
    shown: set[str] = set()
    if head is not None:
        key, value, ci = head
        shown.add(key)
        band = f" [{ci[0]:.4g}, {ci[1]:.4g}] (95% interval over episodes)" if ci else ""
        lines.append(f"  headline  {key} = {value:.4g}{band}")
        same = {
            name: headline_of(other, behavior_headline)
            for name, other in baselines.items()
            if other.get("start") == summary.get("start")
        }
        beside = [f"{name} {h[1]:.4g}" for name, h in same.items() if h and h[0] == key]
        other = sorted(
            f"{name} ({b.get('start')})" for name, b in baselines.items() if name not in same
        )
        if beside:
            lines.append(f"  baselines {', '.join(beside)} (same start)")
        elif other:
            lines.append(
                f"  baselines none from {summary.get('start')} starts; other starts: "
                f"{', '.join(other)} (devlearn eval --policy P --start ...)"
            )
    criteria = summary.get("criteria")
    if isinstance(criteria, dict):  # the same measure under each criterion (hand regard's)
        found = {
            n: headline_of(c, behavior_headline) for n, c in criteria.items() if isinstance(c, dict)
        }
        beside = [f"{n} {h[1]:.4g}" for n, h in found.items() if h]
        if beside:
            lines.append(f"  criteria  {', '.join(beside)} (the headline's measure under each)")
    rest = [
        (k, v)
        for k, v in summary.items()
        if k not in BOOKKEEPING
        and k not in shown
        and not isinstance(v, (list, dict))
        and not k.endswith(("_std", "_ci_low", "_ci_high", "_boot_low", "_boot_high"))
    ]
    if rest:
        text = ", ".join(f"{k} {_figure(v)}" for k, v in rest[:SHOWN_MAX])
        more = f" (+{len(rest) - SHOWN_MAX} more)" if len(rest) > SHOWN_MAX else ""
        lines.append(f"  also      {text}{more}")
    bound = (summary.get("policy_figures") or {}).get("mean_at_bound")
    if bound is not None:  # a network's mean at the action bounds (issue #54)
        lines.append(
            f"  policy    mean action at the bounds in {bound:.0%} of components"
            + (
                ": the mean plays the bounds; compare --action sample"
                if bound > MEAN_AT_BOUND_NOTED
                else ""
            )
        )
    still = (summary.get("policy_figures") or {}).get("ends_still")
    if still:
        from devlearn.evaluation.episodes import STILL_SPEED, STILL_WINDOW_S

        # a deterministic policy held in a posture it never leaves (issue #54)
        lines.append(
            f"  policy    {still:.0%} of episodes end with the body still (joints under "
            f"{STILL_SPEED} a second over the last {STILL_WINDOW_S:g} s): "
            + (
                "a goal held, or a posture the mean action never leaves (a stall that "
                "sampled actions' noise moves out of); compare --action sample"
                if (summary.get("protocol") or {}).get("action", "mean") != "sample"
                else "the policy rests"
            )
        )
    if json_path is not None:
        lines.append(f"  all figures: {json_path} (devlearn eval ... --json prints them)")
    return lines


def _baselines(behavior: str, compare: list[str]) -> dict[str, dict]:
    """Baseline evaluations to show beside a checkpoint's: ``--compare`` folders, else the
    folders a run's summary names (``eval_BEHAVIOR_zero``, ``eval_BEHAVIOR_random``)."""
    folders = [Path(c) for c in compare] or [
        Path(f"eval_{behavior}_{policy}") for policy in ("zero", "random", "held_random")
    ]
    found = {}
    for folder in folders:
        path = folder / "eval.json" if folder.is_dir() else folder
        try:
            data = read_json(path)
        except UsageError as err:
            if compare:
                raise UsageError(
                    f"--compare {folder}: no readable eval.json there ({err})"
                ) from None
            continue
        if isinstance(data, dict) and data.get("behavior") == behavior:
            name = str(data.get("policy") or folder)
            found[name if name not in found else str(folder)] = data
    return found


def _print(summary: dict, as_json: bool, lines: list[str] | None = None) -> None:
    if as_json:
        print(json.dumps(summary, indent=2, default=float))
        return
    print("\n".join(lines or []))


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Evaluate and print the summary (a table, or JSON with --json), then where files went.

    The summary is printed even when writing the files failed (then exit code 2).
    """
    from devlearn.evaluation.evaluate import (
        PARALLEL_MIN_EPISODES,
        EvalRequest,
        Evaluation,
        EvalWriteError,
        default_out_dir,
        paying_workers,
        resolve_checkpoint,
    )

    registry.behavior(args.behavior)  # unknown behaviour: one clear line
    from devlearn.config.checks import SEED_MAX

    episodes = _count(args.episodes, "--episodes", 1, EPISODES_MAX)
    seed = _count(args.seed, "--seed", 0, SEED_MAX)
    envs = None if args.envs is None else _count(args.envs, "--envs", 1, ENVS_MAX)
    workers = None if args.workers is None else _count(args.workers, "--workers", 0, ENVS_MAX)
    session = None if args.session is None else _seconds(args.session, "--session", SESSION_MAX)
    # a session repays a worker's start-up as the 5 s episodes it lasts would
    lengths = 1 if session is None else max(1, round(session / EPISODE_SECONDS))
    if workers and paying_workers(episodes * lengths, workers) < workers:
        kept = paying_workers(episodes * lengths, workers)
        print(
            f"note: --workers {workers} for {episodes} episodes: "
            + (f"{kept} workers" if kept else "played in this process")
            + f" (a worker repays its start-up from {PARALLEL_MIN_EPISODES} episodes on)",
            file=sys.stderr,
        )
        workers = kept
    checkpoint = resolve_checkpoint(args.checkpoint) if args.checkpoint else None
    request = EvalRequest(  # checked before any folder is made
        behavior=args.behavior,
        checkpoint=checkpoint,
        policy=args.policy or "checkpoint",
        episodes=episodes,
        seed=seed,
        start=args.start,
        action=args.action,
        overrides=tuple(args.overrides),
        envs=envs,
        workers=workers,
        session=session,
        video=args.video,
    )
    out_dir = Path(args.out) if args.out else default_out_dir(request)
    request = dataclasses.replace(request, out_dir=out_dir)
    headline = registry.behavior(args.behavior).about.headline_metric
    baselines = _baselines(args.behavior, args.compare) if not args.json else {}

    def human(summary: dict, json_path: Path | None) -> list[str]:
        return human_summary(summary, headline, baselines, json_path)

    try:
        with removed_on_failure(out_dir):
            summary = Evaluation(request, registry).run()
    except EvalWriteError as exc:
        _print(exc.summary, args.json, human(exc.summary, None))
        raise
    written = summary.pop("written", [])
    summary.pop("episode_metrics", None)  # not part of eval.json
    _print(summary, args.json, human(summary, out_dir / "eval.json"))
    files = ", ".join(Path(p).name for p in written)
    # stderr with --json, so that stdout stays one JSON document
    print(
        f"written to {out_dir}: {files}" + (f"; video {args.video}" if args.video else ""),
        file=sys.stderr if args.json else sys.stdout,
    )
    return 0
