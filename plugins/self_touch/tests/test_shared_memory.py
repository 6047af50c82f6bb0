"""Lifetime memory as one agent's: a discovery pays its first-ever bonus once per run (#20)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch
from devlearn_self_touch import SelfTouch, SelfTouchConfig
from devlearn_self_touch.rewards import ContactNovelty, TouchNovelty
from self_touch_fakes import SwappingInfant, make_ctx, train_swapping

from devlearn import BatchContext
from devlearn.testing import (
    Play,
    load_checkpoint,
    load_saved_config,
    registry_for,
    run_config,
    train,
)

GROUPS = np.zeros(68, bool)
GROUPS[:10] = True  # SwappingInfant's env 0 discovers regions 0-4, env 1 regions 5-9


def _pay(term, contexts) -> list[float]:
    term.bind(len(contexts))
    return np.asarray(term(BatchContext(contexts))).tolist()


@pytest.mark.parametrize(
    "memory, touch, contact",
    [("shared", [5.0, 1.0], [10.0, 2.0]), ("per_env", [5.0, 5.0], [10.0, 10.0])],
)
def test_two_envs_one_discovery_one_first_ever_bonus(memory, touch, contact):
    """Both envs touch region 3 with the left hand on the same step: shared memory pays the
    first env first-ever and the second what a known region pays (first in episode)."""
    step = [make_ctx(touched=[3], hand_contacts=[(0, 3)]) for _ in range(2)]
    assert _pay(TouchNovelty(lifetime_memory=memory), step) == touch
    assert _pay(ContactNovelty(lifetime_memory=memory), step) == contact


def test_unknown_lifetime_memory_names_the_valid_ones():
    with pytest.raises(ValueError, match="lifetime_memory 'global'; valid: shared, per_env"):
        SelfTouchConfig(lifetime_memory="global")
    with pytest.raises(ValueError, match="valid: shared, per_env"):
        TouchNovelty(lifetime_memory="run")


def _episode_sums(*batches: Play, term: str) -> list[float]:
    """Play every batch through one episode; return each env's ``reward/<term>`` sum."""
    infos = []
    for batch in batches:
        for steps in batch.play(SwappingInfant.episode_steps):
            infos += [info for *_, info in steps if info is not None]
    return [info[f"reward/{term}"] for info in infos]


def _batch(memory: str, seeds: list[int]) -> Play:
    behavior = SelfTouch(SelfTouchConfig(lifetime_memory=memory))
    batch = Play(behavior, seeds=seeds, infant_factory=SwappingInfant)
    batch.reset()
    return batch


@pytest.mark.parametrize("memory, second", [("shared", 5.0), ("per_env", 25.0)])
def test_in_process_envs_share_their_discoveries(memory, second):
    """Episode 1: each env discovers 5 regions (5 x 5.0); episode 2: each touches the other's
    regions, known to the run (5 x 1.0), or only to the other env (per_env: 5 x 5.0)."""
    batch = _batch(memory, [0, 1])
    try:
        assert _episode_sums(batch, term="touch_novelty") == [25.0, 25.0]
        batch.sync_run_memory()  # nothing to merge in one batch: no change
        assert _episode_sums(batch, term="touch_novelty") == [second, second]
    finally:
        batch.close()


def test_two_workers_merge_their_memories_at_the_iteration_boundary():
    """One env per worker: before the merge each worker knows its own discoveries only; after
    the merge at the runner's iteration boundary (``Play.sync_run_memory``) both know both."""
    first, second = _batch("shared", [0]), _batch("shared", [1])
    try:
        assert _episode_sums(first, second, term="contact_novelty") == [50.0, 50.0]
        envs = [*first.state(), *second.state()]  # 5 pairs x 10.0 each, above
        assert [e["terms"]["touch_novelty"]["ever"].sum() for e in envs] == [5, 5]
        first.sync_run_memory(second)
        for env in [*first.state(), *second.state()]:
            assert np.array_equal(env["terms"]["touch_novelty"]["ever"], GROUPS)
        assert _episode_sums(first, second, term="contact_novelty") == [10.0, 10.0]  # known
    finally:
        first.close()
        second.close()


def test_shared_memory_survives_resume_with_another_worker_count(tmp_path):
    """Train one iteration (= one episode per env) on 2 workers; the checkpoint holds the
    merged memory in every env; resumed on 1 worker and in process, the second episode pays
    the other env's discoveries as known (5 x 1.0), not as new (5 x 5.0)."""
    registry = registry_for(SelfTouch)
    out = tmp_path / "run"
    train_swapping(out, ["save_interval=1"])
    state = load_checkpoint(out / "checkpoint_latest.pt")
    for env in state["env"]["ranks"][0]["envs"]:
        assert np.array_equal(env["terms"]["touch_novelty"]["ever"], GROUPS)
    for workers in (1, 0):
        copy = tmp_path / f"resumed_{workers}"
        copy.mkdir()
        for path in out.iterdir():
            if path.is_file():
                (copy / path.name).write_bytes(path.read_bytes())
        cfg = load_saved_config(copy, registry)
        cfg.workers, cfg.total_steps = workers, 80
        train(cfg, registry, resume=copy, infant_factory=SwappingInfant, progress=False)
        last = json.loads((copy / "metrics.jsonl").read_text().splitlines()[-1])
        assert last["step"] == 80
        assert (last["reward/touch_novelty"], last["reward/contact_novelty"]) == (5.0, 10.0)


def test_same_seed_and_worker_count_same_numbers(tmp_path):
    """Shared memory merged across 2 workers adds nothing random: two runs are identical."""
    registry = registry_for(SelfTouch)
    overrides = [
        "env.action_repeat=1",
        "ppo.num_steps_per_env=20",
        "ppo.num_mini_batches=2",
        "torch_threads=1",
    ]
    drop = {"steps_per_s", "collect_s", "update_s"}  # wall-clock timings
    runs = []
    for name in ("a", "b"):
        cfg = run_config(SelfTouch, overrides, out_dir=str(tmp_path / name), workers=2)
        cfg.num_envs, cfg.total_steps = 2, 80
        train(cfg, registry, infant_factory=SwappingInfant, progress=False)
        lines = (tmp_path / name / "metrics.jsonl").read_text().splitlines()
        state = load_checkpoint(tmp_path / name / "checkpoint_latest.pt")
        runs.append(
            ([{k: v for k, v in json.loads(r).items() if k not in drop} for r in lines], state)
        )
    (rows_a, a), (rows_b, b) = runs
    assert rows_a == rows_b
    assert rows_a[-1]["reward/touch_novelty"] == 15.0  # mean of 25 (new) and 5 (known)
    for key in a["actor_state_dict"]:
        torch.testing.assert_close(a["actor_state_dict"][key], b["actor_state_dict"][key])
