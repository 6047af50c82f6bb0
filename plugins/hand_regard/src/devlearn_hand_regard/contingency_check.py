"""Learn, validate and attack the contingency attribution (issue #58 items 1 and 2).

Commands (``python -m devlearn_hand_regard.contingency_check COMMAND ...``):

``babble``
    Record babbling from BabyBench's scene reduced to blob tables (:mod:`.blob_table`): the
    training kind, ``--arms turns --random-pose`` (both arms anywhere, taking turns), and
    held-out kinds (``--arms both``, both arms moving, from random poses or BabyBench's
    start). The segmentation is recorded beside the blobs for scoring only.
``fit``
    Learn the contingency model (:func:`contingency.fit_contingency_model`) from training
    tables and save a detector file with it (``contingency_model``) beside the given one's
    colour step and visibility model.
``validate``
    Score the rules (``position``, ``visibility``, ``contingency``) on held-out tables
    against the segmentation: precision / recall per side and per (eye, hand) pair, false
    credit.
``replay``
    The adversarial check: every given policy file runs ``devlearn eval``'s protocol (its
    mean action from BabyBench's start, eval seed 0) for ``--episodes`` episodes, its frames
    are reduced to a blob table with its own colour step, and the rule it was published with
    (``old``) and the contingency rule (``new``) are scored on them: false credit (share of
    steps on which some side is credited in an eye that shows none of that hand's pixels)
    and recall (against ``pixels``, at least 20 of the hand's pixels).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from devlearn_hand_regard.blob_table import BlobTable, tabulate
from devlearn_hand_regard.contingency import ContingencyAttribution, fit_contingency_model
from devlearn_hand_regard.detector import Blob, DetectorParams, HandDetector
from devlearn_hand_regard.evaluation import PAIRS, pair_name
from devlearn_hand_regard.visibility import MIN_PIXELS

RULES = ("position", "visibility", "contingency")
"""The side attributions compared."""
SCENE = "sitting_babybench"
MEASURE_DETECTOR = "results/hand_regard/detector/babybench_mittens_sides_detector.json"
"""The shared calibration of issues #29 and #39 (its colour step and visibility model)."""


def _blobs(row: np.ndarray) -> list[Blob]:
    """A table row's blobs as the detector's (their masks empty: the old rules read only the
    centroids and the image size)."""
    empty = np.zeros((64, 64), dtype=bool)
    return [Blob((float(x), float(y)), float(a), empty) for x, y, a in row if np.isfinite(x)]


def credits(detector: HandDetector, rule: str, table: BlobTable) -> np.ndarray:
    """Which (eye, hand) pairs ``rule`` credits on every frame of ``table``.

    ``position`` and ``visibility`` are :class:`HandDetector`'s rules on the table's blobs;
    ``contingency`` is :class:`ContingencyAttribution` with ``detector``'s
    ``contingency_model``, reset at every episode's start.

    Returns:
        (T, 2 eyes, 2 hands) bool.
    """
    out = np.zeros((len(table), 2, 2), dtype=bool)
    params = detector.params
    assert params is not None
    if rule == "contingency":
        attribution = ContingencyAttribution(
            params.contingency_model, pair_blobs=detector.pair_blobs
        )
        for t in range(len(table)):
            if t == 0 or table.episode[t] != table.episode[t - 1]:
                attribution.reset()
            hands = attribution.step(table.blobs[t], table.proprioception[t])
            for eye in range(2):
                for hand in hands[eye]:
                    if hand >= 0:
                        out[t, eye, hand] = True
        return out
    visibility = HandDetector(params, attribution="visibility") if rule == "visibility" else None
    for t in range(len(table)):
        p = table.proprioception[t]
        likelihood = visibility.view_prior(p) if visibility is not None else None
        for eye in range(2):
            found = _blobs(table.blobs[t, eye])
            if not found:
                continue
            if visibility is not None and likelihood is not None:
                attributed = visibility.attribute_by_visibility(found, eye, likelihood[eye])
                for hand in range(2):
                    out[t, eye, hand] = bool(attributed[hand])
            else:
                single = detector.attribute(found, eye, table.image_width, p)
                for hand in range(2):
                    out[t, eye, hand] = single[hand] is not None
    return out


