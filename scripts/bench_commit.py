"""Measure an earlier commit's environments on this machine, to compare with ``devlearn bench``.

Usage (from the repository root, with the set-up .venv)::

    flock /tmp/devlearn-cpu.lock .venv/bin/python scripts/bench_commit.py COMMIT > OUT.json

(``--quick`` after COMMIT: an eighth of the steps, a smoke test.)
The commit's tree is extracted with ``git archive`` into a temporary folder and its own
bench functions run there (its folders first on PYTHONPATH, this .venv's packages otherwise;
``devlearn.bench.speed`` and ``.ceiling``, or before #31's folders ``devlearn.bench`` and
``devlearn.bench_ceiling``), so that old and new code are timed in one session on one machine.
Prints JSON: self-touch and hand-regard single-process steps/s and breakdowns, 16 self-touch envs
over 1 and 2 workers, the crib physics ceiling, and self-touch end-to-end training: steps/s and
the seconds of collection and of the PPO update per iteration.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

MEASURE = """
import json, subprocess, sys, tempfile, time
try:
    from devlearn.bench.speed import bench_behavior_env, bench_vec_env
    from devlearn.bench.ceiling import env_breakdown, physics_ceiling
except ImportError:  # a commit before the folders by concept (#31)
    from devlearn.bench import bench_behavior_env, bench_vec_env
    from devlearn.bench_ceiling import env_breakdown, physics_ceiling
from devlearn.plugins import PluginRegistry

def training(behavior, steps):
    # devlearn run's defaults; means over the iterations after the first (as bench_training)
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "devlearn.cli", "run", behavior, "--steps", str(steps)]
        subprocess.run([*cmd, "--seed", "0", "--out", tmp + "/run"], check=True,
                       capture_output=True)
        lines = open(tmp + "/run/metrics.jsonl").read().splitlines()
    rows = [json.loads(line) for line in lines][1:]
    return {f"{behavior}_train_{key}": sum(r[key] for r in rows) / len(rows)
            for key in ("steps_per_s", "collect_s", "update_s")}

def main(k):
    registry, out = PluginRegistry(), {}
    st, hr = registry.create("self_touch"), registry.create("hand_regard")
    out["physics_crib_steps_per_s"] = physics_ceiling("crib", 4000 // k)
    out["self_touch_steps_per_s"] = max(bench_behavior_env(st, 2000 // k) for _ in range(2))
    out["self_touch_breakdown_ms"] = env_breakdown(st, 2000 // k)
    out["hand_regard_steps_per_s"] = bench_behavior_env(hr, 200 // k)
    out["hand_regard_breakdown_ms"] = env_breakdown(hr, 200 // k)
    for workers in (1, 2):
        key = f"self_touch_vec_steps_per_s_{workers}_workers"
        out[key] = bench_vec_env(st, num_envs=16, workers=workers, steps=200 // k)
    out.update(training("self_touch", 32768 // k))
    out["date"] = time.strftime("%Y-%m-%d %H:%M")
    print(json.dumps(out, indent=2))

if __name__ == "__main__":
    main(int(sys.argv[1]))
"""


def main() -> int:
    commit = sys.argv[1]
    divide = "8" if "--quick" in sys.argv[2:] else "1"  # --quick: 1/8 of the steps
    with tempfile.TemporaryDirectory() as tmp:
        tree = Path(tmp) / "tree"
        tree.mkdir()
        archive = subprocess.run(["git", "archive", commit], capture_output=True, check=True)
        subprocess.run(["tar", "-x", "-C", str(tree)], input=archive.stdout, check=True)
        plugins = [str(p / "src") for p in sorted((tree / "plugins").iterdir())]
        paths = [str(tree), *plugins, os.environ.get("PYTHONPATH", "")]
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in paths if p)}
        script = tree / "measure_commit.py"  # a file: worker processes re-import __main__
        script.write_text(MEASURE)
        done = subprocess.run([sys.executable, str(script), divide], env=env, cwd=tmp)
    return done.returncode


if __name__ == "__main__":
    sys.exit(main())
