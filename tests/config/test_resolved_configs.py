"""Every way a command gets a run's config resolves to the config it resolved to before issue
#59 reworked resolution into one pipeline: the resolved dicts (or the error messages) of a
representative set of requests, recorded in ``data/resolved_configs.json`` and compared key by
key.

The requests: every installed behaviour's defaults and presets, ``--steps`` (short and long:
the run-length defaults), ``--set`` (one of them a key the run-length defaults would set), the
top-level options and ``--out``, ``--config FILE`` (an empty file, a partial one, a run's own
``config.json``, a legacy saved config), ``eval``'s baselines, ``--resume`` of every shape of
saved run under ``results/`` (legacy configs lacking the fields of ``LEGACY_FIELDS`` among
them; a growing run resumed over other steps), ``--from`` a checkpoint's config, and the config
``devlearn eval`` reads from every published policy; and the requests refused, with their
messages.

Record (only when a change is meant to alter resolved configs):
``python tests/config/test_resolved_configs.py`` rewrites the data file.
"""

from __future__ import annotations

import json
import shutil
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from devlearn.api.errors import UsageError
from devlearn.config.resolve import RunRequest, load_run_config, resolve_run, write_config_file
from devlearn.config.run_config import RunConfig, from_dict, to_dict
from devlearn.evaluation.evaluate import baseline_config
from devlearn.plugins import PluginRegistry

ROOT = Path(__file__).resolve().parents[2]
DATA = Path(__file__).parent / "data" / "resolved_configs.json"
sys.path.insert(0, str(ROOT / "tests"))

from published_policies import published_policies  # noqa: E402

BEHAVIORS = ("hand_regard", "hand_to_mouth", "self_touch")
"""The installed behaviours (the core's two plugins and the example)."""
SAVED = (
    "results/growth/i41_pilot/fixed18/seed=1/config.json",
    "results/growth/i41_pilot/grow6to18/seed=1/config.json",
    "results/hand_regard/i29/forward_model/seed=1/config.json",
    "results/hand_regard/i39/paper/seed=1/config.json",
    "results/hand_regard/i39_pilot/bilateral/seed=1/config.json",
    "results/hand_regard/i39_pilot/reach/seed=1/config.json",
    "results/hand_regard/run/config.json",
    "results/learner/final/defaults_2M/seed=1/config.json",
    "results/learners/i54/proof/devlearn_ppo/seed=1/config.json",
    "results/plugins/hand_to_mouth/core_defaults/seed=1/config.json",
    "results/plugins/i54/hand_to_mouth/core_defaults/seed=1/config.json",
    "results/self_touch/ablation/ablation_fixed_only/config.json",
    "results/self_touch/i20/two_stage_s1/run/config.json",
    "results/self_touch/i30/ablation/fixed_only/seed=1/config.json",
    "results/self_touch/i43/ablation_8M/fixed_only/seed=1/config.json",
    "results/self_touch/max_std/run/config.json",
)
"""One saved config of each shape under ``results/`` (behaviour and the set of keys it holds)
whose behaviour is installed: the oldest lack ``network``, ``env`` and the learner fields
(``LEGACY_FIELDS``), or hold reward weights from before issue #31's reward terms."""

Result = dict[str, Any]