def score_credits(credited: np.ndarray, table: BlobTable) -> dict[str, Any]:
    """Credits against the segmentation.

    Returns:
        ``steps``; ``false_credit``: share of steps on which some pair is credited while
        that hand shows no pixel in that eye (and per pair ``false_credit``); per side (the
        hand, both eyes pooled) and per pair ``precision`` and ``recall`` against ``pixels``
        (at least :data:`visibility.MIN_PIXELS` of the hand's pixels: ``devlearn eval``'s
        criterion), ``in_view`` (share of steps).
    """
    pixels = table.hand_pixels
    truth, absent = pixels >= MIN_PIXELS, pixels == 0
    false = credited & absent

    def stats(c: np.ndarray, v: np.ndarray, a: np.ndarray) -> dict[str, Any]:
        tp, fp, fn = int((c & v).sum()), int((c & ~v).sum()), int((~c & v).sum())
        return {
            "precision": round(tp / (tp + fp), 3) if tp + fp else None,
            "recall": round(tp / (tp + fn), 3) if tp + fn else None,
            "false_credit": round(float((c & a).mean()), 4) if c.size else 0.0,
            "in_view": round(float(v.mean()), 3) if v.size else 0.0,
        }

    return {
        "steps": len(table),
        "false_credit": round(float(false.any(axis=(1, 2)).mean()), 4) if len(table) else 0.0,
        "sides": {
            side: stats(credited[:, :, h], truth[:, :, h], absent[:, :, h])
            for h, side in enumerate(("left", "right"))
        },
        "pairs": {
            pair_name(eye, hand): stats(
                credited[:, eye, hand], truth[:, eye, hand], absent[:, eye, hand]
            )
            for eye, hand in PAIRS
        },
        "recall": _recall(credited, truth),
    }


def _recall(credited: np.ndarray, truth: np.ndarray) -> float | None:
    """Pooled recall over every (step, eye, hand) in view."""
    return round(float(credited[truth].mean()), 3) if truth.any() else None


def record_table(
    detector: HandDetector,
    steps: int,
    seed: int,
    arms: str,
    random_pose: bool,
    episode_steps: int,
    start: str = "babybench",
) -> BlobTable:
    """Babble in BabyBench's scene with the segmentation recorded, as a blob table."""
    from typing import cast

    from devlearn import Infant, build_infant
    from devlearn_hand_regard.babbling import babble
    from devlearn_hand_regard.segmentation_score import SegmentationRecorder

    infant = build_infant(SCENE, senses=("proprioception", "eyes"), appearance="mittens")
    try:
        recorder = SegmentationRecorder(infant)
        data = babble(
            steps,
            seed=seed,
            hold_steps=25,
            infant=cast("Infant", recorder),
            episode_steps=episode_steps,
            random_pose=random_pose,
            start=start,
            arms=arms,
        )
        segmentation = np.stack(recorder.segmentation)
    finally:
        infant.close()
    return tabulate(
        detector,
        data.eyes,
        data.proprioception,
        data.episode,
        segmentation,
        data.moving_arm,
        other_arm_hangs=arms == "alternate",
    )


def policy_table(path: Path, episodes: int, detector: HandDetector | None = None) -> BlobTable:
    """A policy's evaluation frames (:func:`replay.record_policy`) as a blob table, with the
    policy's own colour step unless ``detector`` is given."""
    from devlearn_hand_regard.replay import record_policy

    frames = record_policy(path, episodes)
    detector = detector or published_detector(path)
    return tabulate(
        detector,
        frames["eyes"],
        frames["proprioception"],
        frames["episode"],
        frames["segmentation"],
    )


