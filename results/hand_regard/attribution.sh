#!/usr/bin/env bash
# Issue #39, item 2: which hand is it, measured where it matters, the old rule (position)
# beside the new (visibility: each hand's visibility predicted from its own arm's posture).
#
#   bash results/hand_regard/attribution.sh        # ~12 min on 2 busy cores
#
# Writes results/hand_regard/attribution/ (babbling_seed{1,7}.json: measure's full results;
# attribution.{json,md}: the tables) and the detector with its visibility model,
# results/hand_regard/detector/babybench_mittens_sides_detector.json.
set -euo pipefail
cd "$(dirname "$0")/../.."
out=results/hand_regard/attribution
det=results/hand_regard/detector
mkdir -p "$out"
# 1. Issue #29's shared detector (babbling seed 0, one arm per episode) learns which hand is
#    which: its calibration babbling again (10,000 steps) and 50,000 more one-arm steps
#    (seeds 2..6), as a run's calibration does. Scored on the committed protocol's frames:
#    12 x 500 steps of both-arm babbling from BabyBench's start, seed 1 (the position rule's
#    0.55 / 0.54, plugin README).
python -m devlearn_hand_regard.measure --detector "$det/babybench_mittens_detector.json" \
    --test-episodes 12 --save "$det/babybench_mittens_sides_detector.json" \
    --out "$out/babbling_seed1.json"
# 2. The same detector on frames never looked at while the method was chosen: 36 x 500 steps
#    of both-arm babbling, seed 7 (the hands show in a few per cent of frames and the errors
#    come in whole episodes, so 12 episodes measure it loosely).
python -m devlearn_hand_regard.measure --detector "$det/babybench_mittens_sides_detector.json" \
    --test-episodes 36 --test-seed 7 --out "$out/babbling_seed7.json"
# 3. The published policies' own evaluation frames, and the tables.
python results/hand_regard/attribution.py --detector "$det/babybench_mittens_sides_detector.json" \
    --babbling "$out/babbling_seed1.json" "$out/babbling_seed7.json" --out "$out"
