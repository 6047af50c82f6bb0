"""Which hand is it, measured where it matters (issue #39, item 2): the position rule beside
the visibility rule, on both-arm babbling and on the published policies' own frames.

Run from the repository root (results/hand_regard/README.md gives the committed arguments)::

    python -m devlearn_hand_regard.analysis.attribution --detector D.json \\
        --babbling R.json [R2.json ...] --policies P.pt [P2.pt ...] --out FOLDER

Two kinds of frames, each scored against the renderer's segmentation (per (eye, hand) pair
precision and recall against ``pixels``, at least 20 of the hand's pixels, as ``devlearn
eval``; and the share of steps a pair is credited while that hand shows no pixel in that eye):

- **both-arm babbling** from BabyBench's start: read from ``python -m
  devlearn_hand_regard.measure`` results (``--babbling``), which hold the visibility rule's
  score (``score``) and the position rule's on the same frames (``score_position``);
- **trained policies' own frames** (``--policies``): each policy runs ``devlearn eval``'s
  protocol (10 episodes of 1,000 steps from BabyBench's start, eval seed 0, its mean action)
  with the detector it was published with, so the frames are those of its published
  evaluation; the frames it sees (one per decision) are recorded and scored by its own
  calibration under both rules: ``position`` (issue #29's) and ``visibility`` (issue #39's:
  its own visibility model, or for a policy published before issue #39, ``--detector``'s).

Writes ``attribution.json`` (every figure) and ``attribution.md`` (the tables) in ``--out``.
The segmentation is read here only, never by a detector.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from devlearn import UsageError, build_infant, write_text_atomically
from devlearn.testing import PluginRegistry, evaluate_policy, load_checkpoint
from devlearn_hand_regard.babbling import BabblingData
from devlearn_hand_regard.detector import DetectorParams, HandDetector
from devlearn_hand_regard.segmentation_score import score

PAIRS = {
    "left_eye_left_hand": "LL",
    "right_eye_left_hand": "RL",
    "left_eye_right_hand": "LR",
    "right_eye_right_hand": "RR",
}
"""The eye-hand pairs in the paper's Table III order, with their short names."""


class FrameRecorder:
    """Wraps an infant: every time the eyes are read (once per decision, by the behaviour's
    facts), keeps the images, the proprioception and the segmentation."""

    def __init__(self, infant: Any) -> None:
        self.infant = infant
        self.eyes_seen: list[np.ndarray] = []
        self.proprioception_seen: list[np.ndarray] = []
        self.segmentation: list[np.ndarray] = []

    def __getattr__(self, name: str) -> Any:
        return getattr(self.infant, name)

    def eyes(self) -> np.ndarray:
        """The eye images; a copy of them, the proprioception and the segmentation are kept."""
        eyes = self.infant.eyes()
        self.eyes_seen.append(eyes.copy())
        self.proprioception_seen.append(np.asarray(self.infant.proprioception(), np.float32))
        self.segmentation.append(self.infant.eyes_segmentation().copy())
        return eyes

    def frames(self) -> tuple[BabblingData, np.ndarray]:
        """The recorded frames (as a recording ``segmentation_score.score`` reads: T frames)
        and their (T, 2, H, W) segmentation."""
        steps = len(self.eyes_seen)
        data = BabblingData(
            eyes=np.stack(self.eyes_seen),
            proprioception=np.stack(self.proprioception_seen),
            actions=np.zeros((steps, 0), np.float32),
            arm_speed=np.zeros((steps, 2), np.float32),
            episode=np.zeros(steps, int),
        )
        return data, np.stack(self.segmentation)


def policy_frames(path: Path, episodes: int, registry: PluginRegistry) -> dict[str, Any]:
    """Run a policy file under ``devlearn eval``'s protocol (``episodes`` from BabyBench's
    start, eval seed 0, one env), recording its frames.

    Returns:
        ``data`` (the frames, a :class:`BabblingData`), ``segmentation`` ((T, 2, H, W)) and
        ``summary`` (the evaluation's, as its eval.json holds it).
    """
    recorders: list[FrameRecorder] = []

    def factory(scene: str, **options: Any) -> FrameRecorder:
        recorders.append(FrameRecorder(build_infant(scene, **options)))
        return recorders[-1]

    summary = evaluate_policy(
        "hand_regard", path, episodes, registry, infant_factory=factory, seed=0, progress=False
    )
    data, segmentation = recorders[0].frames()
    return {"data": data, "segmentation": segmentation, "summary": summary}


def policy_detector(path: Path) -> DetectorParams:
    """The detector a policy file was published with (``devlearn slim`` stores it).

    Raises:
        UsageError: The file holds no detector.
    """
    stored = (load_checkpoint(path).get("artifacts") or {}).get("hand_detector")
    if stored is None:
        raise UsageError(
            f"{path} holds no hand detector; give a policy file made by `devlearn slim` "
            "from a hand-regard run"
        )
    return DetectorParams.from_dict(stored, source=f"{path}'s hand detector")


