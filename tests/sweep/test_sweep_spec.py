"""Sweep specs: grid, seeds and files parse; bad input is one line, exit 2, nothing started."""

from __future__ import annotations

import sys

import pytest
import tiny_devlearn

from devlearn.api.errors import UsageError
from devlearn.cli import main
from devlearn.cores import available_cores
from devlearn.sweep import build_spec, plan_sweep, variants
from devlearn.sweep.bookkeeping import SweepFolder
from devlearn.sweep.executors import LocalExecutor
from devlearn.sweep.spec import parse_grid, parse_seeds


@pytest.fixture
def cli(monkeypatch):
    tiny_devlearn.install(monkeypatch)
    return main


def test_seeds_and_grid_parse():
    assert parse_seeds("1,2,3") == [1, 2, 3]
    assert parse_seeds("1-3,7") == [1, 2, 3, 7]
    assert parse_grid(["behavior.curriculum=fixed_only, two_stage", "ppo.gamma=0.9"]) == {
        "behavior.curriculum": ["fixed_only", "two_stage"],
        "ppo.gamma": ["0.9"],
    }
    for bad in ("1,x", "3-1", "", "1,,2", "-1"):
        with pytest.raises(UsageError, match="--seeds must be"):
            parse_seeds(bad)
    with pytest.raises(UsageError, match="lists a seed twice"):
        parse_seeds("1,1")


def test_variants_are_named_by_their_values_seeds_outermost():
    grid = {"behavior.curriculum": ["fixed_only", "two_stage"], "ppo.learning_rate": ["1e-3"]}
    names = [v.name for v in variants(grid, [1, 2])]
    assert names == [
        "curriculum=fixed_only,learning_rate=1e-3,seed=1",
        "curriculum=two_stage,learning_rate=1e-3,seed=1",
        "curriculum=fixed_only,learning_rate=1e-3,seed=2",
        "curriculum=two_stage,learning_rate=1e-3,seed=2",
    ]
    first = variants(grid, [1])[0]
    assert first.overrides == ["behavior.curriculum=fixed_only", "ppo.learning_rate=1e-3"]
    # keys sharing a last part keep their whole name; unsafe characters become _
    clash = variants({"a.lr": ["x/y"], "b.lr": ["1"]}, [0])[0]
    assert clash.name == "a.lr=x_y,b.lr=1,seed=0"
    with pytest.raises(UsageError, match="give the same run folder name"):
        variants({"behavior.name": ["a/b", "a_b"]}, [0])


def test_sweep_file_and_options_merge(tmp_path):
    path = tmp_path / "sweep.toml"
    path.write_text(
        'behavior = "tiny"\nout = "from_file"\nseeds = [1, 2]\n'
        '[grid]\n"behavior.target" = [0.3, 0.6]\n"behavior.use_eyes" = [true, false]\n'
        "[train]\nsteps = 4e2\nworkers = 1\nset = { save_interval = 2 }\n"
        "[eval]\nepisodes = 3\n[executor]\njobs = 2\n"
    )
    spec = build_spec("tiny", {"out": "from_cli", "grid": ["behavior.target=0.1"]}, path)
    assert str(spec.out) == "from_cli"
    assert spec.grid == {"behavior.target": ["0.1"], "behavior.use_eyes": ["true", "false"]}
    assert spec.seeds == [1, 2] and spec.jobs == 2 and spec.evaluation.episodes == 3
    assert (spec.train.steps, spec.train.workers, spec.train.cores_per_run) == (400, 1, 1)
    assert spec.train.overrides == ["save_interval=2"]
    path.write_text('behavior = "tiny"\n[train]\nstep = 5\n')
    with pytest.raises(UsageError, match=r"unknown key 'step' in \[train\]; valid: cores, envs"):
        build_spec("tiny", {"out": "x"}, path)
    path.write_text('behavior = "tiny"\n[train\n')
    with pytest.raises(UsageError, match="is not valid TOML"):
        build_spec("tiny", {"out": "x"}, path)
    with pytest.raises(UsageError, match="is for behavior 'tiny', not 'other'"):
        path.write_text('behavior = "tiny"\n')
        build_spec("other", {"out": "x"}, path)


