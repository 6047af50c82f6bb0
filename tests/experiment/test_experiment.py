"""Experiments as data: a file run, restarted, published and tabulated with the tiny behaviour
(the sweep tests' launcher, tests/sweep/tiny_devlearn.py); bad files refused before anything is
made; the SB3 learner's plan; the real experiment files still check."""

from __future__ import annotations

import contextlib
import io
import json
import os
import stat
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "sweep"))

import tiny_devlearn  # noqa: E402

from devlearn.cli import main  # noqa: E402
from devlearn.experiment.publish import CURVE_ROWS, median_seed, thin_curve  # noqa: E402
from devlearn.sweep.progress import Progress  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
LAUNCHER = json.dumps([sys.executable, tiny_devlearn.__file__])
TINY = f"""\
name = "tiny_targets"
behavior = "tiny"
description = "Two targets of the tiny behaviour."
seeds = [1, 2]
baselines = ["zero"]

[train]
steps = 64
envs = 2
workers = 0
torch_threads = 1
set = {{ save_interval = 1 }}

[[arms]]
name = "near"
set = {{ "behavior.target" = 0.1 }}

[[arms]]
name = "far"
set = ["behavior.target=0.3"]

[[protocols]]
name = "rest2"
episodes = 2
seed = 0

[[references]]
source = "a made-up table, row 3"
rows = [{{ label = "near (paper)", value = 0.5, low = 0.4, high = 0.6 }}]

[executor]
launcher = {LAUNCHER}
"""
ARMS = ("near", "far")
HEADLINE = "episode_close_mean"
"""tiny's headline as devlearn eval's summary names it: the per-episode mean of ``close``."""
SEEDS = (1, 2)


def run_cli(argv: list[str]) -> tuple[int, str, str]:
    """``devlearn ...`` in this process with the tiny behaviours; (exit code, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with pytest.MonkeyPatch.context() as patch:
        tiny_devlearn.install(patch)
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = main(argv)
    return code, out.getvalue(), err.getvalue()


def attempts(out: Path) -> dict[str, list[str]]:
    """Every run's commands so far, by phase."""
    found = {}
    for path in sorted((out / "records").glob("*.json")):
        record = json.loads(path.read_text())
        found[record["name"]] = [a["phase"] for a in record["attempts"]]
    return found


def t_interval(values: list[float]) -> tuple[float, float, float]:
    """Mean and 95% t-interval, computed here (not by devlearn's mean_ci)."""
    x = np.asarray(values, dtype=float)
    mean = float(x.mean())
    if x.std(ddof=1) == 0:
        return mean, mean, mean
    half = stats.t.ppf(0.975, len(x) - 1) * x.std(ddof=1) / np.sqrt(len(x))
    return mean, mean - half, mean + half


