"""The real crib infant through the whole path: worker env, PPO iterations, evaluation video."""

from __future__ import annotations

import json

import pytest
import tiny_run

from devlearn.evaluation.evaluate import EvalRequest, Evaluation
from devlearn.training import train

pytest.importorskip("devlearn.infant")


@pytest.mark.slow
def test_tiny_behaviour_on_the_real_crib(tmp_path):
    cfg = tiny_run.config(tmp_path / "run", 64, num_envs=2, workers=1)
    result = train(cfg, tiny_run.registry(), progress=False)  # the real build_infant
    assert result.env_steps == 64
    row = json.loads((result.run_dir / "metrics.jsonl").read_text().splitlines()[-1])
    assert row["steps_per_s"] > 0 and row["stage"] == "fixed"
    video = tmp_path / "episode.mp4"
    summary = Evaluation(
        EvalRequest(
            "tiny",
            result.run_dir / "checkpoint_latest.pt",
            episodes=1,
            video=video,
            out_dir=tmp_path / "eval",
        ),
        tiny_run.registry(),
    ).run()
    assert summary["episodes"] == 1
    assert video.stat().st_size > 1000


@pytest.mark.slow
def test_the_real_crib_grows_in_a_worker(tmp_path):
    # issue #41: the real body rebuilt at a new age inside an env worker, its episode carried on
    cfg = tiny_run.config(tmp_path / "run", 64, "infant.growth=3,9", num_envs=2, workers=1)
    result = train(cfg, tiny_run.registry(), progress=False)
    rows = [
        json.loads(line) for line in (result.run_dir / "metrics.jsonl").read_text().splitlines()
    ]
    assert [r["age_months"] for r in rows] == [3.0, 3.0, 9.0, 9.0]  # 4 iterations of 16 steps
    summary = Evaluation(
        EvalRequest(
            "tiny",
            result.run_dir / "checkpoint_latest.pt",
            episodes=1,
            out_dir=tmp_path / "eval",
            overrides=["infant.age_months=0"],
        ),
        tiny_run.registry(),
        progress=False,
    ).run()
    assert summary["age_months"] == 0.0 and summary["episodes"] == 1