def test_plan_builds_each_runs_commands(tmp_path):
    options = {
        "out": str(tmp_path / "s"),
        "grid": ["behavior.target=0.3,0.6"],
        "seeds": "4",
        "steps": "64",
        "envs": "2",
        "overrides": ["save_interval=1"],
        "eval_args": ["--video", "x.mp4"],
    }
    runs = plan_sweep(build_spec("tiny", options, None), tiny_devlearn.registry())
    assert [r.job.name for r in runs] == ["target=0.3,seed=4", "target=0.6,seed=4"]
    job = runs[1].job
    config = job.config  # resolved and checked, as `devlearn run` resolves one
    assert (config["seed"], config["workers"], config["total_steps"]) == (4, 0, 64)
    assert (config["num_envs"], config["save_interval"]) == (2, 1)
    assert config["behavior"]["target"] == 0.6
    assert config["torch_threads"] == 1  # fixed: the same numbers under either executor
    assert config["out_dir"] == str(job.run_dir)
    assert job.config_path == job.run_dir / "run_config.json"
    assert job.settings == [
        "seed=4", "save_interval=1", "behavior.target=0.6", "torch_threads=1",
    ]  # fmt: skip
    assert job.resume_args == ["--workers", "0", "--steps", "64"]
    assert job.eval_args == ["--episodes", "10", "--seed", "0", "--json", "--video", "x.mp4"]
    assert job.run_dir == (tmp_path / "s" / "runs" / "target=0.6,seed=4").resolve()
    assert runs[0].total_steps == 64


def test_local_executor_gives_each_job_its_own_cores():
    cores = available_cores()
    executor = LocalExecutor(1)
    try:
        assert executor.jobs == len(cores) and executor.pinned
        given = [executor._free.get() for _ in range(executor.jobs)]
        assert sorted(c for chunk in given for c in chunk) == cores
    finally:
        executor.close()
    if len(cores) >= 2:
        two = LocalExecutor(2)
        assert two.jobs == len(cores) // 2
        two.close()
    with pytest.raises(UsageError, match=f"needs {len(cores) + 1} cores but this machine gives"):
        LocalExecutor(len(cores) + 1)


@pytest.mark.skipif(len(available_cores()) < 2, reason="needs two cores")
def test_a_sweep_that_leaves_cores_free_does_not_pin_its_runs():
    """Two `--jobs 1` sweeps side by side (one per arm) once ran on the first core both, the
    second core idle: a sweep pins its runs only when they fill the machine."""
    one = LocalExecutor(1, jobs=1)
    try:
        assert not one.pinned and one._free.get() is None
        assert "not pinned" in one.describe()
    finally:
        one.close()
    crowded = LocalExecutor(1, jobs=len(available_cores()) + 1)
    try:
        assert not crowded.pinned and "more jobs than cores" in crowded.describe()
    finally:
        crowded.close()


def test_bad_input_is_one_line_and_starts_nothing(cli, refused, tmp_path, monkeypatch):
    out = tmp_path / "sweep"
    base = ["sweep", "tiny", "--out", str(out), "--steps", "128"]
    cases = {
        "--grid: unknown config key 'behavior.targt'; valid keys:": ["--grid", "behavior.targt=1"],
        "run target=far,seed=0: bad value 'far' for behavior.target": [
            "--grid", "behavior.target=0.3,far",
        ],
        "--seeds must be seeds >= 0 separated by commas": ["--seeds", "1,two"],
        "--grid cannot vary 'seed'; use --seeds": ["--grid", "seed=1,2"],
        "'save_interval' is both in --grid and in --set": [
            "--grid", "save_interval=1,2", "--set", "save_interval=3",
        ],
        "--grid behavior.target lists a value twice": ["--grid", "behavior.target=1,1"],
        "--steps must be at least 1, got 0": ["--steps", "0"],
        "unknown executor 'slurm'; valid: local, ray": ["--executor", "slurm"],
        "needs 999 cores but this machine gives": ["--cores", "999"],
    }  # fmt: skip
    for message, extra in cases.items():
        assert message in refused(cli, *base, *extra), message
    assert "unknown behavior 'tinyy'" in refused(cli, "sweep", "tinyy", "--out", str(out))
    assert "a sweep needs its folder: --out DIR" in refused(cli, "sweep", "tiny")
    assert not out.exists()


