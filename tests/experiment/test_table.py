"""devlearn experiment table's --metric: any eval.json number, per protocol, over seeds."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from devlearn.api.errors import UsageError
from devlearn.experiment.table import experiment_table, markdown, metric_value

SPEC = """\
name = "made_up"
behavior = "self_touch"
seeds = [1, 2, 3]
baselines = ["zero"]

[[arms]]
name = "a"

[[arms]]
name = "b"

[[protocols]]
name = "random_mean"
episodes = 2
seed = 0
"""
TOUCHES = {"a": {1: 10.0, 2: 14.0, 3: 21.0}, "b": {1: 3.0, 2: 5.0}}
"""Touches per minute by arm and seed; b's seed 3 has no evaluation, its seed 2 no likeness."""


def _write(path: Path, data: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data))


@pytest.fixture
def dest(tmp_path: Path) -> Path:
    """A publication in devlearn experiment publish's layout, written by hand."""
    (tmp_path / "experiment.toml").write_text(SPEC)
    _write(tmp_path / "experiment.json", {"published": "now", "headline_metric": "score"})
    for arm, seeds in TOUCHES.items():
        for seed, touches in seeds.items():
            summary = {"score": 0.1 * seed, "likeness": {"touches_per_minute": touches}}
            if (arm, seed) == ("b", 2):
                summary["likeness"] = {"touches_per_minute": None}
            _write(tmp_path / arm / f"seed={seed}" / "eval_random_mean" / "eval.json", summary)
    zero = {"score": 0.0, "likeness": {"touches_per_minute": 38.25}}
    _write(tmp_path / "baseline_zero" / "eval_random_mean" / "eval.json", zero)
    return tmp_path


def test_a_metric_is_tabulated_over_the_seeds_that_report_it(dest):
    table = experiment_table(dest, ["likeness.touches_per_minute"])
    (protocol,) = table["protocols"]
    metrics = protocol["metrics"]
    a, b = metrics["arms"]
    values = list(TOUCHES["a"].values())
    x = np.asarray(values)
    half = stats.t.ppf(0.975, 2) * x.std(ddof=1) / np.sqrt(3)
    figures = a["metrics"]["likeness.touches_per_minute"]
    assert figures["n"] == 3 and figures["seeds"] == {"1": 10.0, "2": 14.0, "3": 21.0}
    assert (figures["mean"], figures["ci_low"], figures["ci_high"]) == pytest.approx(
        (x.mean(), x.mean() - half, x.mean() + half)
    )
    only = b["metrics"]["likeness.touches_per_minute"]  # seed 2 reports none, seed 3 is missing
    assert only["n"] == 1 and only["mean"] == 3.0 and only["ci_low"] is None
    assert metrics["baselines"] == [
        {"baseline": "zero", "metrics": {"likeness.touches_per_minute": 38.25}}
    ]
    lines = markdown(table).splitlines()
    at = lines.index("| policy | seeds | likeness.touches_per_minute |")
    low, high = x.mean() - half, x.mean() + half
    assert lines[at + 2] == f"| a | 3 | {x.mean():.4g} [{low:.4g}, {high:.4g}] |"
    assert lines[at + 3] == "| b | 1 | 3 |"
    assert lines[at + 4] == "| zero actions (baseline) | - | 38.25 |"


def test_without_metrics_the_tables_are_the_headline_only(dest):
    table = experiment_table(dest)
    assert "metrics" not in table["protocols"][0]
    assert "likeness" not in markdown(table)


def test_a_metric_no_evaluation_has_is_refused_naming_it(dest):
    with pytest.raises(UsageError, match="--metric likeness.touches: no evaluation"):
        experiment_table(dest, ["likeness.touches"])


def test_metric_value_reads_dotted_numbers_only():
    summary = {"a": {"b": 2, "flag": True, "text": "x"}, "c": 1.5}
    assert metric_value(summary, "a.b") == 2.0 and metric_value(summary, "c") == 1.5
    assert metric_value(summary, "a.flag") is None and metric_value(summary, "a.text") is None
    assert metric_value(summary, "a.b.c") is None and metric_value(None, "c") is None


REFERENCES = """
[[references]]
source = "DiMercurio et al. 2018, abstract"
rows = [{ label = "infants, 3-9 weeks", metrics = { "likeness.touches_per_minute" = "<= 40" } }]

[[references]]
source = "the paper"
rows = [{ label = "model", value = 0.5 }]
"""


def test_a_reference_row_gives_metric_figures_as_its_source_words_them(dest):
    (dest / "experiment.toml").write_text(SPEC + REFERENCES)
    table = experiment_table(dest, ["likeness.touches_per_minute"])
    lines = markdown(table).splitlines()
    at = lines.index("| policy | seeds | likeness.touches_per_minute |")
    # the infants' row carries no headline value: only the --metric table shows it
    assert lines[at + 5] == "| infants, 3-9 weeks (reference [2]) | - | <= 40 |"
    assert not any(line.startswith("| infants") for line in lines[:at])
    assert any(line.startswith("| model (reference [1]) | - | 0.5 |") for line in lines[:at])
    assert lines[-1] == "- [2] DiMercurio et al. 2018, abstract"
    # without --metric the metrics-only row is not a headline row
    assert "infants" not in markdown(experiment_table(dest))


