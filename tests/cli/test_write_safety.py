"""Where commands write (issue #55, #59): a device or FIFO is never replaced, a place that cannot
take the file is refused before any work, a failed write leaves nothing and loses no result, a
kill mid-write leaves the old file or the new one, and a run folder is one process's."""

from __future__ import annotations

import json
import os
import signal
import stat
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from devlearn.testing.fake_infant import TinyBehavior

SMALL = ["--envs", "2", "--seed", "1", "--workers", "0", "--set", "save_interval=1"]

CHILD = """
import functools, sys
import devlearn.env.behavior_env
import devlearn.plugins
from devlearn.cli import main
from devlearn.testing import registry_for
from devlearn.testing.fake_infant import TinyBehavior, fake_infant_factory

registry = registry_for(TinyBehavior)
devlearn.plugins.PluginRegistry = lambda *a, **k: registry
devlearn.env.behavior_env.build_default_infant = functools.partial(
    fake_infant_factory, episode_steps=10
)
{setup}
sys.exit(main(sys.argv[1:]))
"""
"""``devlearn ARGV`` in a new process, as the ``cli`` fixture runs it (the tiny behaviour, a fake
infant), after ``setup`` (code that breaks something on purpose)."""

KILLED_WHILE_WRITING = """
import builtins, io, os, signal

name = os.environ["KILL_WRITING"]
real_open = io.open


class HalfThenKilled:
    # a write that stops halfway: the bytes written so far reach the disk, then the process
    # is killed (kill -9 in the middle of writing the file)

    def __init__(self, f):
        self.f = f

    def write(self, data):
        self.f.write(data[: len(data) // 2])
        self.f.flush()
        os.fsync(self.f.fileno())
        os.kill(os.getpid(), signal.SIGKILL)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.f.close()

    def __getattr__(self, attr):
        return getattr(self.f, attr)


def killing_open(file, mode="r", *args, **kwargs):
    f = real_open(file, mode, *args, **kwargs)
    base = os.path.basename(os.fspath(file)) if not isinstance(file, int) else ""
    if "w" in mode and (base == name or base.startswith(f".{name}.tmp-")):
        return HalfThenKilled(f)
    return f


builtins.open = io.open = killing_open
"""
"""Setup for :data:`CHILD`: the process is killed halfway through writing the file named
``$KILL_WRITING`` (or its atomic temporary), whichever way it opens it."""


def child(setup: str, *argv: str, env: dict | None = None, **popen) -> subprocess.Popen:
    code = CHILD.format(setup=setup)
    environ = {**os.environ, **(env or {})}
    return subprocess.Popen([sys.executable, "-c", code, *argv], env=environ, **popen)


@pytest.fixture
def cli(cli_with):
    """Run ``devlearn ...`` in process with the tiny behaviour installed and a fake infant."""
    return cli_with(TinyBehavior)


@pytest.fixture
def run_dir(cli, tmp_path, capsys) -> Path:
    """A finished 2-env run of 32 steps of the tiny behaviour, in ``tmp_path/run``."""
    out = tmp_path / "run"
    assert cli(["run", "tiny", "--steps", "32", "--out", str(out), *SMALL]) == 0
    capsys.readouterr()
    return out