def test_ray_missing_or_unreachable_is_one_line(cli, refused, tmp_path, monkeypatch):
    out = tmp_path / "sweep"
    base = ["sweep", "tiny", "--out", str(out), "--executor", "ray"]
    with monkeypatch.context() as patch:
        patch.setitem(sys.modules, "ray", None)  # as if not installed
        err = refused(cli, *base)
    assert "needs Ray, which is not installed: pip install 'devlearn[ray]'" in err
    pytest.importorskip("ray")
    err = refused(cli, *base, "--address", "127.0.0.1:9")
    assert "cannot reach the Ray cluster at 127.0.0.1:9" in err
    assert "--jobs is for the local executor" in refused(cli, *base, "--jobs", "2")
    assert not out.exists()


def test_a_folder_of_another_sweep_or_behaviour_is_refused(cli, refused, tmp_path):
    out = tmp_path / "sweep"
    other = build_spec("other", {"out": str(out), "grid": ["behavior.target=0.3"]}, None)
    SweepFolder(other, None, "devlearn sweep other ...").close()
    before = sorted(p.name for p in out.iterdir())
    err = refused(cli, "sweep", "tiny", "--out", str(out))
    assert f"sweep folder {out} holds a sweep of 'other', not 'tiny'" in err
    err = refused(cli, "sweep", "other", "--out", str(out), "--steps", "256")
    assert "was started with other settings (train.steps was None, now 256)" in err
    assert sorted(p.name for p in out.iterdir()) == before
    run_dir = tmp_path / "a_run"
    run_dir.mkdir()
    (run_dir / "config.json").write_text("{}")
    err = refused(cli, "sweep", "tiny", "--out", str(run_dir))
    assert "is not a sweep folder (no readable sweep.json) and not empty" in err


def test_dry_run_lists_the_runs(cli, capsys, tmp_path):
    out = tmp_path / "sweep"
    argv = ["sweep", "tiny", "--out", str(out), "--grid", "behavior.target=0.3,0.6", "--dry-run"]
    assert cli([*argv, "--seeds", "1-2"]) == 0
    printed = capsys.readouterr().out.splitlines()
    assert [line.split(":")[0] for line in printed[:4]] == [
        "target=0.3,seed=1", "target=0.6,seed=1", "target=0.3,seed=2", "target=0.6,seed=2",
    ]  # fmt: skip
    assert "behavior.target=0.6" in printed[1] and "seed=1" in printed[1]
    assert "--config" in printed[1] and printed[1].split("--config ")[1].split()[0].endswith(
        "target=0.6,seed=1/run_config.json"
    )
    assert printed[-1].startswith("4 runs in") and not out.exists()


def test_preset_reaches_every_run(capsys, tmp_path):
    """`--preset paper` plans each run from the behaviour's preset (self_touch: unbounded spread,
    8M steps), under --steps and --set, and passes it on to `devlearn run`."""
    from devlearn.plugins import PluginRegistry

    out = tmp_path / "sweep"
    options = {"out": str(out), "seeds": "1,2", "steps": "4096", "preset": "paper",
               "overrides": ["behavior.lifetime_memory=per_env"]}  # fmt: skip
    spec = build_spec("self_touch", options, None)
    assert spec.what()["train"]["preset"] == "paper"
    runs = plan_sweep(spec, PluginRegistry(disabled=()), [])
    config = runs[0].job.config
    assert config["preset"] == "paper" and "preset=paper" in runs[0].job.settings
    assert config["total_steps"] == 4096  # the option wins over the preset's 8M
    assert main(["sweep", "self_touch", "--out", str(out), "--preset", "paper", "--dry-run"]) == 0
    assert "preset=paper" in capsys.readouterr().out
    assert main(["sweep", "self_touch", "--out", str(out), "--preset", "nope", "--dry-run"]) == 2
    assert "paper" in capsys.readouterr().err  # the valid presets are named
    without = build_spec("self_touch", {"out": str(out)}, None)
    assert "preset" not in without.what()["train"]  # sweeps made before keep their identity