def flat(data: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """``{"ppo.gamma": 0.99, ...}``: a config dict by dotted key (a non-empty table is
    opened, lists and values kept)."""
    out: dict[str, Any] = {}
    for key, value in data.items():
        if isinstance(value, dict) and value:
            out.update(flat(value, f"{prefix}{key}."))
        else:
            out[prefix + key] = value
    return out


def config_result(cfg: RunConfig, notes: list[str] | None = None) -> Result:
    """A resolved config as recorded: by dotted key, with the notes resolving printed."""
    return {"config": flat(to_dict(cfg)), "notes": list(notes or [])}


def requests(tmp: Path) -> dict[str, Callable[[], Result]]:
    """Every recorded request by name, each a call that resolves it (files it reads are
    written under ``tmp``)."""
    registry = PluginRegistry(disabled=())

    def shown(text: str) -> str:
        return text.replace(str(tmp), "TMP").replace(str(ROOT), "ROOT")

    def checkpoint_reader(path: str, registry: PluginRegistry, behavior: str) -> RunConfig:
        """``--from``'s reader, on a saved config instead of a checkpoint file: what the
        pipeline does with the config a checkpoint holds (the checkpoint's own reading is
        recorded by the ``eval checkpoint`` requests)."""
        data = json.loads(Path(path).read_text())
        return from_dict(data, registry.behavior(behavior or data["behavior_name"]))

    def resolve(**fields: Any) -> Callable[[], Result]:
        def run() -> Result:
            try:
                resolved = resolve_run(RunRequest(**fields), registry, checkpoint_reader)
            except UsageError as err:
                return {"error": shown(str(err))}
            result = config_result(resolved.cfg, [shown(note) for note in resolved.notes])
            for key in ("out_dir", "start_from"):  # paths: where this test's files lie
                result["config"][key] = shown(result["config"][key])
            return result

        return run

    def file(name: str, data: dict[str, Any]) -> str:
        path = tmp / name
        path.write_text(json.dumps(data))
        return str(path)

    def run_folder(name: str, source: Path) -> str:
        folder = tmp / "runs" / name
        folder.mkdir(parents=True)
        shutil.copy(source, folder / "config.json")
        return str(folder)

    found: dict[str, Callable[[], Result]] = {}
    for name in BEHAVIORS:
        cls = registry.behavior(name)
        found[f"{name} defaults"] = resolve(behavior=name)
        for preset in cls.about.presets:
            found[f"{name} --preset {preset}"] = resolve(behavior=name, preset=preset)
            found[f"{name} --preset {preset} --steps 2e6"] = resolve(
                behavior=name, preset=preset, top={"total_steps": 2_000_000}
            )
        for steps in (20_000, 8_000_000):
            found[f"{name} --steps {steps}"] = resolve(behavior=name, top={"total_steps": steps})
        found[f"{name} options"] = resolve(
            behavior=name,
            top={"num_envs": 4, "workers": 0, "seed": 3, "device": "cpu", "logger": None},
            out_dir="runs/x",
        )
        found[f"{name} --set"] = resolve(
            behavior=name,
            overrides=["ppo.learning_rate=1e-3", "seed=7", "network.head=gaussian"],
            top={"seed": 4},
        )
        found[f"{name} --set env.action_repeat=1 infant.growth"] = resolve(
            behavior=name,
            overrides=["env.action_repeat=1", "infant.growth=6->18"],
            top={"total_steps": 480_000},
        )
        found[f"{name} --config empty"] = resolve(
            behavior=name, config_file=file(f"{name}_empty.json", {}), top={"seed": 2}
        )
        found[f"{name} --config partial"] = resolve(
            behavior=name,
            config_file=file(f"{name}_partial.json", {"behavior_name": name, "ppo": {"lam": 0.9}}),
            overrides=["ppo.gamma=0.98"],
            top={"total_steps": 64_000},
            out_dir="runs/y",
        )
        default = resolve_run(RunRequest(name), registry).cfg
        written = write_config_file(default, tmp / f"{name}_run_config.json")
        found[f"{name} --config run_config.json"] = resolve(
            behavior=name, config_file=str(written), overrides=["seed=2"]
        )
        found[f"{name} eval baseline"] = lambda name=name: config_result(
            baseline_config(name, [], registry)
        )
        found[f"{name} eval baseline --set"] = lambda name=name: config_result(
            baseline_config(name, ["infant.age_months=6", "env.action_repeat=2"], registry)
        )
        found[f"{name} --from"] = resolve(
            behavior=name,
            start_from=str(written),
            preset=next(iter(cls.about.presets), ""),
            top={"seed": 9},
            overrides=["ppo.lam=0.9", "out_dir=ignored"],
            out_dir="runs/branch",
        )
    touch = "self_touch"
    found["self_touch --steps 8e6 --set behavior.fixed_pose_steps"] = resolve(
        behavior=touch,
        overrides=["behavior.fixed_pose_steps=1234"],
        top={"total_steps": 8_000_000},
    )
    found["self_touch --preset paper --set behavior.random_pose_steps"] = resolve(
        behavior=touch, preset="paper", overrides=["behavior.random_pose_steps=99"]
    )
    found["self_touch --set curiosity"] = resolve(
        behavior=touch, overrides=["curiosity=rnd", "learned.rnd.weight=0.5"]
    )
    found["self_touch --set reward term"] = resolve(
        behavior=touch, overrides=["behavior.rewards.balance.weight=0.7"]
    )
    for path in SAVED:
        source = ROOT / path
        label = path.removeprefix("results/").removesuffix("/config.json")
        data = json.loads(source.read_text())
        behavior = data["behavior_name"]
        folder = run_folder(label.replace("/", "_"), source)
        found[f"saved {label}: read"] = lambda folder=folder: config_result(
            load_run_config(folder, registry)
        )
        found[f"saved {label}: --resume"] = resolve(resume=folder)
        found[f"saved {label}: --resume --steps --set"] = resolve(
            resume=folder,
            top={"total_steps": 2 * int(data["total_steps"]), "num_envs": 2},
            overrides=["ppo.learning_rate=1e-4"],
        )
        found[f"saved {label}: --config"] = resolve(behavior=behavior, config_file=str(source))
        found[f"saved {label}: as data"] = resolve(behavior=behavior, saved=data)
        found[f"saved {label}: --from"] = resolve(
            behavior=behavior, start_from=str(source), top={"seed": 11}
        )
    grow = run_folder("grow", ROOT / SAVED[1])
    found["saved growth: --resume another schedule"] = resolve(
        resume=grow, overrides=["infant.growth=6->12"]
    )
    found["saved growth: --resume --seed"] = resolve(resume=grow, top={"seed": 12345})
    for policy in published_policies():
        label = str(policy.relative_to(ROOT / "results").parent)
        found[f"eval checkpoint {label}"] = lambda policy=policy: _checkpoint(policy, registry)
    refused = {
        "unknown behaviour": {"behavior": "self_tuch"},
        "unknown preset": {"behavior": touch, "preset": "nope"},
        "unknown key": {"behavior": touch, "overrides": ["ppo.lr=1"]},
        "bad value": {"behavior": touch, "overrides": ["ppo.gamma=2"]},
        "bad head": {"behavior": touch, "overrides": ["network.head=tanh"]},
        "not key=value": {"behavior": touch, "overrides": ["seed"]},
        "a recorded-only key": {"behavior": touch, "overrides": ["preset=paper"]},
        "--resume --preset": {"resume": "r", "preset": "paper"},
        "--resume --from": {"resume": "r", "start_from": "c.pt"},
        "--resume --out": {"resume": "r", "out_dir": "o"},
        "--from --config": {"start_from": "c.pt", "config_file": "f.json"},
        "--config --preset": {"config_file": "f.json", "preset": "paper"},
        "--resume missing": {"resume": str(tmp / "no_run")},
        "--config missing": {"behavior": touch, "config_file": str(tmp / "no.json")},
        "--config of another behaviour": {
            "behavior": "hand_regard",
            "config_file": file("touch.json", {"behavior_name": touch}),
        },
        "--steps 0": {"behavior": touch, "top": {"total_steps": 0}},
    }
    for label, fields in refused.items():
        found[f"refused: {label}"] = resolve(**fields)
    return found


def _checkpoint(policy: Path, registry: PluginRegistry) -> Result:
    """The config ``devlearn eval`` reads from a published policy file."""
    from devlearn.training.checkpoint import Checkpoint

    return config_result(Checkpoint.open(policy, registry).config)


def record(results: dict[str, Result]) -> dict[str, Any]:
    """The data file's form: each behaviour's defaults in full, every other config as the keys
    in which it differs from its behaviour's defaults (``changed``, ``removed``)."""
    bases = {
        name: results[f"{name} defaults"]["config"]
        for name in BEHAVIORS
        if "config" in results[f"{name} defaults"]
    }
    cases: dict[str, Any] = {}
    for label, result in results.items():
        if "config" not in result:
            cases[label] = result
            continue
        config = result["config"]
        base = bases.get(config.get("behavior_name"), {})
        cases[label] = {
            "base": config.get("behavior_name") if base else None,
            "changed": {k: v for k, v in config.items() if k not in base or base[k] != v},
            "removed": sorted(k for k in base if k not in config),
            "notes": result["notes"],
        }
    return {"bases": bases, "cases": cases}


def expected(data: dict[str, Any], label: str) -> Result:
    """The recorded result of ``label``, rebuilt from :func:`record`'s form."""
    case = data["cases"][label]
    if "error" in case:
        return case
    config = dict(data["bases"][case["base"]]) if case["base"] else {}
    for key in case["removed"]:
        config.pop(key)
    config.update(case["changed"])
    return {"config": config, "notes": case["notes"]}


@pytest.fixture(scope="module")
def resolved(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Result]:
    tmp = tmp_path_factory.mktemp("resolved")
    return {label: resolve() for label, resolve in requests(tmp).items()}


@pytest.fixture(scope="module")
def recorded() -> dict[str, Any]:
    return json.loads(DATA.read_text())


def test_the_same_requests_are_resolved(resolved, recorded):
    assert sorted(resolved) == sorted(recorded["cases"])


def test_every_request_resolves_as_recorded(resolved, recorded):
    changed = {}
    for label, result in resolved.items():
        if label not in recorded["cases"]:
            continue
        want = expected(recorded, label)
        if result != want:
            if "config" in result and "config" in want:
                keys = set(result["config"]) | set(want["config"])
                diff = {
                    k: (want["config"].get(k, "<absent>"), result["config"].get(k, "<absent>"))
                    for k in sorted(keys)
                    if want["config"].get(k, "<absent>") != result["config"].get(k, "<absent>")
                }
                changed[label] = diff or {"notes": (want["notes"], result["notes"])}
            else:
                changed[label] = (want, result)
    assert not changed, json.dumps(changed, indent=1, default=str)


def test_the_record_covers_what_the_brief_names(recorded):
    """The record is no empty file: configs for every path, errors for the refusals."""
    cases = recorded["cases"]
    assert set(recorded["bases"]) == set(BEHAVIORS)
    for path in ("--preset", "--steps", "--set", "--config", "--resume", "--from", "eval"):
        assert any(path in label and "error" not in cases[label] for label in cases), path
    legacy = [cases[f"saved {p[8:-12]}: read"] for p in SAVED]
    assert any(case["changed"].get("network.head") == "paper" for case in legacy)
    assert sum("error" in case for case in cases.values()) >= 16


if __name__ == "__main__":
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        results = {label: resolve() for label, resolve in requests(Path(folder)).items()}
    DATA.parent.mkdir(exist_ok=True)
    DATA.write_text(json.dumps(record(results), indent=1, sort_keys=True) + "\n")
    print(f"wrote {len(results)} requests to {DATA.relative_to(ROOT)}")
