"""``devlearn run`` / ``eval`` on bad or hostile input: one line, exit code 2, nothing run."""

from __future__ import annotations

import dataclasses
import errno
import json
import os
import sys
from pathlib import Path
from typing import Any

import pytest
import torch

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "env"))

from tiny_behaviors import OtherBehavior  # noqa: E402

import devlearn  # noqa: E402
import devlearn.plugins  # noqa: E402
from devlearn.config import checks  # noqa: E402
from devlearn.testing.fake_infant import (  # noqa: E402
    Reach,
    TinyBehavior,
    TinyConfig,
)
from devlearn.training import checkpoint as checkpoint_module  # noqa: E402

SMALL = ["--envs", "2", "--seed", "1", "--workers", "0", "--set", "save_interval=1"]


@pytest.fixture
def cli(cli_with):
    """Run ``devlearn ...`` in process with the tiny behaviours installed and a fake infant."""
    return cli_with(TinyBehavior, OtherBehavior)


def finished_run(cli, behavior: str, tmp_path: Path, capsys) -> Path:
    """A finished 2-env run of 32 steps of ``behavior``, in ``tmp_path/run``."""
    out = tmp_path / "run"
    assert cli(["run", behavior, "--steps", "32", "--out", str(out), *SMALL]) == 0
    capsys.readouterr()
    return out


@pytest.fixture
def run_dir(cli, tmp_path, capsys):
    """A finished 2-env tiny run of 32 steps."""
    return finished_run(cli, "tiny", tmp_path, capsys)