def published_detector(path: Path) -> HandDetector:
    """The detector a policy file was published with: its stored calibration, attributing as
    its config's ``hand_attribution`` says (a config without the key: the legacy rule,
    ``position``)."""
    from devlearn.testing import load_checkpoint
    from devlearn_hand_regard.config import HandRegardConfig

    state = load_checkpoint(path)
    stored = (state.get("artifacts") or {}).get("hand_detector")
    if state.get("behavior") != "hand_regard" or not stored:
        raise SystemExit(f"{path}: not a hand_regard policy with its hand detector")
    params = DetectorParams.from_dict(stored, source=f"{path}: hand detector")
    legacy = HandRegardConfig.LEGACY_DEFAULTS
    behavior = state["config"]["behavior"]
    rule = behavior.get("hand_attribution", legacy["hand_attribution"])
    pairs = behavior.get("contingency_pairs", legacy["contingency_pairs"])
    return HandDetector(params, attribution=rule, pair_blobs=pairs)


def _with_model(params: DetectorParams, model: dict[str, Any]) -> HandDetector:
    """``params``' colour step with the contingency model ``model``."""
    own = DetectorParams(**{**params.__dict__, "contingency_model": model})
    return HandDetector(own, attribution="contingency")


def _cmd_babble(args: argparse.Namespace) -> None:
    detector = HandDetector(DetectorParams.load(args.detector))
    began = time.monotonic()
    table = record_table(
        detector,
        args.steps,
        args.seed,
        args.arms,
        args.random_pose,
        args.episode_steps,
        args.start,
    )
    table.save(args.out)
    print(f"{args.out}: {len(table)} frames, {time.monotonic() - began:.0f} s", flush=True)


def _cmd_fit(args: argparse.Namespace) -> None:
    params = DetectorParams.load(args.detector)
    if not params.visibility_model:
        raise SystemExit(f"{args.detector}: no visibility model (its joints are the posture's)")
    tables = [BlobTable.load(p) for p in args.tables]
    joints = params.visibility_model["joints"]
    model = fit_contingency_model(tables, joints, scene_body_schema(tables[0].image_width))
    labelled = _label_accuracy(tables, joints)
    model["label_accuracy"] = labelled
    out = DetectorParams(**{**params.__dict__, "contingency_model": model})
    out.save(args.save)
    print(json.dumps({k: model[k] for k in ("reach", "label_counts", "distance_quantiles")}))
    print(json.dumps({"labels": labelled}), flush=True)


def scene_body_schema(image_size: int = 64) -> dict[str, Any]:
    """:func:`contingency_body.body_schema` of BabyBench's seated infant (the babbling's)."""
    from devlearn import build_infant
    from devlearn_hand_regard.contingency_body import body_schema

    infant = build_infant(SCENE, senses=("proprioception",), appearance="mittens")
    try:
        return body_schema(infant.model, list(infant.actuator_names), image_size)
    finally:
        infant.close()


def _label_accuracy(tables: list[BlobTable], joints: list[list[int]]) -> dict[str, Any]:
    """How often the contingency labels name the blob's true hand (informative only: the
    segmentation is read here, never by the fit)."""
    from devlearn_hand_regard.contingency import contingency_labels

    right = total = 0
    for table in tables:
        labels = contingency_labels(table, joints)
        known = (labels >= 0) & (table.blob_hand >= 0)
        right += int((labels[known] == table.blob_hand[known]).sum())
        total += int(known.sum())
    return {"labelled": total, "right": round(right / max(total, 1), 4)}


def _cmd_validate(args: argparse.Namespace) -> dict[str, Any]:
    detector = HandDetector(DetectorParams.load(args.detector))
    out: dict[str, Any] = {"argv": sys.argv[1:], "tables": {}}
    for path in args.tables:
        table = _strided(BlobTable.load(path), args.stride)
        row = {rule: score_credits(credits(detector, rule, table), table) for rule in RULES}
        out["tables"][Path(path).stem] = row
        print(Path(path).stem, json.dumps({r: _brief(v) for r, v in row.items()}), flush=True)
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(json.dumps(out, indent=1) + "\n")
    return out


def _strided(table: BlobTable, stride: int) -> BlobTable:
    """Every ``stride``-th frame (babbling records every step; the behaviour decides every
    fifth, and the rule's motion window counts decisions)."""
    if stride <= 1:
        return table
    keep = slice(None, None, stride)
    return BlobTable(
        table.blobs[keep],
        table.proprioception[keep],
        table.episode[keep],
        table.hand_pixels[keep],
        table.blob_hand[keep],
        table.moving_arm[keep],
        table.image_width,
    )


