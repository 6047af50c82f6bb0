"""Every ``devlearn`` sub-command declared once, in one table: its name, help, description and
options. An option several commands share (the behaviour, ``--set``, ``--preset``, ``--envs``...)
is declared once in ``SHARED``; a command names it and gives only what differs there (its help).

Building the parser from this table imports no command module, so ``devlearn --help`` stays
cheap; a command's module (``devlearn/cli/<module>.py``, with ``run(args, registry) -> int``) is
imported only when that command runs.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any


@dataclass(frozen=True)
class Option:
    """One ``add_argument`` call: the flags (or a positional's name) and its keyword arguments."""

    flags: tuple[str, ...]
    kwargs: dict[str, Any]


class OneOf:
    """Options of which a command takes at most one (exactly one when ``required``)."""

    def __init__(self, *options: Option, required: bool = False) -> None:
        self.options = options
        self.required = required


class Command:
    """A sub-command, written as argparse takes it: its name, its options in the order its
    help lists them, what ``devlearn --help`` (``help``) and ``devlearn NAME --help``
    (``description``) say, and the module whose ``run(args, registry)`` it calls
    (``devlearn/cli/<module>.py``; by default the command's name). A command with
    ``actions`` (``devlearn experiment run|publish|table``) takes one of them next, each a
    Command of its own options; the module's ``run`` finds it in ``args.action``."""

    def __init__(
        self,
        name: str,
        *options: Option | OneOf,
        help: str,
        description: str | None = None,
        module: str = "",
        actions: tuple[Command, ...] = (),
    ) -> None:
        self.name = name
        self.options = options
        self.help = help
        self.description = description
        self.module = f"devlearn.cli.{module or name}"
        self.actions = actions


SET_HELP = "override a config field, e.g. ppo.learning_rate=3e-4 (repeatable)"
PRESET_HELP = (
    "start from a named set of the behaviour's values (e.g. paper); "
    "`devlearn config BEHAVIOR` lists them"
)
SHARED: dict[str, dict[str, Any]] = {
    "behavior": {"help": "behaviour name (see `devlearn plugins`)"},
    "--set": {
        "dest": "overrides",
        "action": "append",
        "default": [],
        "metavar": "KEY=VALUE",
        "help": SET_HELP,
    },
    "--preset": {"metavar": "NAME", "help": PRESET_HELP},
    "--steps": {"metavar": "N"},
    "--envs": {"metavar": "N"},
    "--workers": {"metavar": "N"},
    "--seed": {"metavar": "S"},
    "--episodes": {"metavar": "N"},
    "--json": {"action": "store_true"},
    "--out": {"metavar": "DIR"},
}
"""What every command that takes one of these options gives it, by flag (a command's own
keyword arguments, usually its help, win)."""


def option(*flags: str, **kwargs: Any) -> Option:
    """An option as ``add_argument(*flags, **kwargs)`` takes it, over what ``SHARED`` declares
    for its first flag."""
    return Option(flags, {**SHARED.get(flags[0], {}), **kwargs})


REPORT_ROWS_SHOWN = 12
"""Metric rows `devlearn report` prints without ``--full`` (the headline first)."""

BEHAVIOR = option("behavior")

COMMANDS: tuple[Command, ...] = (
    Command(
        "run",
        BEHAVIOR,
        option("--steps", help="total environment steps (e.g. 8e6)"),
        option("--envs", help="environments per process"),
        option(
            "--workers",
            help="environment worker processes (0: in process; default -1: one per core)",
        ),
        option("--seed", help="random seed"),
        option("--out", help="run directory (default runs/BEHAVIOR-TIME)"),
        option("--device", metavar="DEV", help="cpu or cuda (default cpu)"),
        option(
            "--logger",
            choices=("tensorboard", "wandb"),
            help="also log to W&B (default tensorboard)",
        ),
        option("--set"),
        option("--preset"),
        option("--resume", metavar="RUN_DIR", help="continue a run from its latest checkpoint"),
        option(
            "--from",
            dest="start_from",
            metavar="CHECKPOINT",
            help="""start a new run (in --out) from another run's checkpoint: its config
            (changed by --set and the options above), weights, optimiser, step count and env
            memory""",
        ),
        option(
            "--config",
            metavar="FILE",
            help="""start a new run from a resolved config file (a run's config.json, a sweep's
            run_config.json), changed by --set and the options above""",
        ),
        option(
            "--force",
            action="store_true",
            help="""with --out: replace the run that DIR holds (deletes what DIR holds once the
            new run has started); without it such a folder is refused""",
        ),
        help="train a behaviour with PPO",
        description="""Train a behaviour; writes config.json, checkpoints, metrics.jsonl and
        TensorBoard logs to the run directory. Ctrl-C or SIGTERM saves a checkpoint; --resume
        continues.""",
    ),
    Command(
        "eval",
        BEHAVIOR,
        OneOf(
            option(
                "--checkpoint",
                metavar="PATH",
                help="""checkpoint or policy file (.pt), or a run folder (its
                checkpoint_latest.pt)""",
            ),
            option(
                "--policy",
                choices=("zero", "random", "held_random"),
                help="""baseline instead of a checkpoint: zero action, uniform random in [-1, 1]
                every step, or held_random (uniform random actions held ~8 steps, as babbling)""",
            ),
            required=True,
        ),
        option("--episodes", default="10", help="episodes to run (default 10)"),
        option("--seed", default="0", help="seed of the initial poses"),
        option(
            "--envs",
            help="""environments playing episodes at once (default: 4 per worker, 1 without
            workers); the results are those of one environment playing every episode in order""",
        ),
        option(
            "--workers",
            help="""worker processes the environments are split over (0: this process; default:
            one per core when there are episodes enough to repay their start-up)""",
        ),
        option(
            "--start",
            choices=("stage", "babybench", "rest", "random"),
            default="stage",
            help="""where episodes start: stage (default): the behaviour's evaluation protocol
            (self_touch: seeded random poses; hand_regard: babybench), or for a behaviour that
            declares none, the curriculum stage where the policy trained; babybench (the scene's
            settled state + 10 seeded random-action steps, as BabyBench's reset); rest (that
            state alone, every episode: a deterministic policy then repeats one episode); random
            (random joint angles: generalisation)""",
        ),
        option(
            "--session",
            metavar="SECONDS",
            help="""play every episode as one session of SECONDS simulated seconds, without a
            reset inside (e.g. --session 300 --start rest: the 5-minute sessions from rest that
            infant studies code); default: the behaviour's episodes (5 s). eval.json records it
            as protocol.session_s, and its per-episode figures are then per session""",
        ),
        option(
            "--action",
            choices=("mean", "sample", "expected_clipped"),
            default="mean",
            help="""a checkpoint's action: mean (deterministic, default), sample (drawn from
            the policy's distribution, seeded by --seed, as in training) or expected_clipped
            (deterministic: the action the env applies on average when the policy samples,
            E[clip(mean + std * noise, -1, 1)])""",
        ),
        option(
            "--set",
            help="""a baseline's config value, e.g.
            behavior.detector_file=runs/hr/hand_detector.json (hand regard's baselines then
            score with a calibrated detector); repeatable. With a checkpoint only
            infant.age_months=A: the body's age (0-24 months; default: the age it last trained
            at), written to eval_A_months/ unless --out""",
        ),
        option("--json", help="print every figure as JSON (eval.json's content)"),
        option(
            "--compare",
            action="append",
            default=[],
            metavar="DIR",
            help="""a baseline's evaluation folder to show beside the headline (repeatable;
            default: eval_BEHAVIOR_zero / _random / _held_random here, when they exist)""",
        ),
        option(
            "--video",
            metavar="PATH",
            help="write the first episode as a video (.mp4, .mkv, .mov or .avi)",
        ),
        option(
            "--out",
            help="""output directory (default CHECKPOINT_DIR/eval; baselines:
            eval_BEHAVIOR_POLICY)""",
        ),
        help="evaluate a trained checkpoint or a baseline policy",
        module="evaluate",
        description="""Run episodes in the behaviour's evaluation stage (a checkpoint's mean
        action, or a zero / uniform-random / held-random baseline under the same protocol);
        writes eval.json (with the protocol) and the behaviour's pictures to --out.""",
    ),
    Command(
        "info",
        BEHAVIOR,
        option("--json", help="print a JSON object"),
        help="describe a behaviour's observations, actions, skin",
    ),
    Command(
        "config",
        BEHAVIOR,
        option("--json", help="print a JSON list of keys"),
        option(
            "--set",
            help="show the values after these overrides (checked as `devlearn run` would)",
        ),
        option(
            "--preset",
            help="""show the values of one of the behaviour's presets (as `devlearn run
            --preset`)""",
        ),
        help="list a behaviour's config keys (type, default, meaning)",
        description="""List every key `devlearn run BEHAVIOR --set KEY=VALUE` accepts: the
        run's, PPO's and the behaviour's own, with type, the value a run would use and its
        docstring. Values set by the behaviour's train_defaults() are marked.""",
    ),
    Command(
        "new",
        option("name", metavar="PLUGIN_NAME", help="behaviour name, lower_snake_case"),
        option("--out", help="where to write it (default ./devlearn-NAME)"),
        help="write a new plugin distribution (behaviour, reward term, tests)",
        description="""Write an installable plugin: pyproject.toml with the devlearn entry
        point, a behaviour with a reward term and an evaluator, and tests (conformance kit,
        reward by hand, a tiny training run). `pip install -e DIR && python -m pytest DIR/tests`
        passes.""",
    ),
    Command(
        "plugins",
        option("--json", help="print a JSON list of plugin objects"),
        option("--disable", metavar="NAME", help="disable a plugin without uninstalling it"),
        option("--enable", metavar="NAME", help="re-enable a disabled plugin"),
        help="list installed plugins (or enable/disable one)",
    ),
    Command(
        "bench",
        option("--json", help="print the figures as a JSON object"),
        option("--quick", action="store_true", help="fewer steps (rougher figures)"),
        option(
            "--only",
            metavar="SECTIONS",
            default="",
            help="""measure only these sections, comma-separated (default: all, in this order):
            startup, infant, envs, vec, gym, train, eval, learner, cnn""",
        ),
        help="measure environment and training speed",
    ),
    Command(
        "picture",
        option(
            "what",
            choices=("body-map", "eyes", "growth"),
            help="""body-map: skin regions; eyes: both eye images; growth: the infant at 0, 6,
            12, 18 and 24 months side by side, at one scale""",
        ),
        option(
            "--out", required=True, metavar="PATH", help="picture file to write (.png, .jpg...)"
        ),
        help="draw the 68-region body map, what the two eyes see, or the body at 0-24 months (PNG)",
    ),
    Command(
        "curve",
        option(
            "run_dirs",
            type=Path,
            nargs="+",
            metavar="DIR",
            help="""run folders holding metrics.jsonl (several: one line each, e.g. an
            ablation), or evaluation folders holding eval.json (together: one point per
            checkpoint)""",
        ),
        option(
            "--metric",
            action="append",
            default=None,
            help="""metrics.jsonl or eval.json key to plot (repeatable; default for runs: the
            behaviour's headline, the reward, then its other metrics/* keys but counters; of
            evaluations, the behaviour's headline and its per-episode mean)""",
        ),
        option(
            "--health",
            action="store_true",
            help="""runs: also the learner's health (spread, saturated means, explained
            variance, reward scale, learning rate, losses)""",
        ),
        option(
            "--vs",
            action="append",
            nargs="+",
            type=Path,
            default=None,
            metavar="DIR",
            help="another line to compare: evaluation folders of another run (repeatable)",
        ),
        option("--smooth", type=int, default=10, help="moving-average window (iterations)"),
        option(
            "--out",
            type=Path,
            metavar=None,  # a file, shown as OUT (argparse's default)
            help="""PNG path (default: FIRST_DIR/learning_curve.png for runs; for evaluations
            eval_curve.png in the folder holding them, e.g. RUN/eval_curve.png for RUN/eval_*)""",
        ),
        help="plot metrics of a run against environment steps",
    ),
    Command(
        "export",
        BEHAVIOR,
        option("--checkpoint", required=True, metavar="PATH", help="checkpoint file (.pt)"),
        option("--format", default="onnx", metavar="FORMAT", help="onnx or torchscript"),
        option("--out", required=True, metavar="FILE", help="file to write"),
        help="write a trained policy as ONNX or TorchScript",
        description="""Write the deterministic policy (observations to the mean action, in
        [-1, 1]) of a checkpoint for use outside devlearn, e.g. on a robot. Inputs are the
        behaviour's observations by name, batch first, in the dtypes it observes (uint8 images,
        float32 otherwise); normalisation happens inside. ONNX needs the optional packages: pip
        install 'devlearn[export]'.""",
    ),
    Command(
        "slim",
        option("checkpoint", metavar="CHECKPOINT", help="training checkpoint or run folder"),
        option("--out", metavar="PATH", help="policy file (default CHECKPOINT_DIR/policy.pt)"),
        help="write a small policy file from a training checkpoint",
        description="""Keep what evaluation needs (policy weights, config, training steps and
        the behaviour's calibration, e.g. hand_regard's detector) and drop what only resuming
        needs (critic, optimiser, env and rng state). The policy file evaluates from any folder
        with `devlearn eval BEHAVIOR --checkpoint FILE`; it cannot resume training.""",
    ),
    Command(
        "report",
        option("paths", nargs="+", metavar="PATH", help="evaluation or run folders"),
        option("--out", default="report", help="output folder (default report)"),
        option(
            "--full",
            action="store_true",
            help=f"print every metric's row (default: the first {REPORT_ROWS_SHOWN}; "
            "report.md always has them all)",
        ),
        help="table and chart of evaluations: mean and 95%% interval over seeds",
        description="""Read evaluation folders (eval.json) or run folders containing them, group
        them by variant (the config keys that differ; seeds pooled) and write report.md (mean
        and 95%% t-interval over seeds per metric, zero/random baselines beside them when given
        or found next to the paths, and the paper's figures where the behaviour gives them) and
        report.png.""",
    ),
    Command(
        "sweep",
        BEHAVIOR,
        option("--file", metavar="TOML", help="sweep file with the same settings"),
        option("--out", help="the sweep folder (required here or in the file)"),
        option(
            "--grid",
            action="append",
            metavar="KEY=V1,V2",
            help="""config values to try, e.g. behavior.curriculum=fixed_only,two_stage
            (repeatable: every combination)""",
        ),
        option("--seeds", metavar="LIST", help="seeds of every combination: 1,2,3 or 1-3"),
        option("--steps", help="environment steps per run (e.g. 4e5)"),
        option("--envs", help="environments per run"),
        option("--workers", help="env worker processes per run (default 0: in process)"),
        option("--cores", metavar="N", help="cores each run holds (default: max(1, workers))"),
        option("--set", help="config override of every run (repeatable)"),
        option(
            "--preset",
            help="""every run starts from this preset of the behaviour (e.g. paper; `devlearn
            config BEHAVIOR` lists them); --steps, --envs, --set and the grid apply over it""",
        ),
        option("--episodes", help="evaluation episodes per run (default 10)"),
        option("--eval-seed", metavar="S", help="seed of the evaluations (default 0)"),
        option(
            "--eval-args",
            metavar="'ARGS'",
            help="further devlearn eval options, quoted as one",
        ),
        option("--executor", metavar="local|ray", help="where runs execute (default local)"),
        option("--jobs", metavar="N", help="local: runs at a time (default: as cores allow)"),
        option(
            "--address",
            metavar="auto|HOST:PORT",
            help="ray: the cluster to use (default: start a local Ray instance)",
        ),
        option(
            "--no-report",
            dest="report",
            action="store_false",
            default=None,
            help="skip the report",
        ),
        option(
            "--dry-run",
            action="store_true",
            help="check everything and list the runs; start nothing",
        ),
        help="train and evaluate a grid of variants times seeds, then report",
        description="""Run an experiment in one folder: every combination of --grid values times
        --seeds is trained (devlearn run) and evaluated (devlearn eval) in its own run folder,
        then devlearn report compares them. Started again, a sweep keeps finished runs and
        continues unfinished ones from their checkpoints. Settings can come from a TOML sweep
        file (--file); options given here win.""",
    ),
    Command(
        "experiment",
        help="run, publish and tabulate an experiment declared in a TOML file",
        description="""An experiment file (docs/experiments.md) declares the behaviour, the arms
        (--set values, a preset, or learner = "sb3_ppo"), seeds, budget, evaluation protocols,
        baselines and reference figures. `run` trains and evaluates it, `publish` keeps what a
        reader needs, `table` prints the comparison.""",
        actions=(
            Command(
                "run",
                option("file", metavar="FILE", help="the experiment file (TOML)"),
                option("out", metavar="OUT", help="the experiment folder (new, or to restart)"),
                option(
                    "--dry-run",
                    action="store_true",
                    help="check the file and every arm's config; list the runs; start nothing",
                ),
                option(
                    "--jobs", metavar="N", help="local: runs at a time (default: as cores allow)"
                ),
                option(
                    "--executor",
                    choices=("local", "ray"),
                    help="where runs execute (default: the file's [executor] kind, else local)",
                ),
                option(
                    "--address",
                    metavar="auto|HOST:PORT",
                    help="ray: the cluster to use (default: start a local Ray instance)",
                ),
                help="train every arm x seed, evaluate under every protocol, with the baselines",
                description="""Check the experiment file (every arm's config resolved as
                devlearn run would, every protocol as devlearn eval would), then train every arm
                x seed and evaluate each under every protocol, and the baselines once per
                protocol, in OUT; records the commit and the file there. Started again, finished
                steps are kept and unfinished runs continue from their checkpoints.""",
            ),
            Command(
                "publish",
                option("out", metavar="OUT", help="the experiment folder"),
                option(
                    "dest",
                    metavar="DEST",
                    help="where to publish (an earlier publication is replaced)",
                ),
                help="keep the evaluations, configs, curves and one policy per arm",
                description="""Copy what a reader needs from OUT into DEST: every eval.json (arms x
                seeds x protocols, baselines x protocols), per run its config, seconds of learning
                and a thinned training curve, one policy file per arm (its median seed under the
                first protocol), the experiment file and the commit.""",
            ),
            Command(
                "table",
                option(
                    "dest",
                    metavar="DEST",
                    nargs="+",
                    help="a publication (devlearn experiment publish); several pool an arm's "
                    "seeds across them",
                ),
                option("--json", help="print the figures as JSON"),
                option(
                    "--versus",
                    metavar="ARM",
                    help="also each arm's paired difference from ARM over the seeds both have",
                ),
                option(
                    "--ignore-config",
                    metavar="KEY",
                    action="append",
                    help="pooling: a resolved-config key (or section) that arms of one name may "
                    "differ in, because it does not decide their numbers; repeatable",
                ),
                option("--out", metavar="FILE", help="also write the tables (or JSON) to FILE"),
                option(
                    "--metric",
                    metavar="KEY",
                    action="append",
                    help="also tabulate this eval.json number, by its dotted key "
                    "(likeness.touches_per_minute); repeatable",
                ),
                help="print the comparison as markdown tables (or JSON)",
                description="""Per protocol, every arm's headline as the mean and 95% t-interval
                over seeds with each seed's value, its seconds of learning where recorded, the
                baselines under the same protocol and the references with their source; with
                --metric, a table of those eval.json numbers per protocol too. Several DESTs
                make one table: an arm of the same name pools its seeds across them (the same
                behaviour, budget and arm settings, protocols of the same definition; each
                seed in one publication only).""",
            ),
        ),
    ),
)
"""The sub-commands, in the order ``devlearn --help`` lists them."""
