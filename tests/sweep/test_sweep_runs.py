"""Whole sweeps of the tiny behaviour: evaluated runs, report, kill and restart, a failing run,
and the same numbers on a local Ray instance as on the local executor."""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import io
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest
import tiny_devlearn

from devlearn.cli import main
from devlearn.cores import available_cores

GRID = ["--grid", "behavior.target=0.1,0.15", "--seeds", "1,2"]
ONE_RUN = ["--grid", "behavior.target=0.3", "--seeds", "1", "--no-report"]
NAMES = ["target=0.1,seed=1", "target=0.15,seed=1", "target=0.1,seed=2", "target=0.15,seed=2"]
TIMINGS = {"steps_per_s", "collect_s", "update_s"}


def launcher_file(folder: Path) -> Path:
    """A sweep file whose launcher trains the tiny behaviour (tiny_devlearn.py)."""
    path = folder / "tiny_launcher.toml"
    path.write_text(
        f"[executor]\nlauncher = {json.dumps([sys.executable, tiny_devlearn.__file__])}\n"
    )
    return path


def sweep_argv(out: Path, steps: int = 64, *extra: str) -> list[str]:
    return [
        "sweep", "tiny", "--file", str(launcher_file(out.parent)), "--out", str(out),
        "--steps", str(steps), "--envs", "2", "--episodes", "2", "--set", "save_interval=1",
        *extra,
    ]  # fmt: skip


def start_sweep(argv: list[str], stdout: Any = subprocess.PIPE) -> subprocess.Popen:
    """The tiny sweep ``argv`` started as another process, in its own process group (as a
    shell's job, so that a test can stop it with its runs), its output merged into ``stdout``."""
    return subprocess.Popen(
        [sys.executable, tiny_devlearn.__file__, *argv],
        stdout=stdout,
        stderr=subprocess.STDOUT,
        start_new_session=True,
    )


def wait_unlocked(lock_path: Path, timeout: float = 60.0) -> None:
    """Wait until no process holds the sweep's run lock ``lock_path``: a killed sweep's training
    child gets its SIGKILL with the sweep, but may take a moment longer to exit and let go."""
    deadline = time.time() + timeout
    with open(lock_path) as lock:
        while True:
            try:
                fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                assert time.time() < deadline, (
                    f"{lock_path} still held {timeout:.0f} s after the kill"
                )
                time.sleep(0.05)
                continue
            fcntl.flock(lock, fcntl.LOCK_UN)
            return