def _brief(result: dict[str, Any]) -> dict[str, Any]:
    return {
        "false_credit": result["false_credit"],
        "recall": result["recall"],
        **{side: (v["precision"], v["recall"]) for side, v in result["sides"].items()},
    }


def _cmd_replay(args: argparse.Namespace) -> dict[str, Any]:
    model = DetectorParams.load(args.detector).contingency_model
    if not model:
        raise SystemExit(f"{args.detector}: no contingency_model (run the fit command first)")
    out: dict[str, Any] = {"argv": sys.argv[1:], "episodes": args.episodes, "policies": {}}
    for path, name in zip(args.policies, args.names or args.policies):
        own = published_detector(Path(path))
        assert own.params is not None
        if args.tables and Path(args.tables, f"{_slug(name)}.npz").exists():
            table = BlobTable.load(Path(args.tables, f"{_slug(name)}.npz"))
        else:
            table = policy_table(Path(path), args.episodes, own)
            if args.tables:
                table.save(Path(args.tables, f"{_slug(name)}.npz"))
        old = score_credits(credits(own, own.attribution, table), table)
        new = score_credits(credits(_with_model(own.params, model), "contingency", table), table)
        out["policies"][name] = {
            "episodes": int(table.episode.max()) + 1,
            "steps": len(table),
            "old_rule": own.attribution,
            "old": old,
            "new": new,
        }
        print(
            f"{name}: old ({own.attribution}) false credit {old['false_credit']:.4f}, new "
            f"{new['false_credit']:.4f}, new recall {new['recall']}",
            flush=True,
        )
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(json.dumps(out, indent=1) + "\n")
    return out


def _slug(name: str) -> str:
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in name)


def main(argv: list[str] | None = None) -> None:
    """Command line: see the module docstring."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    commands = parser.add_subparsers(dest="command", required=True)
    babble = commands.add_parser("babble", help="record babbling as a blob table")
    babble.add_argument("--detector", default=MEASURE_DETECTOR, help="colour step (JSON)")
    babble.add_argument("--steps", type=int, default=10_000)
    babble.add_argument("--seed", type=int, default=100)
    babble.add_argument("--arms", default="turns", choices=("turns", "both", "alternate"))
    babble.add_argument("--random-pose", action="store_true", help="episodes from random poses")
    babble.add_argument("--start", default="babybench", help="start without --random-pose")
    babble.add_argument("--episode-steps", type=int, default=200)
    babble.add_argument("--out", required=True, help="blob table (.npz)")
    fit = commands.add_parser("fit", help="learn the contingency model from babbling tables")
    fit.add_argument("--detector", default=MEASURE_DETECTOR, help="detector to extend (JSON)")
    fit.add_argument("--tables", nargs="+", required=True, help="training blob tables")
    fit.add_argument("--save", required=True, help="the detector with its model (JSON)")
    validate = commands.add_parser("validate", help="score the rules on held-out tables")
    validate.add_argument("--detector", required=True, help="detector with contingency_model")
    validate.add_argument("--tables", nargs="+", required=True, help="held-out blob tables")
    validate.add_argument("--stride", type=int, default=5, help="frames per decision")
    validate.add_argument("--out", help="JSON file for the figures")
    replay = commands.add_parser("replay", help="false credit on published policies' frames")
    replay.add_argument("--detector", required=True, help="detector with contingency_model")
    replay.add_argument("--policies", nargs="+", required=True, help="policy files")
    replay.add_argument("--names", nargs="*", help="a name per policy (default: the paths)")
    replay.add_argument("--episodes", type=int, default=10, help="evaluation episodes each")
    replay.add_argument("--tables", help="folder caching each policy's blob table")
    replay.add_argument("--out", help="JSON file for the figures")
    args = parser.parse_args(argv)
    {"babble": _cmd_babble, "fit": _cmd_fit, "validate": _cmd_validate, "replay": _cmd_replay}[
        args.command
    ](args)


if __name__ == "__main__":
    main()