def test_grid_varies_a_learned_reward_option_and_checks_it_up_front(tmp_path):
    """`--grid learned.TERM.OPTION=...` is a key like `--set` takes (e.g. a curiosity weight of 0
    as the control); an unknown option of the term fails at planning, before any run starts."""
    from devlearn.plugins import PluginRegistry

    registry = PluginRegistry(disabled=())
    options = {"out": str(tmp_path / "s"), "seeds": "1", "steps": "5120",
               "grid": ["learned.rnd.weight=0,0.05"], "overrides": ["curiosity=rnd"]}  # fmt: skip
    runs = plan_sweep(build_spec("self_touch", options, None), registry, [])
    assert len(runs) == 2
    sets = [a for r in runs for a in r.job.settings if a.startswith("learned.")]
    assert sets == ["learned.rnd.weight=0", "learned.rnd.weight=0.05"]
    typo = {**options, "grid": ["learned.rnd.wieght=0,0.05"]}
    with pytest.raises(UsageError, match="wieght"):
        plan_sweep(build_spec("self_touch", typo, None), registry, [])
    unknown = {**options, "grid": ["learnd.rnd.weight=0"]}
    with pytest.raises(UsageError, match="unknown config key 'learnd.rnd.weight'"):
        plan_sweep(build_spec("self_touch", unknown, None), registry, [])


def test_dry_run_checks_what_the_sweep_would_refuse(cli, refused, tmp_path):
    out = tmp_path / "sweep"
    base = ["sweep", "tiny", "--out", str(out), "--steps", "128", "--dry-run"]
    assert "needs 99 cores but this machine gives" in refused(cli, *base, "--cores", "99")
    long = "0." + "1" * 300
    err = refused(cli, *base, "--grid", f"behavior.target={long}")
    assert "its folder name would be" in err and "over the file system's 255" in err
    err = refused(cli, *base, "--seeds", "0-100000000")
    assert "--seeds '0-100000000' lists more than 10,000 seeds" in err
    assert not out.exists()


def test_a_grid_of_too_many_runs_is_refused_before_any_is_planned(cli, refused, tmp_path):
    # issue #55, fault 12: seeds were capped, grid x seeds was not (3000 x 3000 planned for hours)
    with pytest.raises(UsageError, match="would train 10,001 runs"):  # first: fast on old code
        variants({"a": [str(i) for i in range(10_001)]}, [0])
    assert len(variants({"a": [str(i) for i in range(5_000)]}, [0, 1])) == 10_000
    out = tmp_path / "sweep"
    base = ["sweep", "tiny", "--out", str(out), "--steps", "128", "--dry-run"]
    values = ",".join(f"0.{i:04d}" for i in range(1, 3001))
    grid = ["--grid", f"behavior.target={values}", "--grid", f"save_interval={values}"]
    err = refused(cli, *base, *grid)
    assert err == (
        "devlearn: error: the sweep would train 9,000,000 runs (3,000 values of behavior.target "
        "x 3,000 values of save_interval x 1 seed), more than 10,000; give fewer grid values or "
        "seeds, or split it into several sweeps"
    )
    err = refused(cli, *base, "--grid", f"behavior.target={values}", "--seeds", "1-4")
    assert "the sweep would train 12,000 runs (3,000 values of behavior.target x 4 seeds)" in err
    assert not out.exists()


def test_a_sweep_file_is_read_with_guards(cli, refused, tmp_path):
    # issue #55, fault 8: a deep TOML array was a RecursionError; /dev/zero read until memory ran
    # out (the deep file first: it fails fast where the guards are missing)
    deep = tmp_path / "deep.toml"
    deep.write_text("seeds = " + "[" * 100_000 + "]" * 100_000 + "\n")
    base = ["sweep", "tiny", "--out", str(tmp_path / "sweep"), "--dry-run", "--file"]
    assert f"sweep file {deep} is nested too deeply" in refused(cli, *base, str(deep))
    err = refused(cli, *base, "/dev/zero")
    assert "cannot read /dev/zero: a character device, not a file" in err
    assert not (tmp_path / "sweep").exists()


def test_a_set_budget_is_the_one_a_restart_trains_to(tmp_path):
    # --set total_steps=... wins over --steps for the run (the config resolves it last), and a
    # restart trains to that budget, not --steps's
    options = {"out": str(tmp_path / "s"), "steps": "64", "envs": "2"}
    runs = plan_sweep(
        build_spec("tiny", {**options, "overrides": ["total_steps=32"]}, None),
        tiny_devlearn.registry(),
    )
    assert [(r.total_steps, r.job.resume_args) for r in runs] == [
        (32, ["--workers", "0", "--steps", "32"])
    ]