def run_cli(argv: list[str]) -> tuple[int, str, str]:
    """``devlearn ...`` in this process with the tiny behaviours; (exit code, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with pytest.MonkeyPatch.context() as patch:
        tiny_devlearn.install(patch)
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = main(argv)
    return code, out.getvalue(), err.getvalue()


def records(out: Path) -> dict[str, dict]:
    return {r["name"]: r for r in json.loads((out / "runs.json").read_text())["runs"]}


def metrics(run_dir: Path) -> list[dict]:
    rows = [json.loads(line) for line in (run_dir / "metrics.jsonl").read_text().splitlines()]
    return [{k: v for k, v in row.items() if k not in TIMINGS} for row in rows]


def results(path: Path) -> dict:
    """An eval.json without what may differ between two sweeps: times, hosts, commits, paths."""
    drop = re.compile(r"time|wall|date|host|commit|path|dir|_s$")

    def keep(value):
        if isinstance(value, dict):
            return {k: keep(v) for k, v in value.items() if not drop.search(k)}
        return None if isinstance(value, str) and "/" in value else value

    return keep(json.loads(path.read_text()))


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.fixture(scope="module")
def local_sweep(tmp_path_factory):
    """The 2x2 sweep (two targets x seeds 1, 2) on the local executor, two runs at a time."""
    out = tmp_path_factory.mktemp("local") / "sweep"
    code, stdout, stderr = run_cli(sweep_argv(out, 64, *GRID, "--jobs", "2"))
    return out, code, stdout, stderr


@pytest.mark.slow
def test_two_by_two_sweep_trains_and_evaluates_four_runs(local_sweep):
    out, code, stdout, stderr = local_sweep
    assert sorted(p.name for p in (out / "runs").iterdir()) == sorted(NAMES), stderr
    found = records(out)
    assert list(found) == NAMES  # runs.json keeps the sweep's order
    for name in NAMES:
        record = found[name]
        assert record["status"] == "done", (record.get("error"), record.get("log_tail"))
        summary = json.loads((out / "runs" / name / "eval" / "eval.json").read_text())
        assert summary["episodes"] == 2 and summary["checkpoint_env_steps"] == 64
        assert record["eval"] == summary
        config = record["config"]
        assert config["seed"] == int(name[-1]) and config["total_steps"] == 64
        assert config["behavior"]["target"] == float(name.split(",")[0].split("=")[1])
        assert [a["phase"] for a in record["attempts"]] == ["train", "eval"]
        assert all(a["returncode"] == 0 and a["wall_s"] > 0 for a in record["attempts"])
        assert record["commit"]["commit"] and len(record["commit"]["commit"]) == 40
        assert record["wall_s"] == pytest.approx(record["train_wall_s"] + record["eval_wall_s"])
        argv = record["attempts"][0]["argv"]  # started from the resolved config file
        assert argv[argv.index("--config") + 1] == str(out / "runs" / name / "run_config.json")
    # two at a time, each pinned to a core of its own
    cores = {tuple(found[n]["attempts"][0]["cores"] or ()) for n in NAMES[:2]}
    if len(available_cores()) >= 2:
        assert len(cores) == 2 and all(len(c) == 1 for c in cores)
    lines = stdout.splitlines()
    for name in NAMES:
        for state in ("queued", "training", "evaluating", "done"):
            assert any(line.split()[:2] == [state, name] for line in lines), (state, name)
    sweep = json.loads((out / "sweep.json").read_text())
    assert sweep["what"]["behavior"] == "tiny" and sweep["seeds"] == [1, 2]
    assert sweep["grid"] == {"behavior.target": ["0.1", "0.15"]}


@pytest.mark.slow
def test_a_sweep_run_has_the_config_and_numbers_of_the_same_direct_run(local_sweep, tmp_path):
    """Each run starts from the run_config.json the sweep resolved; `devlearn run` with the
    same options resolves the same config (all but the folder) and trains the same numbers."""
    out, code, stdout, stderr = local_sweep
    run_dir = out / "runs" / NAMES[1]
    written = json.loads((run_dir / "run_config.json").read_text())
    direct = tmp_path / "direct"
    argv = ["run", "tiny", "--out", str(direct), "--steps", "64", "--envs", "2", "--seed", "1",
            "--workers", str(written["workers"]), "--set", "save_interval=1",
            "--set", "behavior.target=0.15", "--set", "torch_threads=1"]  # fmt: skip
    code, _, err = run_cli(argv)
    assert code == 0, err
    ours = json.loads((run_dir / "config.json").read_text())
    theirs = json.loads((direct / "config.json").read_text())
    assert ours.pop("out_dir") == str(run_dir) and written.pop("out_dir") == str(run_dir)
    theirs.pop("out_dir")
    assert ours == theirs
    assert written == {**theirs, "workers": written["workers"]}
    assert metrics(run_dir) == metrics(direct)


def _cells(line: str) -> list[str]:
    return [cell.strip() for cell in line.strip().strip("|").split("|")]


def _naming(labels: list[str], value: str) -> list[str]:
    return [label for label in labels if re.search(rf"(?<![\d.]){re.escape(value)}(?!\d)", label)]


@pytest.mark.slow
def test_two_by_two_sweep_reports_one_row_per_variant(local_sweep):
    """A 2 x 2 sweep ends in devlearn report's table, one row per variant."""
    out, code, stdout, stderr = local_sweep
    assert code == 0, stderr
    assert (out / "report" / "report.png").exists()
    report = (out / "report" / "report.md").read_text()
    table = []
    for line in report.splitlines():
        if line.startswith("|"):
            table.append(line)
        elif table:
            break  # the first table only
    header, rows = _cells(table[0]), [_cells(row) for row in table[2:]]
    # one entry per variant (seeds pooled): a row each, or a column each
    for labels in ([row[0] for row in rows], header[1:]):
        if len(_naming(labels, "0.1")) == 1 and len(_naming(labels, "0.15")) == 1:
            assert _naming(labels, "0.1") != _naming(labels, "0.15")
            break
    else:
        raise AssertionError(f"no row or column per variant in:\n{report}")