def files(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


class Payload:
    """Unpickling this runs ``exec``, which writes a marker file."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return exec, (f"open({str(self.marker)!r}, 'w').write('ran')",)


def test_a_crafted_checkpoint_runs_nothing_on_eval(cli, refused, tmp_path):
    marker = tmp_path / "marker"
    crafted = tmp_path / "crafted.pt"
    state = {"format": "devlearn-checkpoint-1", "behavior": "tiny", "x": Payload(marker)}
    torch.save(state, crafted)
    err = refused(cli, "eval", "tiny", "--checkpoint", str(crafted), "--episodes", "1")
    assert f"checkpoint {crafted} refused: it needs builtins.exec" in err
    assert not marker.exists()


def test_a_genuine_checkpoint_with_a_payload_runs_nothing_on_resume(
    cli, refused, run_dir, tmp_path
):
    marker = tmp_path / "marker"
    for path in run_dir.glob("checkpoint_*.pt"):
        state = torch.load(path, weights_only=False)  # our own file: trusted here
        state["env"]["ranks"][0]["extra"] = Payload(marker)
        path.unlink()
        torch.save(state, path)
    err = refused(cli, "run", "tiny", "--resume", str(run_dir), "--steps", "64")
    assert "refused: it needs builtins.exec" in err and not marker.exists()


def test_out_on_an_existing_run_is_refused_and_leaves_it_unchanged(cli, refused, run_dir):
    before = files(run_dir)
    err = refused(cli, "run", "tiny", "--steps", "64", "--out", str(run_dir), *SMALL)
    assert f"--out {run_dir} already holds a run" in err
    assert f"--resume {run_dir}" in err and "--force" in err
    assert files(run_dir) == before
    assert cli(["run", "tiny", "--steps", "16", "--out", str(run_dir), "--force", *SMALL]) == 0
    steps = [json.loads(r)["step"] for r in (run_dir / "metrics.jsonl").read_text().splitlines()]
    assert steps == [16]


def test_a_rejected_resume_leaves_config_json_as_it_was(cli, refused, run_dir):
    config = (run_dir / "config.json").read_bytes()
    err = refused(cli, "run", "tiny", "--resume", str(run_dir), "--envs", "8", "--steps", "128")
    assert "checkpoint has 2 envs per rank; resume with --envs 2" in err
    assert (run_dir / "config.json").read_bytes() == config
    assert cli(["run", "tiny", "--resume", str(run_dir), "--steps", "48"]) == 0


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["--seed", "-1"], "--seed must be an integer from 0 to 4294967295, got -1"),
        (["--seed", "1e30"], "--seed must be an integer from 0 to 4294967295"),
        (["--set", "ppo.learning_rate=-1"], "ppo.learning_rate must be a finite number in (0, 1]"),
        (["--set", "ppo.learning_rate=nan"], "ppo.learning_rate must be a finite number"),
        (["--set", "ppo.learning_rate=inf"], "ppo.learning_rate must be a finite number"),
        (["--set", "ppo.gamma=inf"], "ppo.gamma must be a finite number in (0, 1], got inf"),
        (["--set", "ppo.clip_param=-1"], "ppo.clip_param must be a finite number in (0, 1]"),
        (["--steps", "1e30"], "--steps must be at most 1e+12, got 1e+30"),
        (["--envs", "1e9"], "--envs must be at most 1e+06, got 1e+09"),
        (["--workers", "1e9"], "--workers must be at most 4096, got 1e+09"),
        (["--workers", "-2"], "--workers must be at least -1 (-1: one per core, 0: in process)"),
        (["--set", "save_interval=1e20"], "save_interval must be at most 1e+09, got 1e+20"),
        (["--set", "torch_threads=1e9"], "torch_threads must be at most 4096"),
        (["--set", "update_threads=-1"], "update_threads must be at least 0 (0: automatic)"),
        (["--set", "ppo.num_steps_per_env=1e12"], "ppo.num_steps_per_env must be at most 1e+06"),
        (["--set", "ppo.num_mini_batches=0"], "ppo.num_mini_batches must be at least 1, got 0"),
        # values that passed their bounds, then crashed, hung or trained past the budget
        (["--set", "env.action_repeat=7"], "env.action_repeat=7 must divide the episode (1000"),
        (["--set", "env.action_repeat=1e9"], "env.action_repeat must be at most 1000"),
        (["--envs", "2", "--set", "env.action_repeat=1000"], "--steps 16 is less than a tenth of one iteration"),
        (["--envs", "2", "--set", "ppo.num_mini_batches=1000000"], "fewer than 2 samples per mini"),
        (["--envs", "1", "--steps", "64", "--set", "ppo.num_steps_per_env=1"], "a rollout of 1 sample"),
    ],
)
def test_bad_values_are_one_line_errors(cli, refused, tmp_path, argv, expected):
    out = tmp_path / "run"
    assert expected in refused(cli, "run", "tiny", "--steps", "16", "--out", str(out), *argv)
    assert not out.exists()


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["--episodes", "100000000000"], "--episodes must be at most 1000000"),
        (["--episodes", "0"], "--episodes must be at least 1, got 0"),
        (["--seed", "1" + "0" * 20], "--seed must be at most 4294967295"),
    ],
)
def test_bad_eval_numbers_are_one_line_errors(cli, refused, tmp_path, argv, expected):
    out = tmp_path / "eval"
    err = refused(cli, "eval", "tiny", "--policy", "zero", "--out", str(out), *argv)
    assert expected in err
    assert not out.exists()


def test_more_envs_than_memory_is_refused_before_building_them(cli, refused, tmp_path, monkeypatch):
    monkeypatch.setattr(checks, "available_memory_mb", lambda: 1000.0)
    out = tmp_path / "run"
    err = refused(
        cli,
        "run",
        "tiny",
        "--steps",
        "8000",
        "--envs",
        "1000",
        "--workers",
        "0",
        "--out",
        str(out),
    )
    assert "--envs 1000 needs at least 9.8 GB of memory" in err and "use --envs 100 or fewer" in err
    assert not out.exists()
    err = refused(cli, "run", "tiny", "--envs", "100000", "--steps", "1e6")
    assert "--envs 100000 needs at least" in err


def test_unusable_out_folders(cli, refused, tmp_path):
    a_file = tmp_path / "file"
    a_file.write_text("x")
    assert f"--out {a_file} is a file" in refused(cli, "run", "tiny", "--out", str(a_file))
    under = a_file / "run"
    assert f"lies under {a_file}, which is a file" in refused(
        cli, "run", "tiny", "--out", str(under)
    )
    if os.geteuid() == 0:  # root writes anywhere a mode allows nothing: use sysfs
        read_only = Path("/sys/devlearn-test-run")
        if not Path("/sys").is_dir() or os.access("/sys", os.W_OK) and _writable("/sys"):
            pytest.skip("no read-only folder available to root")
    else:
        locked = tmp_path / "locked"
        locked.mkdir()
        locked.chmod(0o555)
        read_only = locked / "run"
    err = refused(cli, "run", "tiny", "--steps", "128", "--out", str(read_only))
    assert f"--out {read_only} is not writable" in err


def _writable(folder: str) -> bool:
    try:
        with open(Path(folder) / ".devlearn-probe", "w"):
            pass
    except OSError:
        return False
    os.unlink(Path(folder) / ".devlearn-probe")
    return True


def test_a_config_json_list_is_refused(cli, refused, run_dir):
    (run_dir / "config.json").write_text("[1, 2]\n")
    err = refused(cli, "run", "tiny", "--resume", str(run_dir))
    assert "config.json is not a run config: it holds a JSON list" in err


def test_a_checkpoint_missing_keys_is_refused(cli, refused, run_dir, tmp_path):
    state = torch.load(run_dir / "checkpoint_latest.pt", weights_only=False)
    for path in run_dir.glob("checkpoint_*.pt"):
        path.unlink()
    del state["rng"], state["curriculum"]
    torch.save(state, run_dir / "checkpoint_latest.pt")
    err = refused(cli, "run", "tiny", "--resume", str(run_dir))
    assert "is incomplete: it lacks curriculum, rng" in err
    del state["actor_state_dict"]
    policy = tmp_path / "policy.pt"
    torch.save(state, policy)
    err = refused(cli, "eval", "tiny", "--checkpoint", str(policy))
    assert "is incomplete: it lacks actor_state_dict" in err


def damage(run_dir: Path, change) -> dict:
    """Apply ``change(state)`` to every checkpoint of the run (our own files: trusted here)."""
    for path in run_dir.glob("checkpoint_*.pt"):
        state = torch.load(path, weights_only=False)
        change(state)
        path.unlink()
        torch.save(state, path)
    return state


def first_tensor(state: dict, key: str) -> str:
    return next(iter(state[key]))


def nan_actor(state: dict) -> None:
    """Every actor weight NaN (what a diverged run could save)."""
    for tensor in state["actor_state_dict"].values():
        if tensor.is_floating_point():
            tensor.fill_(float("nan"))


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        (
            lambda s: s["actor_state_dict"].update(
                {first_tensor(s, "actor_state_dict"): torch.zeros(3, 3)}
            ),
            "does not fit the network its behaviour builds under its config: actor_state_dict:",
        ),
        (lambda s: s.update(iteration=-100), "is damaged: 'iteration' is -100, below 0"),
        (lambda s: s.update(env_steps=-100), "is damaged: 'env_steps' is -100, below 0"),
        (
            lambda s: s["rng"].update(numpy=("MT19937", [1, 2, 3])),
            "is damaged: 'rng' holds an unusable numpy state",
        ),
        (
            lambda s: s["rng"].update(torch=torch.zeros(7, dtype=torch.uint8)),
            "is damaged: 'rng' holds an unusable torch state",
        ),
        (lambda s: s["rng"].update(random=(3, (1, 2), None)), "unusable random state"),
        (nan_actor, "actor_state_dict: '"),
        (lambda s: s.update(iteration=True), "is damaged: 'iteration' is True, not a count"),
        (lambda s: s.update(env_steps=10**30), "is damaged: 'env_steps' is 1e+30, above 1e+12"),
    ],
)
def test_a_checkpoint_with_bad_values_is_refused_on_resume(cli, refused, run_dir, change, expected):
    damage(run_dir, change)
    before = files(run_dir)
    err = refused(cli, "run", "tiny", "--resume", str(run_dir), "--steps", "64")
    assert expected in err
    assert files(run_dir) == before


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        (
            lambda s: s["actor_state_dict"].update(
                {first_tensor(s, "actor_state_dict"): torch.zeros(3, 3)}
            ),
            "does not fit the network its behaviour builds under its config: actor_state_dict: '",
        ),
        (
            lambda s: s["actor_state_dict"].pop(first_tensor(s, "actor_state_dict")),
            "actor_state_dict: it lacks '",
        ),
        (lambda s: s["config"].update(behavior=5), "'behavior' holds 5, not a table of its fields"),
        (nan_actor, "holds NaN or infinite values"),
        (lambda s: s.update(env_steps=10**30), "is damaged: 'env_steps' is 1e+30, above 1e+12"),
        (lambda s: s["config"].update(ppo=[1]), "'ppo' holds [1], not a table of its fields"),
    ],
)
def test_a_checkpoint_with_bad_values_is_refused_on_eval(
    cli, refused, run_dir, tmp_path, change, expected
):
    damage(run_dir, change)
    out = tmp_path / "eval"
    argv = ["eval", "tiny", "--checkpoint", str(run_dir), "--episodes", "1", "--out", str(out)]
    assert expected in refused(cli, *argv)


class FullDisk:
    """``open`` on a full disk: the file is created, its first write fails."""

    def __init__(self, *args, **kwargs):
        open(*args, **kwargs).close()  # the temporary file exists, as on a real disk

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def write(self, data):
        raise OSError(errno.ENOSPC, "No space left on device")


def test_a_full_disk_before_the_first_checkpoint_says_to_start_again(
    cli, tmp_path, capsys, monkeypatch
):
    monkeypatch.setattr(checkpoint_module, "open", FullDisk, raising=False)
    out = tmp_path / "run"
    capsys.readouterr()
    assert cli(["run", "tiny", "--steps", "32", "--out", str(out), *SMALL]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert "disk full: cannot write" in err and "no checkpoint was written before it" in err
    assert "--resume" not in err and "the previous checkpoint is kept" not in err


def test_a_full_disk_is_reported_as_such(cli, run_dir, capsys, monkeypatch):
    monkeypatch.setattr(checkpoint_module, "open", FullDisk, raising=False)
    before = (run_dir / "checkpoint_latest.pt").read_bytes()
    capsys.readouterr()
    assert cli(["run", "tiny", "--resume", str(run_dir), "--steps", "64"]) == 2
    printed = capsys.readouterr().err
    err = printed.strip().splitlines()[-1]  # after the progress bar
    assert err.startswith("devlearn: error: ") and "Traceback" not in printed
    assert "disk full: cannot write" in err and "the previous checkpoint is kept" in err
    assert (run_dir / "checkpoint_latest.pt").read_bytes() == before


# --- resuming: what it keeps and what it says -----------------------------------------------


def test_resume_refuses_another_seed_and_keeps_config_json(cli, refused, run_dir):
    config = (run_dir / "config.json").read_bytes()
    for argv in (["--seed", "7"], ["--set", "seed=7"]):
        err = refused(cli, "run", "tiny", "--resume", str(run_dir), "--steps", "64", *argv)
        assert f"run {run_dir} was trained with seed 1, which a resumed run keeps" in err
        assert "--seed 7 --out NEW_DIR" in err
        assert (run_dir / "config.json").read_bytes() == config
    assert cli(["run", "tiny", "--resume", str(run_dir), "--steps", "48", "--seed", "1"]) == 0


def test_resume_says_when_it_falls_back_to_an_older_checkpoint(cli, run_dir, capsys):
    assert sorted(p.name for p in run_dir.glob("checkpoint_*.pt"))[-1] == "checkpoint_latest.pt"
    (run_dir / "checkpoint_latest.pt").unlink()
    (run_dir / "checkpoint_latest.pt").write_bytes(b"garbage")
    capsys.readouterr()
    assert cli(["run", "tiny", "--resume", str(run_dir), "--steps", "48"]) == 0
    err = capsys.readouterr().err
    assert "devlearn: warning: checkpoint " in err and "checkpoint_latest.pt is corrupt" in err
    assert "resuming from checkpoint_32.pt (step 32), the newest that loads" in err


def test_a_run_killed_before_its_first_checkpoint_says_how_to_restart(cli, refused, run_dir):
    for path in run_dir.glob("checkpoint_*.pt"):
        path.unlink()
    temporary = run_dir / ".checkpoint_latest.pt.tmp-12345"
    temporary.write_bytes(b"")  # what a kill during the first save leaves
    err = refused(cli, "run", "tiny", "--resume", str(run_dir))
    assert "the run stopped before its first checkpoint, so there is nothing to resume" in err
    assert f"start it again with --out {run_dir} --force" in err
    assert "removed 1 unfinished checkpoint file" in err and not temporary.exists()
    err = refused(cli, "run", "tiny", "--out", str(run_dir), *SMALL)
    assert "holds a run that stopped before its first checkpoint (nothing to resume)" in err
    assert "--resume" not in err
    assert cli(["run", "tiny", "--steps", "16", "--out", str(run_dir), "--force", *SMALL]) == 0


def test_a_refusal_prints_only_its_error(cli, run_dir, capsys):
    capsys.readouterr()
    assert cli(["run", "tiny", "--steps", "16", "--out", str(run_dir), *SMALL]) == 2
    printed = capsys.readouterr()
    assert printed.out == "" and "already holds a run" in printed.err


@pytest.mark.parametrize("protocol", [0, 2, 4, 5, "legacy"])
def test_a_plain_pickle_with_a_payload_is_refused_by_name(cli, refused, tmp_path, protocol):
    marker = tmp_path / "marker"
    crafted = tmp_path / "crafted.pt"
    state = {"format": "devlearn-checkpoint-1", "behavior": "tiny", "x": Payload(marker)}
    if protocol == "legacy":
        torch.save(state, crafted, _use_new_zipfile_serialization=False)
    else:
        import pickle

        crafted.write_bytes(pickle.dumps(state, protocol=protocol))
    err = refused(cli, "eval", "tiny", "--checkpoint", str(crafted), "--episodes", "1")
    assert f"checkpoint {crafted} refused: it needs builtins.exec" in err
    assert not marker.exists()


def test_failed_commands_leave_no_new_folders(cli, refused, tmp_path):
    missing = tmp_path / "runs" / "nope" / "checkpoint_latest.pt"
    err = refused(cli, "eval", "tiny", "--checkpoint", str(missing), "--episodes", "1")
    assert "does not exist" in err and not (tmp_path / "runs").exists()
    out = tmp_path / "reports" / "r"
    refused(cli, "report", str(tmp_path / "no_eval_here"), "--out", str(out))
    assert not (tmp_path / "reports").exists()
    kept = tmp_path / "kept"
    kept.mkdir()
    refused(cli, "eval", "tiny", "--checkpoint", str(missing), "--out", str(kept))
    assert kept.is_dir()  # what existed before stays


@dataclasses.dataclass
class TermsConfig(TinyConfig):
    """The tiny behaviour's options with its reward declared as a term table."""

    rewards: dict[str, devlearn.RewardTermCfg] = dataclasses.field(
        default_factory=lambda: {"reach": devlearn.RewardTermCfg(Reach, 1.0, {"target": 0.5})}
    )


class TermsBehavior(TinyBehavior):
    """The tiny behaviour with a ``rewards`` table (class, weight, params) in its config."""

    name = "terms"
    config_class = TermsConfig

    def reward_terms(self) -> Any:
        return devlearn.Behavior.reward_terms(self)


@pytest.fixture
def hostile(monkeypatch, tmp_path):
    """A module on the path whose import writes a marker: what a hostile ``cls`` names."""
    package = tmp_path / "pkg"
    package.mkdir()
    marker = tmp_path / "imported"
    (package / "evil_term.py").write_text(f"open({str(marker)!r}, 'w').write('ran')\nX = 1\n")
    monkeypatch.syspath_prepend(str(package))
    return marker


@pytest.fixture
def terms_cli(cli_with):
    return cli_with(TermsBehavior)


@pytest.fixture
def terms_run(terms_cli, tmp_path, capsys):
    return finished_run(terms_cli, "terms", tmp_path, capsys)


EVIL = "evil_term:X"
REFUSED = "behavior.rewards.reach.cls: unknown reward term class 'evil_term:X'"


def test_a_reward_term_class_named_by_set_or_config_is_never_imported(
    terms_cli, refused, hostile, tmp_path
):
    out = tmp_path / "new"
    err = refused(terms_cli, "run", "terms", "--steps", "32", "--out", str(out), *SMALL,
                "--set", f"behavior.rewards.reach.cls={EVIL}")  # fmt: skip
    assert REFUSED in err and "valid: " in err and "fake_infant:Reach" in err
    config = tmp_path / "config.json"
    config.write_text(json.dumps({"behavior": {"rewards": {"reach": {"cls": EVIL}}}}))
    err = refused(terms_cli, "run", "terms", "--config", str(config), "--out", str(out))
    assert REFUSED in err
    err = refused(terms_cli, "config", "terms", "--set", f"behavior.rewards.reach.cls={EVIL}")
    assert REFUSED in err
    assert not hostile.exists() and "evil_term" not in sys.modules and not out.exists()


def test_a_checkpoint_naming_a_reward_term_class_imports_nothing(
    terms_cli, refused, terms_run, hostile, tmp_path
):
    state = damage(
        terms_run, lambda s: s["config"]["behavior"]["rewards"]["reach"].update(cls=EVIL)
    )
    (terms_run / "config.json").write_text(json.dumps(state["config"]))
    before = files(terms_run)
    checkpoint = str(terms_run / "checkpoint_latest.pt")
    commands = [
        ["eval", "terms", "--checkpoint", checkpoint, "--episodes", "1", "--out", str(tmp_path / "e")],
        ["run", "terms", "--resume", str(terms_run), "--steps", "64"],
        ["run", "terms", "--from", checkpoint, "--out", str(tmp_path / "branch"), "--steps", "64"],
        ["export", "terms", "--checkpoint", checkpoint, "--format", "torchscript",
         "--out", str(tmp_path / "policy.ts")],
        ["slim", checkpoint, "--out", str(tmp_path / "policy.pt")],
        ["run", "terms", "--config", str(terms_run / "config.json"), "--out", str(tmp_path / "c")],
    ]  # fmt: skip
    for argv in commands:
        assert REFUSED in refused(terms_cli, *argv), argv
    assert not hostile.exists() and "evil_term" not in sys.modules
    assert files(terms_run) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pkg", "run"]  # nothing written


class _ReachHelper(Reach):
    """A private class of a plugin (as self_touch's ``_LifetimeNovelty``): registered, no term."""


class Stranger(devlearn.IntrinsicReward):
    """Another behaviour's term (as hand_to_mouth's ``MouthContact`` to self-touch): it reads a
    fact the terms behaviour never computes, and failed at step 0 after a run folder was
    written."""

    def __call__(self, ctx: devlearn.StepContext) -> float:
        return float(ctx.facts["mouth_contact"])


@pytest.mark.parametrize(
    "cls",
    [
        "devlearn.api.rewards:BatchedFromPerEnv",
        f"{__name__}:_ReachHelper",
        f"{__name__}:Stranger",
    ],
)
def test_a_term_its_behaviour_does_not_declare_is_refused_on_every_path(
    terms_cli, refused, terms_run, tmp_path, cls
):
    # issue #55, fault 3: through --set, --config, a checkpoint's config, --resume and the
    # Gymnasium env, one check (check_reward_table) refuses it before anything is written
    expected = f"behavior.rewards.reach.cls: unknown reward term class '{cls}'"
    valid = "valid: devlearn.testing.fake_infant:Reach"
    out = tmp_path / "new"
    err = refused(terms_cli, "run", "terms", "--steps", "32", "--out", str(out), *SMALL,
                  "--set", f"behavior.rewards.reach.cls={cls}")  # fmt: skip
    assert expected in err and err.endswith(valid)
    config = tmp_path / "config.json"
    config.write_text(json.dumps({"behavior": {"rewards": {"reach": {"cls": cls}}}}))
    assert expected in refused(terms_cli, "run", "terms", "--config", str(config),
                               "--out", str(out))  # fmt: skip
    config.unlink()
    state = damage(terms_run, lambda s: s["config"]["behavior"]["rewards"]["reach"].update(cls=cls))
    (terms_run / "config.json").write_text(json.dumps(state["config"]))
    before = files(terms_run)
    checkpoint = str(terms_run / "checkpoint_latest.pt")
    commands = [
        ["eval", "terms", "--checkpoint", checkpoint, "--episodes", "1", "--out", str(out)],
        ["run", "terms", "--resume", str(terms_run), "--steps", "64"],
        ["run", "terms", "--from", checkpoint, "--out", str(out), "--steps", "64"],
        ["run", "terms", "--config", str(terms_run / "config.json"), "--out", str(out)],
    ]  # fmt: skip
    for argv in commands:
        assert expected in refused(terms_cli, *argv), argv
    assert files(terms_run) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]  # nothing written
    from devlearn.gym.env import DevlearnEnv
    from devlearn.testing import registry_for

    with pytest.raises(devlearn.api.errors.UsageError, match=expected):
        DevlearnEnv("terms", {"behavior.rewards.reach.cls": cls},
                    registry=registry_for(TermsBehavior))  # fmt: skip