def files(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


@pytest.fixture
def fifo() -> Iterator:
    """``fifo(path)``: make a FIFO at ``path`` with a reader that drains it, so that a command
    which wrongly writes into it goes on (and fails the test) instead of blocking forever."""
    readers: list[int] = []
    made: list[Path] = []
    stop = threading.Event()

    def drain() -> None:
        while not stop.is_set():
            for fd in list(readers):
                try:
                    os.read(fd, 1 << 16)
                except BlockingIOError:
                    pass
            time.sleep(0.005)

    thread = threading.Thread(target=drain, daemon=True)
    thread.start()

    def make(path: Path) -> Path:
        path.parent.mkdir(parents=True, exist_ok=True)
        os.mkfifo(path)
        made.append(path)
        readers.append(os.open(path, os.O_RDONLY | os.O_NONBLOCK))
        return path

    yield make
    stop.set()
    thread.join()
    for fd in readers:
        os.close(fd)
    for path in made:  # no FIFO named eval.json left for a later folder scan to block on
        if path.exists() and is_fifo(path):
            path.unlink()


def is_fifo(path: Path) -> bool:
    return stat.S_ISFIFO(os.lstat(path).st_mode)


def test_no_command_replaces_or_writes_into_a_fifo(cli, refused, run_dir, tmp_path, fifo):
    checkpoint = str(run_dir / "checkpoint_latest.pt")
    assert cli(["eval", "tiny", "--checkpoint", checkpoint, "--episodes", "1",
                "--out", str(tmp_path / "e")]) == 0  # fmt: skip
    forced = tmp_path / "forced"  # a run folder whose config.json is a FIFO
    forced.mkdir()
    fifo(forced / "config.json")
    e2, report = tmp_path / "e2", tmp_path / "r"
    cases = [
        (tmp_path / "p.ts",
         ["export", "tiny", "--checkpoint", checkpoint, "--format", "torchscript", "--out"]),
        (tmp_path / "policy.pt", ["slim", checkpoint, "--out"]),
        (tmp_path / "curve.png", ["curve", str(run_dir), "--out"]),
        (tmp_path / "v.mp4",
         ["eval", "tiny", "--checkpoint", checkpoint, "--episodes", "1", "--video"]),
        (e2 / "eval.json",
         ["eval", "tiny", "--checkpoint", checkpoint, "--episodes", "1", "--out", str(e2)]),
        (report / "report.md", ["report", str(tmp_path / "e"), "--out", str(report)]),
        (forced / "config.json",
         ["run", "tiny", "--out", str(forced), "--force", "--steps", "32", *SMALL]),
    ]  # fmt: skip
    for path, argv in cases:
        if not path.exists():
            fifo(path)
        if argv[-1] == "--out" or argv[-1] == "--video":
            argv = [*argv, str(path)]
        err = refused(cli, *argv)
        assert f"{path}: it is a FIFO, not a regular file" in err, argv
        assert is_fifo(path), f"{argv} replaced the FIFO"
    assert sorted(p.name for p in e2.iterdir()) == ["eval.json"]
    assert sorted(p.name for p in report.iterdir()) == ["report.md"]
    assert sorted(p.name for p in forced.iterdir()) == ["config.json"]


@pytest.mark.skipif(os.geteuid() != 0, reason="making a device node needs root")
def test_export_and_slim_leave_a_device_node_as_it_is(cli, refused, run_dir, tmp_path):
    """The tester's case: ``--out`` a character device (here a null device made in tmp_path,
    never /dev/null itself) was replaced by a regular file and the command said it wrote it."""
    node = tmp_path / "n"
    os.mknod(node, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
    checkpoint = str(run_dir / "checkpoint_latest.pt")
    for argv in (
        ["export", "tiny", "--checkpoint", checkpoint, "--format", "torchscript", "--out"],
        ["slim", checkpoint, "--out"],
    ):
        err = refused(cli, *argv, str(node))
        assert f"cannot write {node}: it is a character device, not a regular file" in err
        mode = os.lstat(node)
        assert stat.S_ISCHR(mode.st_mode) and mode.st_rdev == os.makedev(1, 3)


def test_an_export_to_a_full_disk_is_one_line_and_leaves_no_temporary(run_dir, tmp_path):
    """TorchScript's own file writer aborted the process (exit 134) when a write failed, and left
    ``.x.ts.tmp-PID``. Here writes past 4 kB fail (RLIMIT_FSIZE: EFBIG, as ENOSPC on a full
    disk) in a process of its own."""
    limit = "\n".join(
        [
            "import resource, signal",
            "signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a failed write, not a signal",
            "resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))",
        ]
    )
    out = tmp_path / "full" / "x.ts"
    out.parent.mkdir()
    argv = ["export", "tiny", "--checkpoint", str(run_dir / "checkpoint_latest.pt"),
            "--format", "torchscript", "--out", str(out)]  # fmt: skip
    proc = child(limit, *argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    stdout, stderr = proc.communicate(timeout=300)
    assert proc.returncode == 2, stderr[-2000:]
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert lines == [f"devlearn: error: cannot write {out}: File too large"], stderr[-2000:]
    assert list(out.parent.iterdir()) == []  # no partial file, no temporary


def test_an_unknown_or_unwritable_picture_path_is_refused_before_drawing(
    refused, tmp_path, monkeypatch
):
    from devlearn.cli import main
    from devlearn.infant import pictures

    def drawn(*args, **kwargs):
        raise AssertionError("drew a picture for a path it cannot write")

    monkeypatch.setattr(pictures, "body_map_picture", drawn)
    base = ["picture", "body-map", "--out"]
    err = refused(main, *base, str(tmp_path / "body_map"))
    assert "cannot write a '(no extension)' file; valid: .png, .jpg" in err
    err = refused(main, *base, str(tmp_path / "map.txt"))
    assert "cannot write a '.txt' file; valid: .png" in err
    assert f"--out {tmp_path} is a folder" in refused(main, *base, str(tmp_path))
    if Path("/proc/self").is_dir():  # the tester's case: exit 0, and nothing written
        err = refused(main, *base, "/proc/x.png")
        assert "cannot write /proc/x.png: cannot create files in /proc" in err
    assert list(tmp_path.iterdir()) == []


def test_a_bad_video_path_is_refused_before_any_episode(cli, refused, run_dir, tmp_path):
    checkpoint = str(run_dir / "checkpoint_latest.pt")
    base = ["eval", "tiny", "--checkpoint", checkpoint, "--episodes", "1",
            "--out", str(tmp_path / "e"), "--video"]  # fmt: skip
    err = refused(cli, *base, str(tmp_path / "v.txt"))
    assert "--video" in err and "cannot write a '.txt' file; valid: .mp4, .mkv, .mov, .avi" in err
    assert f"--video {tmp_path} is a folder" in refused(cli, *base, str(tmp_path))
    (tmp_path / "file").write_text("")
    err = refused(cli, *base, str(tmp_path / "file" / "v.mp4"))
    assert f"cannot write {tmp_path / 'file' / 'v.mp4'}: {tmp_path / 'file'} is not a folder" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file", "run"]  # no eval folder


def test_a_video_that_fails_keeps_the_evaluation(cli, run_dir, tmp_path, capsys, monkeypatch):
    """The video failed after the episodes ran, and eval.json was never written."""
    import imageio_ffmpeg

    def full_disk(path, *args, **kwargs):
        yield  # ffmpeg started; the first frame finds the disk full
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(imageio_ffmpeg, "write_frames", full_disk)
    video, out = tmp_path / "v.mp4", tmp_path / "e"
    capsys.readouterr()
    argv = ["eval", "tiny", "--checkpoint", str(run_dir / "checkpoint_latest.pt"),
            "--episodes", "2", "--out", str(out), "--video", str(video)]  # fmt: skip
    assert cli(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err == (
        f"devlearn: error: evaluated, but cannot write the video {video}: No space left on "
        f"device ({out / 'eval.json'} is written)"
    )
    assert json.loads((out / "eval.json").read_text())["episodes"] == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["e", "run"]  # no video, no temporary


@pytest.mark.parametrize("name", ["eval.json", "config.json"])
def test_a_kill_mid_write_leaves_the_old_file(cli, run_dir, tmp_path, name):
    """Issue #59: eval.json and config.json (which --resume reads) were written in place, so a
    kill while writing left half a file."""
    checkpoint = str(run_dir / "checkpoint_latest.pt")
    evaluate = ["eval", "tiny", "--checkpoint", checkpoint, "--episodes", "1",
                "--out", str(tmp_path / "e")]  # fmt: skip
    assert cli(evaluate) == 0
    if name == "eval.json":
        path, argv = tmp_path / "e" / "eval.json", evaluate
    else:
        path = run_dir / "config.json"
        argv = ["run", "tiny", "--resume", str(run_dir), "--steps", "48"]
    before = path.read_bytes()
    proc = child(KILLED_WHILE_WRITING, *argv, env={"KILL_WRITING": name},
                 stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)  # fmt: skip
    _, stderr = proc.communicate(timeout=300)
    assert proc.returncode == -signal.SIGKILL, stderr.decode()[-2000:]  # killed while writing
    assert path.read_bytes() == before
    json.loads(path.read_text())
    if name == "config.json":  # the run goes on from it, and its half temporary is cleared
        assert cli(["run", "tiny", "--resume", str(run_dir), "--steps", "48"]) == 0
        assert not list(run_dir.glob(".config.json.tmp-*"))


def test_a_run_folder_in_use_is_refused_and_left_alone(cli, refused, run_dir, tmp_path):
    """Two ``run --resume D`` at once interleaved their steps in metrics.jsonl, and ``run --out
    D --force`` beside a running run deleted its checkpoints. A run holds its folder's lock
    until it ends, however it ends."""
    holds = "\n".join(
        [
            "import time",
            "from devlearn.training.runner import DevRunner",
            "def learn(self, total_steps):  # a run in the middle of its training",
            "    print('learning', flush=True)",
            "    time.sleep(600)",
            "DevRunner.learn = learn",
        ]
    )
    proc = child(holds, "run", "tiny", "--resume", str(run_dir), "--steps", "64",
                 stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)  # fmt: skip
    try:
        assert proc.stdout is not None
        for line in proc.stdout:
            if line.strip() == "learning":
                break
        else:
            raise AssertionError(f"the first run ended without training (code {proc.wait()})")
        before = files(run_dir)
        in_use = f"{run_dir} is in use by pid {proc.pid}"
        assert in_use in refused(cli, "run", "tiny", "--resume", str(run_dir), "--steps", "64")
        assert in_use in refused(
            cli, "run", "tiny", "--out", str(run_dir), "--force", "--steps", "32", *SMALL
        )
        assert files(run_dir) == before  # its checkpoints and metrics untouched
    finally:
        proc.kill()  # as kill -9: the lock ends with the process
        proc.wait(timeout=60)
    assert cli(["run", "tiny", "--resume", str(run_dir), "--steps", "48"]) == 0
    rows = (run_dir / "metrics.jsonl").read_text().splitlines()
    assert [json.loads(row)["step"] for row in rows] == [16, 32, 48]