@pytest.mark.slow
def test_an_experiment_runs_restarts_publishes_and_tabulates(tmp_path):
    file, out, dest = tmp_path / "tiny.toml", tmp_path / "out", tmp_path / "published"
    file.write_text(TINY)
    code, stdout, stderr = run_cli(["experiment", "run", str(file), str(out), "--jobs", "2"])
    assert code == 0, stdout + stderr
    names = ["baseline_zero", *[f"{arm},seed={s}" for s in SEEDS for arm in ARMS]]
    assert attempts(out) == {
        n: ["eval"] if n.startswith("baseline") else ["train", "eval"] for n in names
    }
    info = json.loads((out / "experiment.json").read_text())
    head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True)
    assert info["commit"]["commit"] == head.stdout.strip()
    assert (out / "experiment.toml").read_text() == TINY
    for name in names:  # the arms trained with their own settings, evaluated under the protocol
        summary = json.loads((out / "runs" / name / "eval_rest2" / "eval.json").read_text())
        assert summary["episodes"] == 2 and summary["protocol"]["seed"] == 0
        if not name.startswith("baseline"):
            config = json.loads((out / "runs" / name / "config.json").read_text())
            assert config["behavior"]["target"] == (0.1 if name.startswith("near") else 0.3)
            assert config["total_steps"] == 64 and config["seed"] == int(name[-1])

    # Started again: every finished step is skipped; a lost evaluation alone is redone
    code, stdout, _ = run_cli(["experiment", "run", str(file), str(out)])
    assert code == 0 and all(f"done        {n}  (earlier)" in stdout for n in names), stdout
    before = attempts(out)
    eval_json = out / "runs" / "far,seed=2" / "eval_rest2" / "eval.json"
    kept = eval_json.read_text()
    eval_json.unlink()
    code, stdout, _ = run_cli(["experiment", "run", str(file), str(out)])
    assert code == 0, stdout
    after = attempts(out)
    assert after == {**before, "far,seed=2": [*before["far,seed=2"], "eval"]}
    assert json.loads(eval_json.read_text())[HEADLINE] == json.loads(kept)[HEADLINE]

    code, stdout, stderr = run_cli(["experiment", "publish", str(out), str(dest)])
    assert code == 0, stderr
    evaluations = {}
    for name in names:
        arm, _, seed = name.partition(",")
        published = dest / arm / seed / "eval_rest2" / "eval.json"
        assert (
            published.read_bytes()
            == (out / "runs" / name / "eval_rest2" / "eval.json").read_bytes()
        )
        evaluations[name] = json.loads(published.read_text())
        if arm in ARMS:
            assert (dest / arm / seed / "config.json").is_file()
            learning = json.loads((dest / arm / seed / "learning.json").read_text())
            rows = [
                json.loads(x)
                for x in (out / "runs" / name / "metrics.jsonl").read_text().splitlines()
            ]
            assert learning["env_steps"] == 64
            assert learning["learn_s"] == pytest.approx(
                sum(r["collect_s"] + r["update_s"] for r in rows)
            )
            curve = [
                json.loads(x) for x in (dest / arm / seed / "curve.jsonl").read_text().splitlines()
            ]
            assert curve[-1]["step"] == rows[-1]["step"] and f"metrics/{HEADLINE}" in curve[-1]
    assert (dest / "experiment.toml").read_text() == TINY
    published_info = json.loads((dest / "experiment.json").read_text())
    assert published_info["commit"] == head.stdout.strip() and published_info["missing"] == []
    assert not list(dest.rglob("checkpoint_*.pt")) and not list(dest.rglob("metrics.jsonl"))
    for arm in ARMS:
        values = {s: evaluations[f"{arm},seed={s}"][HEADLINE] for s in SEEDS}
        chosen = published_info["policies"][arm]
        assert chosen["seed"] == sorted(SEEDS, key=lambda s: (values[s], s))[0]  # lower median
        assert (dest / arm / "policy.pt").is_file()

    code, text, stderr = run_cli(["experiment", "table", str(dest), "--json"])
    assert code == 0, stderr
    (table,) = json.loads(text)["protocols"]
    assert table["headline"] == HEADLINE
    for row, arm in zip(table["arms"], ARMS):
        values = [evaluations[f"{arm},seed={s}"][HEADLINE] for s in SEEDS]
        mean, low, high = t_interval(values)
        assert row["arm"] == arm and row["n"] == 2
        assert row["seeds"] == {str(s): v for s, v in zip(SEEDS, values)}
        assert (row["mean"], row["ci_low"], row["ci_high"]) == pytest.approx((mean, low, high))
    zero = evaluations["baseline_zero"]
    assert table["baselines"] == [
        {
            "baseline": "zero",
            "value": zero[HEADLINE],
            "ci_low": zero[HEADLINE.replace("_mean", "_ci_low")],  # its interval over episodes
            "ci_high": zero[HEADLINE.replace("_mean", "_ci_high")],
        }
    ]
    assert table["references"][0]["source"] == "a made-up table, row 3"

    code, text, _ = run_cli(["experiment", "table", str(dest), "--out", str(tmp_path / "t.md")])
    assert code == 0 and (tmp_path / "t.md").read_text() == text
    rows = {line.split("|")[1].strip(): line for line in text.splitlines() if line.startswith("| ")}
    for arm, row in zip(ARMS, table["arms"]):
        interval = f"{row['mean']:.4g} [{row['ci_low']:.4g}, {row['ci_high']:.4g}]"
        assert interval in rows[arm], rows[arm]
    assert f"{zero[HEADLINE]:.4g}" in rows["zero actions (baseline)"]
    assert "0.5 [0.4, 0.6]" in rows["near (paper) (reference [1])"]
    assert "- [1] a made-up table, row 3" in text
    fifo = tmp_path / "t.fifo"  # refused before the table is made, and left a FIFO
    os.mkfifo(fifo)
    code, text, stderr = run_cli(["experiment", "table", str(dest), "--out", str(fifo)])
    assert code == 2 and text == "" and f"cannot write {fifo}: it is a FIFO" in stderr
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    fifo.unlink()