def brief(result: dict[str, Any]) -> dict[str, Any]:
    """The figures of a ``segmentation_score.score`` result that the tables show."""
    return {
        "steps": result["steps"],
        "pair_mean": {k: result["pair_mean"][k] for k in ("precision_pixels", "recall_pixels")},
        "pairs": {
            name: {
                k: pair[k]
                for k in ("precision_pixels", "recall_pixels", "credited_absent", "in_view")
            }
            for name, pair in result["pairs"].items()
        },
        "credited_absent_max": result["credited_absent_max"],
        "any_hand": result["any_hand"],
    }


def _cell(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f}"


def table_row(label: str, rule: str, result: dict[str, Any]) -> str:
    """One Markdown row of a :func:`brief` result: pair-averaged and per-pair precision /
    recall, and the largest share of steps a pair is credited with its hand absent."""
    mean = result["pair_mean"]
    pairs = " | ".join(
        f"{_cell(p['precision_pixels'])} / {_cell(p['recall_pixels'])}"
        for p in result["pairs"].values()
    )
    absent = max(p["credited_absent"] for p in result["pairs"].values())
    return (
        f"| {label} | {rule} | {result['steps']:,} | **{_cell(mean['precision_pixels'])} / "
        f"{_cell(mean['recall_pixels'])}** | {pairs} | {100 * absent:.1f}% |"
    )


HEADER = (
    "| frames | attribution | steps | pair-averaged precision / recall | "
    + " | ".join(PAIRS.values())
    + " | most steps a pair is credited with the hand absent |\n"
    + "|---|---|---|---|---|---|---|---|---|"
)
"""The table's header (:func:`table_row`'s columns)."""


def policy_name(path: Path) -> str:
    """A policy's name in the tables: its file's two folders (``i39/paper``)."""
    return f"{path.parent.parent.name}/{path.parent.name}"


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line: see the module docstring. Returns what ``attribution.json`` holds."""
    parser = argparse.ArgumentParser(
        prog="python -m devlearn_hand_regard.analysis.attribution",
        description=(__doc__ or "").splitlines()[0],
    )
    parser.add_argument("--detector", required=True, help="the detector with a visibility model")
    parser.add_argument("--babbling", nargs="*", default=[], help="measure results (JSON)")
    parser.add_argument("--policies", nargs="*", default=[], help="policy files")
    parser.add_argument("--episodes", type=int, default=10, help="evaluation episodes each")
    parser.add_argument("--out", required=True, help="folder for attribution.json / .md")
    args = parser.parse_args(argv)
    sides = DetectorParams.load(args.detector)
    new = HandDetector(sides, attribution="visibility")
    registry = PluginRegistry()
    out: dict[str, Any] = {"argv": sys.argv[1:] if argv is None else argv, "babbling": {}}
    rows = [HEADER]
    for path in args.babbling:
        measured = json.loads(Path(path).read_text())
        frames = measured["test_frames"]
        label = (
            f"both-arm babbling, {frames['episodes']} x {frames['episode_steps']} steps, "
            f"seed {frames['seed']}"
        )
        entry = {
            "position": brief(measured["score_position"]),
            "visibility": brief(measured["score"]),
        }
        out["babbling"][Path(path).name] = entry
        rows += [table_row(label, rule, entry[rule]) for rule in ("position", "visibility")]
    out["policies"] = {}
    for name in args.policies:
        path = Path(name)
        recorded = policy_frames(path, args.episodes, registry)
        data, segmentation = recorded["data"], recorded["segmentation"]
        own = policy_detector(path)
        # both rules with the policy's own calibration; a policy published before issue #39
        # has no visibility model, so the new rule is --detector's (the same calibration's)
        visibility = HandDetector(own, attribution="visibility") if own.visibility_model else new
        entry = {
            "position": brief(score(HandDetector(own), data, segmentation)),
            "visibility": brief(score(visibility, data, segmentation)),
            "published_pixels": recorded["summary"]["criteria"]["pixels"]["visibility"],
        }
        out["policies"][policy_name(path)] = entry
        label = f"policy `{policy_name(path)}`, {args.episodes} eval episodes"
        rows += [table_row(label, rule, entry[rule]) for rule in ("position", "visibility")]
    folder = Path(args.out)
    folder.mkdir(parents=True, exist_ok=True)
    write_text_atomically(folder / "attribution.json", json.dumps(out, indent=1) + "\n")
    markdown = "\n".join(rows) + "\n"
    write_text_atomically(folder / "attribution.md", markdown)
    print(markdown)
    return out


if __name__ == "__main__":
    main()
