"""`devlearn new`: the plugin it writes installs and passes its tests; the guide is true."""

from __future__ import annotations

import importlib
import json
import os
import subprocess
import sys
from pathlib import Path

import doc_commands
import pytest

from devlearn.api.errors import UsageError
from devlearn.cli import main
from devlearn.cli.new import write_plugin

GUIDE = Path(__file__).resolve().parents[2] / "docs" / "writing-a-plugin.md"


def test_writes_a_distribution_with_entry_point_behavior_and_tests(tmp_path):
    files = write_plugin("my_reach", tmp_path / "p")
    names = sorted(str(f.relative_to(tmp_path / "p")) for f in files)
    assert names == [
        "README.md",
        "pyproject.toml",
        "src/devlearn_my_reach/__init__.py",
        "src/devlearn_my_reach/behavior.py",
        "src/devlearn_my_reach/plugin.py",
        "tests/test_my_reach.py",
    ]
    pyproject = (tmp_path / "p" / "pyproject.toml").read_text()
    assert "[build-system]" in pyproject and 'version = "0.1.0"' in pyproject
    assert 'my_reach = "devlearn_my_reach.plugin"' in pyproject
    behavior = (tmp_path / "p" / "src/devlearn_my_reach/behavior.py").read_text()
    assert "class MyReach(devlearn.Behavior)" in behavior and "$" not in behavior
    compile(behavior, "behavior.py", "exec")


def test_the_generated_plugin_passes_the_gymnasium_check(tmp_path, monkeypatch):
    """A third-party behaviour made by `devlearn new` is a Gymnasium env as the built-in ones."""
    from devlearn.testing import check_gymnasium

    write_plugin("my_reach", tmp_path / "p")
    monkeypatch.syspath_prepend(str(tmp_path / "p" / "src"))
    module = importlib.import_module("devlearn_my_reach.behavior")
    try:
        check_gymnasium(module.MyReach)
    finally:
        for name in [n for n in sys.modules if n.startswith("devlearn_my_reach")]:
            del sys.modules[name]


@pytest.mark.parametrize("name", ["My-Reach", "1st", "class", "self_touch"])
def test_bad_or_taken_names_are_refused(tmp_path, capsys, name):
    assert main(["new", name, "--out", str(tmp_path / "x")]) == 2
    assert "devlearn: error:" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_a_non_empty_folder_is_refused(tmp_path):
    (tmp_path / "keep.txt").write_text("mine")
    with pytest.raises(UsageError, match="already exists and is not empty"):
        write_plugin("my_reach", tmp_path)


def test_a_name_or_folder_the_file_system_refuses_is_one_line(tmp_path, capsys, monkeypatch):
    """Issue #55: a 301-character name or ``--out /proc/x`` was an OSError traceback."""
    monkeypatch.chdir(tmp_path)
    assert main(["new", "a" * 301]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("devlearn: error: plugin name 'aaaa") and "\n" not in err
    assert "is 301 characters; at most" in err
    cases = [str(tmp_path / ("b" * 300) / "x")]  # a folder name over the file system's limit
    if os.path.isdir("/proc/self"):
        cases.append("/proc/x")
    for out in cases:
        assert main(["new", "my_reach", "--out", out]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("devlearn: error: ") and "\n" not in err, err
    assert list(tmp_path.iterdir()) == []


def test_a_write_that_fails_leaves_nothing(tmp_path, monkeypatch):
    import devlearn.cli.new as new

    written = []

    def full_disk(path, text):
        if len(written) == 3:
            raise OSError(28, "No space left on device")
        written.append(path)
        path.write_text(text)

    monkeypatch.setattr(new, "write_text_atomically", full_disk)
    with pytest.raises(UsageError, match="cannot write the plugin to .*: No space left on device"):
        write_plugin("my_reach", tmp_path / "deep" / "p")
    assert len(written) == 3 and list(tmp_path.iterdir()) == []


def test_every_file_excerpt_in_the_guide_is_what_new_writes(tmp_path):
    write_plugin("my_reach", tmp_path / "devlearn-my-reach")
    guide = GUIDE.read_text()
    excerpts = doc_commands.blocks(guide, "python") + doc_commands.blocks(guide, "toml")
    checked = 0
    for excerpt in excerpts:
        first, _, body = excerpt.partition("\n")
        if not first.startswith("# devlearn-my-reach/"):
            continue
        path = tmp_path / first[2:].strip()
        assert body.strip() in path.read_text(), f"guide excerpt differs from {path.name}"
        checked += 1
    assert checked >= 6


def _run_guide_command(words: list[str], cwd: Path, env: dict) -> subprocess.CompletedProcess:
    if words[:3] == ["pip", "install", "-e"]:  # into a folder of its own, not the shared venv
        pip = [sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--target", "site"]
        try:
            import setuptools  # noqa: F401  (build offline with the venv's setuptools)

            pip.append("--no-build-isolation")
        except ImportError:
            pass
        words = [*pip, str(cwd / words[3])]  # a path, not a name on the index
    elif words[:3] == ["python", "-m", "pytest"]:
        words = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *words[3:]]
    else:
        words = doc_commands.shrink(words)
    result = subprocess.run(words, cwd=cwd, env=env, capture_output=True, text=True, timeout=900)
    assert result.returncode == 0, (
        f"{' '.join(words)}\n{result.stdout[-3000:]}\n{result.stderr[-3000:]}"
    )
    return result


@pytest.mark.slow
def test_the_guide_from_an_empty_folder_to_a_trained_evaluated_plugin(tmp_path):
    """Runs section 1's commands (pip installs into ./site; budgets shrunk by doc_commands)."""
    walk = doc_commands.commands(doc_commands.blocks(GUIDE.read_text(), "bash")[0])
    assert [w[:2] for w in walk][:2] == [["devlearn", "new"], ["pip", "install"]]
    site = tmp_path / "site"
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(site), os.environ.get("PYTHONPATH", "")]),
    }
    outputs = {}
    for words in walk:
        outputs[" ".join(words[:2])] = _run_guide_command(words, tmp_path, env).stdout
    assert "my_reach" in outputs["devlearn plugins"]
    assert "7 passed" in outputs["python -m"]  # the generated tests, as generated
    assert (tmp_path / "runs/my_reach/checkpoint_latest.pt").exists()
    evaluation = outputs["devlearn eval"]
    assert "mean_regions" in json.loads(evaluation[evaluation.index("{") :])