def test_a_reference_row_needs_a_value_or_metrics(dest):
    (dest / "experiment.toml").write_text(
        SPEC + '[[references]]\nsource = "x"\nrows = [{ label = "y" }]\n'
    )
    with pytest.raises(UsageError, match="value"):
        experiment_table(dest)


LATER = SPEC.replace("seeds = [1, 2, 3]", "seeds = [4, 5]").replace(
    '[[arms]]\nname = "b"\n', '[[arms]]\nname = "c"\n'
)
"""A later experiment: arm a's seeds 4-5 under the same protocol, and an arm c of its own."""


@pytest.fixture
def later(tmp_path: Path, dest: Path) -> Path:
    folder = tmp_path / "later"
    folder.mkdir()
    (folder / "experiment.toml").write_text(LATER)
    _write(folder / "experiment.json", {"published": "later", "headline_metric": "score"})
    for arm, scores in {"a": {4: 0.9, 5: 0.2}, "c": {4: 0.5, 5: 0.6}}.items():
        for seed, score in scores.items():
            _write(
                folder / arm / f"seed={seed}" / "eval_random_mean" / "eval.json", {"score": score}
            )
    return folder


def test_publications_pool_an_arms_seeds(dest, later):
    table = experiment_table([dest, later])
    (protocol,) = table["protocols"]
    rows = {row["arm"]: row for row in protocol["arms"]}
    assert list(rows) == ["a", "b", "c"]
    values = [0.1, 0.2, 0.30000000000000004, 0.9, 0.2]
    assert rows["a"]["seeds"] == dict(zip(["1", "2", "3", "4", "5"], values))
    assert rows["a"]["n"] == 5 and rows["a"]["mean"] == pytest.approx(np.mean(values))
    assert rows["c"]["n"] == 2 and rows["b"]["n"] == 2
    assert table["seeds"] == [1, 2, 3, 4, 5] and table["publications"] == [str(dest), str(later)]
    assert "Pooled publications" in markdown(table)
    # the first publication alone is unchanged
    alone = experiment_table(dest)["protocols"][0]["arms"][0]
    assert alone["n"] == 3 and "publications" not in experiment_table(dest)


def test_versus_gives_the_paired_difference_over_common_seeds(dest, later):
    table = experiment_table([dest, later], versus="c")
    rows = {row["arm"]: row for row in table["protocols"][0]["arms"]}
    paired = rows["a"]["paired"]  # a and c share seeds 4 and 5: 0.9 - 0.5, 0.2 - 0.6
    x = np.array([0.4, -0.4])
    half = stats.t.ppf(0.975, 1) * x.std(ddof=1) / np.sqrt(2)
    assert paired["seeds"] == ["4", "5"] and paired["n"] == 2
    assert (paired["mean"], paired["ci_high"]) == pytest.approx((0.0, half))
    assert rows["b"]["paired"]["n"] == 0 and rows["c"]["paired"] is None
    assert "paired with c (same seeds)" in markdown(table)
    with pytest.raises(UsageError, match="--versus d: no such arm"):
        experiment_table([dest, later], versus="d")


def test_an_arm_trained_otherwise_or_a_seed_twice_is_refused(dest, later):
    (later / "experiment.toml").write_text(
        LATER.replace('name = "a"\n', 'name = "a"\nset = ["ppo.learning_rate=1e-3"]\n')
    )
    with pytest.raises(UsageError, match="arm a in .* is not the arm of the same name"):
        experiment_table([dest, later])
    (later / "experiment.toml").write_text(LATER.replace("seeds = [4, 5]", "seeds = [3, 4]"))
    with pytest.raises(UsageError, match="arm a seed 3 is in both"):
        experiment_table([dest, later])
    (later / "experiment.toml").write_text(LATER.replace("episodes = 2", "episodes = 3"))
    with pytest.raises(UsageError, match="protocol random_mean is"):
        experiment_table([dest, later])


def test_resolved_configs_that_agree_pool_arms_whose_files_differ(dest, later):
    """Issue #54's proof was published before its file named the fixed-pose stage that was
    then the default: its runs' resolved configs say they trained alike."""
    (later / "experiment.toml").write_text(
        LATER.replace('name = "a"\n', 'name = "a"\nset = ["x=1"]\n')
    )
    for folder, seed in ((dest, 1), (later, 4)):
        _write(folder / "a" / f"seed={seed}" / "config.json", {"seed": seed, "ppo": {"lr": 1}})
    assert experiment_table([dest, later])["protocols"][0]["arms"][0]["n"] == 5
    _write(later / "a" / "seed=4" / "config.json", {"seed": 4, "ppo": {"lr": 2}})
    with pytest.raises(UsageError, match=r"resolved config differs in 1 key\(s\) \(ppo.lr: 2"):
        experiment_table([dest, later])
    # a reader may declare a key that does not decide the numbers (an outside learner's unused
    # network settings): the arms pool, and the table says which keys were not compared
    table = experiment_table([dest, later], ignore_config=["ppo"])
    assert table["protocols"][0]["arms"][0]["n"] == 5 and table["ignored_config"] == ["ppo"]
    assert "Resolved configs compared without: ppo." in markdown(table)
    with pytest.raises(UsageError, match="ppo.lr"):
        experiment_table([dest, later], ignore_config=["pp"])  # a section, not a prefix