@pytest.mark.parametrize(
    ("config", "expected"),
    [
        ({"ppo": {"normalize_rewards": 7}}, "bad value 7 for ppo.normalize_rewards: expected bool"),
        ({"ppo": {"normalize_rewards": []}}, "bad value [] for ppo.normalize_rewards"),
        ({"ppo": {"normalize_rewards": None}}, "bad value None for ppo.normalize_rewards"),
        ({"num_envs": True}, "bad value True for num_envs: expected int"),
        ({"behavior": {"stage_steps": -5}}, "its curriculum() rejects the config: stage 'fixed'"),
        ({"behavior": {"rewards": {"reach": {"cls": Reach.__module__ + ":Reach",
                                             "params": {"target": 0.5, "nope": 1}}}}},
         "unknown parameter 'behavior.rewards.reach.params.nope' of Reach; valid: target"),
        ({"behavior": {"rewards": {"reach": {"cls": Reach.__module__ + ":Reach", "weight": 1e308,
                                             "params": {"target": 0.5}}}}},
         "behavior.rewards.reach.weight must be a finite number from -1e+06 to 1e+06"),
    ],
)  # fmt: skip
def test_config_files_with_bad_values_are_refused_before_anything_is_written(
    terms_cli, refused, tmp_path, config, expected
):
    path = tmp_path / "config.json"
    path.write_text(json.dumps(config))
    out = tmp_path / "run"
    assert expected in refused(terms_cli, "run", "terms", "--config", str(path),
                             "--out", str(out), "--steps", "32", "--envs", "2")  # fmt: skip
    assert not out.exists()


