"""The real crib infant through the whole path: worker env, PPO iterations, evaluation video."""

from __future__ import annotations

import json

import pytest
import tiny_run

from devlearn.evaluation.evaluate import evaluate
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
    summary = evaluate(
        "tiny",
        result.run_dir / "checkpoint_latest.pt",
        1,
        tiny_run.registry(),
        video=video,
        out_dir=tmp_path / "eval",
    )
    assert summary["episodes"] == 1
    assert video.stat().st_size > 1000
