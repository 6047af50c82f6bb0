#!/usr/bin/env bash
# Sets up devlearn in ./.venv: the core, the built-in plugins and the example plugin,
# pinned by constraints.txt (CPU torch 2.13, mujoco 3.17, dm-control 1.0.50, rsl-rl-lib 5.5.1).
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  "$PY" -m venv .venv
fi
# The test extra brings the pinned ruff, import-linter and mypy (.ci/run) and the wandb extra W&B
# logging, so CI tests `--logger wandb` (offline); the sb3 extra Stable-Baselines3, so CI trains
# examples/sb3. Install the pinned torch first so nothing else pulls a CUDA build.
.venv/bin/python -m pip install -q --disable-pip-version-check -c constraints.txt torch
.venv/bin/python -m pip install -q --disable-pip-version-check -c constraints.txt \
  -e ".[test,wandb,export,ray,sb3]" -e plugins/self_touch -e plugins/hand_regard -e plugins/curiosity \
  -e examples/hand_to_mouth
echo "devlearn is set up in .venv (activate with: source .venv/bin/activate)"
