"""Real runs: both terms train and resume, on a tiny fake body and on hand regard."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from devlearn_curiosity import RND, ForwardModel

from devlearn.testing import (
    TinyBehavior,
    fake_infant_factory,
    load_checkpoint,
    registry_for,
    run_command,
    run_config,
    train,
)


def rows(run_dir: Path) -> list[dict]:
    return [json.loads(line) for line in (run_dir / "metrics.jsonl").read_text().splitlines()]


@pytest.mark.slow  # about 20 s: worker processes start
def test_both_terms_train_and_resume_with_worker_processes(tmp_path):
    registry = registry_for(TinyBehavior, learned_rewards=(RND, ForwardModel))
    out = tmp_path / "run"
    sets = ["curiosity=rnd,forward_model", "behavior.use_eyes=true", "learned.rnd.weight=0.5"]

    def run(steps: int, workers: int, resume: Path | None = None):
        cfg = run_config(
            TinyBehavior,
            sets,
            out_dir=str(out),
            total_steps=steps,
            num_envs=4,
            workers=workers,
            save_interval=1,
        )
        return train(
            cfg, registry, resume=resume, infant_factory=fake_infant_factory, progress=False
        )

    run(64, workers=0)
    first = load_checkpoint(out / "checkpoint_latest.pt")["learned"]
    assert {name: state["updates"] for name, state in first.items()} == {
        "rnd": 2,
        "forward_model": 2,
    }
    result = run(128, workers=2, resume=out)  # the models live in the learner, not the workers
    assert result.env_steps == 128
    lines = rows(out)
    assert [r["step"] for r in lines] == [32, 64, 96, 128]
    for row in lines:
        assert row["reward/rnd/weight"] == 0.5 and row["reward/forward_model/weight"] == 0.1
        assert row["reward/rnd/raw"] > 0 and row["reward/forward_model/loss"] > 0
    state = load_checkpoint(out / "checkpoint_latest.pt")["learned"]
    assert {name: s["updates"] for name, s in state.items()} == {"rnd": 4, "forward_model": 4}
    predictor = "predictor.0.weight"
    assert not (
        state["forward_model"]["model"][predictor] == first["forward_model"]["model"][predictor]
    ).all()
    config = json.loads((out / "config.json").read_text())
    assert config["learned"]["forward_model"]["observations"] == []  # default: the images


def _detector_file(path: Path) -> None:
    """A plausible fixed hand detector (the pink mittens' hue), so no babbling is needed:
    these runs test that curiosity trains and resumes, not what the detector sees."""
    from devlearn_hand_regard.detector import DetectorParams

    centre = [[[20.0, 44.0], [44.0, 44.0]], [[20.0, 44.0], [44.0, 44.0]]]
    DetectorParams([[136, 60, 40, 140, 255, 255]], 4.0, 2000.0, 60.0, centre).save(path)


@pytest.mark.slow
@pytest.mark.parametrize("term", ["forward_model", "rnd"])
def test_hand_regard_trains_and_resumes_with_curiosity(tmp_path, term):
    pytest.importorskip("devlearn_hand_regard")
    out = tmp_path / "run"
    out.mkdir()
    _detector_file(out / "hand_detector.json")
    base = ["run", "hand_regard", "--envs", "2", "--workers", "0"]
    sets = [
        "--set",
        f"curiosity={term}",
        "--set",
        "env.action_repeat=1",  # iterations of 16 physics steps, as the test counts
        "--set",
        "ppo.num_steps_per_env=8",
        "--set",
        "ppo.num_mini_batches=1",
        "--set",
        "ppo.num_learning_epochs=1",
    ]
    # as a user runs them (a new process each): a run, then its resume
    for args in (
        ["--steps", "16", "--out", str(out), *sets],
        ["--steps", "32", "--resume", str(out)],
    ):
        done = run_command(*base, *args)
        assert done.code == 0, done.err
    lines = rows(out)
    assert [r["step"] for r in lines] == [16, 32]
    assert all(r[f"reward/{term}/raw"] > 0 for r in lines)
    state = load_checkpoint(out / "checkpoint_latest.pt")
    assert state["learned"][term]["updates"] == 2
    config = json.loads((out / "config.json").read_text())
    assert config["curiosity"] == [term]