@pytest.fixture
def cli(monkeypatch):
    tiny_devlearn.install(monkeypatch)
    return main


ARM_X = '[[arms]]\nname = "x"\n'
BAD = [
    (
        'name = "tiny_targets"',
        "sed = 3",
        "the top level: unknown key 'sed'; valid: arms, baseline_set, baselines",
    ),
    (
        'baselines = ["zero"]',
        'baselines = ["zeros"]',
        "baselines: unknown value 'zeros'; valid: zero,",
    ),
    ("steps = 64", "steps = 1.5", "[train] steps: must be an integer from 1 to"),
    (
        "[[protocols]]",
        '[[arms]]\nname = "near"\n[[protocols]]',
        "arms: the name 'near' is given twice",
    ),
    (
        "[[protocols]]",
        ARM_X + 'lerner = "sb3_ppo"\n[[protocols]]',
        "arms[2]: unknown key 'lerner'; valid: learner,",
    ),
    (
        "[[protocols]]",
        ARM_X + 'learner = "sb4"\n[[protocols]]',
        "arms 'x' learner: unknown value 'sb4'; valid: devlearn,",
    ),
    (
        "[[protocols]]",
        ARM_X + 'preset = "paper"\nlearner = "sb3_ppo"\n[[protocols]]',
        "arms 'x' preset: a preset is devlearn's",
    ),
    (
        "[[protocols]]",
        ARM_X + 'set = ["behavior.targt=0.2"]\n[[protocols]]',
        "run x,seed=1: unknown config key 'behavior.targt'",
    ),
    ("[[protocols]]", ARM_X + 'set = ["ppo.gamma=2"]\n[[protocols]]', "run x,seed=1: ppo.gamma"),
    (
        "seed = 0",
        'seed = 0\nstart = "randm"',
        "protocols 'rest2' start: unknown value 'randm'; valid: stage,",
    ),
    (
        "seed = 0",
        'seed = 0\nset = ["behavior.target=0.2"]',
        "protocols 'rest2': --set applies to baselines only",
    ),
    ("seed = 0", "seed = 0\nsession_s = -5", "protocols 'rest2' session_s: must be above 0"),
    (
        "seed = 0",
        "seed = 0\nsession_s = 0.0125",
        "protocols 'rest2' session_s: 0.0125 s is not a whole number of physics steps",
    ),
    (
        'set = ["behavior.target=0.3"]\n\n[[protocols]]\nname = "rest2"\n',
        'set = ["behavior.target=0.3", "env.action_repeat=4"]\n\n[[protocols]]\n'
        'name = "rest2"\nsession_s = 0.01\n',
        "protocols 'rest2' session_s 0.01 for run far,seed=1: env.action_repeat=4 must divide "
        "the episode (2 physics steps)",
    ),
    (
        'source = "a',
        'protocol = "q"\nsource = "a',
        "references[0] protocol: unknown protocol 'q'; valid: rest2",
    ),
]
"""(text of the tiny experiment file, what replaces it, what the one-line error says)."""


@pytest.mark.parametrize("old,new,message", BAD, ids=[m.split(":")[0] for *_, m in BAD])
def test_a_bad_file_is_refused_in_one_line_and_nothing_is_made(
    cli, refused, tmp_path, old, new, message
):
    assert old in TINY
    file, out = tmp_path / "bad.toml", tmp_path / "out"
    file.write_text(TINY.replace(old, new, 1))
    for extra in ([], ["--dry-run"]):
        error = refused(cli, "experiment", "run", str(file), str(out), *extra)
        assert message in error, error
        assert not out.exists()