def test_a_deeply_nested_config_file_is_one_line(refused, terms_cli, tmp_path):
    path = tmp_path / "deep.json"
    path.write_text('{"a":' * 100_000 + "1" + "}" * 100_000)
    err = refused(terms_cli, "run", "terms", "--config", str(path))
    assert "its JSON is nested too deeply" in err


def test_json_a_command_is_given_is_read_with_guards(refused, cli, run_dir, tmp_path):
    # issue #55, fault 8: `--config /dev/zero` read until the OOM killer stopped it, and JSON
    # nested 100k deep was a RecursionError traceback in `eval --compare`, `report` and
    # `--set`; one guarded reader refuses each with one line
    deep = tmp_path / "deep"
    deep.mkdir()
    (deep / "eval.json").write_text("[" * 100_000 + "]" * 100_000)
    fifo = tmp_path / "fifo.json"
    os.mkfifo(fifo)
    big = tmp_path / "big.json"
    with open(big, "wb") as f:
        f.truncate(65 << 20)  # sparse: 65 MiB of zeros
    out = tmp_path / "new"
    checkpoint = str(run_dir / "checkpoint_latest.pt")
    for argv, expected in [  # what ran away on today's code last: /dev/zero, the pipe
        (["eval", "tiny", "--checkpoint", checkpoint, "--episodes", "1", "--out", str(out),
          "--compare", str(deep)], "its JSON is nested too deeply"),
        (["report", str(deep), "--out", str(out)], "its JSON is nested too deeply"),
        (["run", "tiny", "--out", str(out), "--set",
          "curiosity=" + "[" * 60_000 + "]" * 60_000], "nested too deeply"),
        (["run", "tiny", "--config", str(tmp_path), "--out", str(out)],
         f"cannot read {tmp_path}: a folder, not a file"),
        (["run", "tiny", "--config", str(big), "--out", str(out)],
         f"cannot read {big}: 68,157,440 bytes, more than the 67,108,864"),
        (["run", "tiny", "--config", str(fifo), "--out", str(out)],
         f"cannot read {fifo}: a pipe, not a file"),
        (["run", "tiny", "--config", "/dev/zero", "--out", str(out)],
         "cannot read /dev/zero: a character device, not a file"),
    ]:  # fmt: skip
        assert expected in refused(cli, *argv), argv
    assert not out.exists()


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        (nan_actor, "holds NaN or infinite values"),
        (
            lambda s: s["actor_state_dict"].update(
                {first_tensor(s, "actor_state_dict"): torch.zeros(3, 3)}
            ),
            "has shape (3, 3), the network expects",
        ),
        (
            lambda s: s["actor_state_dict"].update({first_tensor(s, "actor_state_dict"): "x"}),
            "is a str, not a tensor",
        ),
    ],
)
def test_slim_export_from_and_resume_write_nothing_from_an_unusable_checkpoint(
    cli, refused, run_dir, tmp_path, change, expected
):
    damage(run_dir, change)
    before = files(run_dir)
    checkpoint = str(run_dir / "checkpoint_latest.pt")
    commands = [
        ["slim", checkpoint, "--out", str(tmp_path / "policy.pt")],
        ["export", "tiny", "--checkpoint", checkpoint, "--format", "torchscript",
         "--out", str(tmp_path / "policy.ts")],
        ["run", "tiny", "--from", checkpoint, "--out", str(tmp_path / "branch"), "--steps", "64"],
        ["run", "tiny", "--resume", str(run_dir), "--steps", "64"],
    ]  # fmt: skip
    for argv in commands:
        assert expected in refused(cli, *argv), argv
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]  # nothing written
    assert files(run_dir) == before  # config.json included