@pytest.mark.slow
def test_killed_in_its_second_run_a_restart_finishes_without_retraining_the_first(tmp_path):
    out, steps = tmp_path / "sweep", 480  # 30 iterations of 2 envs x 8 steps
    argv = sweep_argv(out, steps, *GRID, "--jobs", "1", "--no-report")
    log = open(tmp_path / "sweep.log", "wb")
    proc = start_sweep(argv, log)  # killed with its runs below
    first, second = (out / "runs" / n for n in NAMES[:2])
    try:
        deadline = time.time() + 300
        while not (second / "checkpoint_latest.pt").exists():
            assert proc.poll() is None, (tmp_path / "sweep.log").read_text()
            assert time.time() < deadline, "the second run never wrote a checkpoint"
            time.sleep(0.02)
        os.killpg(proc.pid, signal.SIGKILL)  # the sweep and its running training, as a crash
        proc.wait(timeout=30)
        wait_unlocked(out / "records" / f"{NAMES[1]}.lock")  # the training has exited too
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        log.close()
    killed_at = metrics(second)[-1]["step"]
    assert killed_at < steps, "the second run finished before the kill: the test proves nothing"
    assert json.loads((out / "records" / f"{NAMES[1]}.json").read_text())["status"] == "training"
    assert not (out / "runs" / NAMES[2]).exists()
    before = {p.name: digest(p) for p in first.rglob("*") if p.is_file()}
    first_record = json.loads((out / "records" / f"{NAMES[0]}.json").read_text())

    code, stdout, stderr = run_cli(argv[:-3] + ["--jobs", "2", "--no-report"])
    assert code == 0, stdout + stderr
    assert {p.name: digest(p) for p in first.rglob("*") if p.is_file()} == before
    found = records(out)
    assert found[NAMES[0]]["attempts"] == first_record["attempts"]  # not run again
    assert any(line.split()[:3] == ["done", NAMES[0], "(earlier)"] for line in stdout.splitlines())
    assert [a["phase"] for a in found[NAMES[1]]["attempts"]] == ["train", "resume", "eval"]
    assert "--resume" in found[NAMES[1]]["attempts"][1]["argv"]
    rows = metrics(second)
    assert [r["step"] for r in rows] == list(range(16, steps + 1, 16))  # continued, no repeats
    assert [r["iteration"] for r in rows] == list(range(steps // 16))
    for name in NAMES:
        assert found[name]["status"] == "done"
        assert found[name]["eval"]["checkpoint_env_steps"] == steps


@pytest.mark.slow
def test_sigterm_stops_the_sweep_and_its_run_saves_a_checkpoint(tmp_path):
    from devlearn.training.checkpoint import load_checkpoint

    out = tmp_path / "sweep"
    proc = start_sweep(sweep_argv(out, 10**6, *ONE_RUN))
    run_dir = out / "runs" / "target=0.3,seed=1"
    try:
        deadline = time.time() + 300
        while not (run_dir / "checkpoint_latest.pt").exists():
            assert proc.poll() is None and time.time() < deadline
            time.sleep(0.05)
        proc.send_signal(signal.SIGTERM)  # to the sweep process only, as a scheduler would
        stdout = proc.communicate(timeout=120)[0].decode()
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130, stdout
    assert "interrupted target=0.3,seed=1" in stdout and "devlearn: interrupted" in stdout
    record = records(out)["target=0.3,seed=1"]
    assert record["status"] == "interrupted" and record["attempts"][0]["returncode"] == 130
    saved = load_checkpoint(run_dir / "checkpoint_latest.pt")["env_steps"]
    assert 0 < saved < 10**6 and saved == metrics(run_dir)[-1]["step"]  # saved on the way out


@pytest.mark.slow
def test_a_failing_combination_is_reported_and_the_others_finish(tmp_path):
    out = tmp_path / "sweep"
    argv = sweep_argv(out, 64, "--grid", "behavior.break_after=20,0", "--seeds", "3")
    argv[1] = "fragile"
    code, stdout, stderr = run_cli([*argv, "--jobs", "1", "--no-report"])  # the failure first
    assert code == 1
    found = records(out)
    statuses = {name: r["status"] for name, r in found.items()}
    assert statuses == {"break_after=20,seed=3": "failed", "break_after=0,seed=3": "done"}
    failed = found["break_after=20,seed=3"]
    assert failed["error"].startswith("exit code 2 while training")  # a reward term that raises
    assert any("fragile reward broke after 20 steps" in line for line in failed["log_tail"])
    lines = stdout.splitlines()
    at = next(i for i, line in enumerate(lines) if line.startswith("failed      break_after=20"))
    assert "logs/break_after=20,seed=3.log" in lines[at]
    assert any("fragile reward broke after 20 steps" in line for line in lines[at + 1 : at + 16])
    assert "1 of 2 runs done" in stdout and "not done: break_after=20,seed=3" in stdout
    assert (out / "runs" / "break_after=0,seed=3" / "eval" / "eval.json").exists()


@pytest.fixture(scope="module")
def local_ray():
    """A local Ray instance for this module (Ray's start-up takes seconds)."""
    ray = pytest.importorskip("ray")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield ray
    ray.shutdown()


@pytest.mark.slow
def test_ray_executor_gives_the_same_numbers(local_sweep, local_ray, tmp_path):
    local = local_sweep[0]
    out = tmp_path / "sweep"
    # the local sweep's seed-1 runs: Ray starts 4 processes (train, eval) instead of 8, and
    # the two runs differ, so equal numbers are still no coincidence
    grid, names = [*GRID[:2], "--seeds", "1"], NAMES[:2]
    code, stdout, stderr = run_cli(sweep_argv(out, 64, *grid, "--executor", "ray", "--no-report"))
    assert code == 0, stdout + stderr
    assert "as Ray tasks of 1 CPU(s) each" in stdout
    found = records(out)
    assert list(found) == names
    for name in names:
        assert found[name]["status"] == "done"
        ours, theirs = out / "runs" / name, local / "runs" / name
        assert results(ours / "eval" / "eval.json") == results(theirs / "eval" / "eval.json")
        assert metrics(ours) == metrics(theirs)
        assert found[name]["attempts"][0]["cores"] is None  # Ray holds the CPUs, no pinning
    trained = {json.dumps(metrics(out / "runs" / name)) for name in names}
    assert len(trained) == len(names)  # the runs differ, so equal numbers are no coincidence


def descendants(pid: int) -> set[int]:
    """Every living process below ``pid`` (from /proc)."""
    parents = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if fields[0] != "Z":  # a zombie has ended
                parents[int(entry.name)] = int(fields[1])
    found, frontier = set(), {pid}
    while frontier:
        frontier = {p for p, parent in parents.items() if parent in frontier} - found
        found |= frontier
    return found


def alive(pids: set[int]) -> set[int]:
    living = set()
    for pid in pids:
        try:
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:
            continue
        if state != "Z":
            living.add(pid)
    return living


@pytest.mark.slow
@pytest.mark.parametrize("how", ["ctrl-c", "kill -9"])
def test_a_stopped_sweep_leaves_no_process_behind(tmp_path, how):
    """One Ctrl-C (SIGINT to the terminal's process group) stops the sweep and everything it
    started; a sweep killed outright (SIGKILL, nothing of it runs) takes its runs with it."""
    out = tmp_path / "sweep"
    proc = start_sweep(sweep_argv(out, 10**6, *ONE_RUN))  # its own group, as a foreground job
    run_dir = out / "runs" / "target=0.3,seed=1"
    started: set[int] = set()
    try:
        deadline = time.time() + 900  # generous: the machine may be busy with other work
        while not (run_dir / "checkpoint_latest.pt").exists():
            assert proc.poll() is None, proc.communicate()[0].decode()
            assert time.time() < deadline, "the run wrote no checkpoint in 15 minutes"
            time.sleep(0.05)
        started = descendants(proc.pid)
        assert started, "the sweep's run is not running"
        if how == "ctrl-c":
            os.killpg(proc.pid, signal.SIGINT)
            proc.communicate(timeout=120)
            assert proc.returncode == 130
        else:
            proc.kill()
            proc.wait(timeout=30)
        deadline = time.time() + 60
        while alive(started) and time.time() < deadline:
            time.sleep(0.1)
        assert not alive(started), f"left behind: {alive(started)}"
    finally:
        for pid in alive(started) | ({proc.pid} if proc.poll() is None else set()):
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