def test_a_dry_run_lists_every_run_and_its_evaluations_and_starts_nothing(cli, capsys, tmp_path):
    pytest.importorskip("stable_baselines3")
    file, out = tmp_path / "tiny.toml", tmp_path / "out"
    file.write_text(
        TINY.replace(
            "[[protocols]]", '[[arms]]\nname = "sb3"\nlearner = "sb3_ppo"\n\n[[protocols]]'
        )
    )
    assert cli(["experiment", "run", str(file), str(out), "--dry-run"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert not out.exists()
    assert lines[-1].startswith("6 runs (3 arms x 2 seeds), 1 baseline(s), 7 evaluations in")
    starts = [line.split(":")[0] for line in lines if not line.startswith(" ")]
    assert starts[:4] == ["baseline_zero", "near,seed=1", "far,seed=1", "sb3,seed=1"]
    sb3 = next(line for line in lines if line.startswith("sb3,seed=2:"))
    assert "examples/sb3/train.py --algo ppo --behavior tiny --steps 64 --seed 2 --envs 2" in sb3
    assert "--threads 1" in sb3 and "--set save_interval=1" in sb3
    evaluation = lines[lines.index(sb3) + 1]
    assert "sb3,seed=2/policy.pt" in evaluation and "--action mean" in evaluation
    # a scripted policy cannot sample: refused before anything starts
    file.write_text(file.read_text().replace('name = "rest2"', 'name = "rest2"\naction = "sample"'))
    assert cli(["experiment", "run", str(file), str(out), "--dry-run"]) == 2
    assert "action 'sample' needs a devlearn checkpoint; arm 'sb3'" in capsys.readouterr().err


def test_a_session_protocol_evaluates_whole_sessions(cli, capsys, tmp_path):
    # issue #57: whole sessions without a reset inside, as devlearn eval --session plays them
    from devlearn.experiment.spec import read_experiment

    file, out = tmp_path / "tiny.toml", tmp_path / "out"
    session = '[[protocols]]\nname = "sessions"\nstart = "rest"\nepisodes = 3\nsession_s = 300\n'
    file.write_text(TINY.replace("[[references]]", session + "\n[[references]]"))
    assert cli(["experiment", "run", str(file), str(out), "--dry-run"]) == 0
    lines = capsys.readouterr().out.splitlines()
    sessions = [line for line in lines if "eval_sessions:" in line]
    assert len(sessions) == 5  # the baseline and 2 arms x 2 seeds
    assert all("--episodes 3 --seed 0 --start rest" in line for line in sessions)
    assert all(line.endswith("--session 300") for line in sessions), sessions[0]
    assert not any("--session" in line for line in lines if "eval_rest2:" in line)
    spec = read_experiment(file)
    assert spec.protocols[1].what()["session_s"] == 300.0
    assert "session_s" not in spec.protocols[0].what()  # folders started before the key match
    assert spec.protocols[1].describe().startswith("3 sessions of 300 s from rest starts")


def test_baseline_set_goes_to_every_baseline_evaluation_only(cli, capsys, tmp_path):
    # hand regard's baselines scored by the arms' shared detector (issue #56)
    from devlearn.experiment.spec import read_experiment

    file, out = tmp_path / "tiny.toml", tmp_path / "out"
    file.write_text(
        TINY.replace(
            'baselines = ["zero"]', 'baselines = ["zero"]\nbaseline_set = ["behavior.target=0.2"]'
        )
    )
    assert cli(["experiment", "run", str(file), str(out), "--dry-run"]) == 0
    lines = capsys.readouterr().out.splitlines()
    evaluations = [line for line in lines if "eval_rest2:" in line]
    baseline = [line for line in evaluations if "--policy zero" in line]
    assert len(baseline) == 1 and baseline[0].endswith("--set behavior.target=0.2")
    assert len(evaluations) == 5
    assert not any("behavior.target" in line for line in evaluations if line not in baseline)
    assert read_experiment(file).what()["baseline_set"] == ["behavior.target=0.2"]
    file.write_text(TINY)  # folders started before the key match
    assert "baseline_set" not in read_experiment(file).what()
    # checked like any --set item, before anything starts
    file.write_text(
        TINY.replace(
            'baselines = ["zero"]', 'baselines = ["zero"]\nbaseline_set = ["behavior.targt=0.2"]'
        )
    )
    assert cli(["experiment", "run", str(file), str(out), "--dry-run"]) == 2
    assert "behavior.targt" in capsys.readouterr().err and not out.exists()


@pytest.mark.slow
def test_the_learners_experiment_file_checks_with_the_real_behaviour(tmp_path, capsys):
    """experiments/learners.toml (issue #45's comparison) resolves through the config pipeline
    with self_touch installed: a dry run lists its 10 runs and 2 baselines."""
    pytest.importorskip("stable_baselines3")
    assert (
        main(
            [
                "experiment",
                "run",
                str(ROOT / "experiments" / "learners.toml"),
                str(tmp_path / "o"),
                "--dry-run",
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert "10 runs (2 arms x 5 seeds), 2 baseline(s), 12 evaluations" in out
    assert "--steps 2048000" in out and "--episodes 100 --seed 0" in out
    assert not (tmp_path / "o").exists()


def test_published_curves_are_thinned_and_the_policy_seed_is_the_median():
    rows = [
        {"step": i, "mean_reward": 0.0, "metrics/episode_close_mean": 0.5, "loss/value": 1.0}
        for i in range(1, 501)
    ]
    curve = thin_curve(rows, "close")
    assert len(curve) <= CURVE_ROWS + 1 and curve[-1]["step"] == 500
    assert set(curve[0]) == {"step", "mean_reward", "metrics/episode_close_mean"}
    assert median_seed({1: 0.3, 2: 0.1, 3: 0.2}) == 3
    assert median_seed({1: 0.3, 2: 0.1, 3: 0.2, 4: 0.4}) == 3  # the lower middle one
    assert median_seed({5: 0.2, 4: 0.2, 3: 0.2}) == 4


def test_progress_estimates_the_time_left_from_this_starts_rate():
    progress = Progress(3, "close", io.StringIO())
    try:
        progress.started = time.monotonic() - 10.0
        progress.first_step.update(a=1000, b=0)  # a resumed at 1,000 steps
        progress.step.update(a=3000, b=1000)  # 3,000 steps trained in 10 s: 300 steps/s
        progress.ended.add("b")
        left = (4000 - 3000) + 6000  # a's rest and c's whole budget; b ended
        assert progress.eta({"a": 4000, "b": 4000, "c": 6000}) == pytest.approx(
            left / 300, rel=0.05
        )
        assert Progress(1, None, io.StringIO()).eta({"a": 10}) is None  # no rate yet
    finally:
        progress.close()


def test_an_arm_with_its_own_budget_restarts_to_that_budget(tmp_path):
    # an arm that sets total_steps (issue #54's equal-seconds arm) trains, and resumes, to its
    # own budget, not the file's [train] steps
    from devlearn.experiment.plan import plan_experiment
    from devlearn.experiment.spec import read_experiment

    file = tmp_path / "tiny.toml"
    file.write_text(TINY.replace('set = ["behavior.target=0.3"]', 'set = ["total_steps=32"]'))
    with pytest.MonkeyPatch.context() as patch:
        tiny_devlearn.install(patch)
        import devlearn.plugins

        plan = plan_experiment(
            read_experiment(file), tmp_path / "out", devlearn.plugins.PluginRegistry()
        )
    budgets = {run.job.name: (run.total_steps, run.job.resume_args) for run in plan.runs}
    for seed in SEEDS:
        assert budgets[f"far,seed={seed}"] == (32, ["--workers", "0", "--steps", "32"])
        assert budgets[f"near,seed={seed}"] == (64, ["--workers", "0", "--steps", "64"])