def test_export_to_an_unusable_place_is_one_line_and_leaves_nothing(
    cli, refused, run_dir, tmp_path, monkeypatch
):
    checkpoint = str(run_dir / "checkpoint_latest.pt")
    base = ["export", "tiny", "--checkpoint", checkpoint, "--format", "torchscript", "--out"]
    err = refused(cli, *base, str(tmp_path))
    assert f"--out {tmp_path} is a folder; give the file to write" in err
    err = refused(cli, *base, str(tmp_path / "missing" / "p.ts"))
    assert "does not exist" in err
    if os.geteuid() == 0 and Path("/sys").is_dir() and not _writable("/sys"):
        assert "cannot write /sys/p.ts: " in refused(cli, *base, "/sys/p.ts")
    full = tmp_path / "full"
    full.mkdir()
    real_fsync = os.fsync

    def no_space(fd):  # the bytes written so far stay in the file, as a full disk leaves them
        if os.fstat(fd).st_size:
            raise OSError(errno.ENOSPC, "No space left on device")
        real_fsync(fd)

    monkeypatch.setattr(os, "fsync", no_space)  # the policy is written by Python (issue #55)
    err = refused(cli, *base, str(full / "p.ts"))
    assert err.endswith(f"cannot write {full / 'p.ts'}: No space left on device")
    assert list(full.iterdir()) == []  # no partial file


def test_an_obfuscated_pickle_is_refused_naming_what_it_computes(cli, refused, tmp_path):
    obfuscated = tmp_path / "obf.pt"  # the module's name comes from a call: str('os')
    obfuscated.write_bytes(
        b"\x80\x04\x8c\x08builtins\x94\x8c\x03str\x94\x93\x94\x8c\x02os\x94\x85\x94R\x94"
        b"\x8c\x06system\x94\x93\x94\x8c\x04echo\x94\x85\x94R\x94."
    )
    err = refused(cli, "eval", "tiny", "--checkpoint", str(obfuscated))
    assert "refused: it needs <computed at load time>.system, builtins.str" in err
    assert "None." not in err


def test_a_fifo_or_a_link_loop_is_named_as_such(cli, refused, tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    loop = tmp_path / "loop1"
    loop.symlink_to(tmp_path / "loop2")
    (tmp_path / "loop2").symlink_to(loop)
    dangling = tmp_path / "dangling"
    dangling.symlink_to(tmp_path / "gone.pt")
    cases = {
        fifo: "is a FIFO, not a checkpoint file",
        loop: "is a symbolic link loop",
        dangling: f"is a symbolic link to a missing file ({tmp_path / 'gone.pt'})",
        tmp_path / "nothing.pt": "does not exist",
    }
    for path, expected in cases.items():
        assert f"checkpoint {path} {expected}" in refused(cli, "eval", "tiny",
                                                        "--checkpoint", str(path))  # fmt: skip


def test_argparse_errors_are_one_line(cli, capsys):
    with pytest.raises(SystemExit) as stop:
        cli(["eval", "tiny", "--start", "nowhere"])
    assert stop.value.code == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("devlearn: error: argument --start: invalid choice: 'nowhere'")
    assert "\n" not in err and err.endswith("(see `devlearn eval --help`)")


def test_a_start_up_failure_prints_only_its_error(cli, run_dir, capsys):
    """A checkpoint that fails while the run is built (its weights, restored after every
    config check) is one line on stderr, and stdout says nothing (no 'run directory')."""
    damage(run_dir, nan_actor)
    capsys.readouterr()
    assert cli(["run", "tiny", "--resume", str(run_dir), "--steps", "64"]) == 2
    printed = capsys.readouterr()
    assert printed.out == ""
    assert printed.err.strip().count("\n") == 0 and "NaN or infinite" in printed.err
