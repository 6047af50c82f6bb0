"""The calibrated hand detector (HSV threshold, morphology, contours) and hand optical flow.

Nothing here knows what a hand looks like: the colour ranges, the blob sizes and the
left/right attribution all come from :class:`DetectorParams`, which motor babbling learns
(:mod:`devlearn_hand_regard.calibration`, paper sec. II-B2) and saves as JSON with the run.
"""

from __future__ import annotations

import json
import math
import warnings
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from devlearn import write_text_atomically
from devlearn.api.json_files import read_json_object
from devlearn_hand_regard.attribution import VisibilityPredictor, assign
from devlearn_hand_regard.blob_table import MAX_BLOBS, blob_row
from devlearn_hand_regard.contingency import (
    PAIR_BLOBS,
    ContingencyAttribution,
    check_contingency_model,
)

FORMAT_VERSION = 2
"""2: no static-body masks (the mittens made them unnecessary); 1 files are refused."""


@dataclass
class DetectorParams:
    """What babbling learned about the hands' appearance.

    Attributes:
        hsv_ranges: Colour boxes ``[h_lo, s_lo, v_lo, h_hi, s_hi, v_hi]`` in OpenCV HSV
            (H 0..179, S and V 0..255); a pixel is hand-coloured when inside any box (a hue
            range crossing red's 179 -> 0 wrap is stored as two boxes).
        min_area: Smallest hand blob, in pixels (after morphology).
        max_area: Largest hand blob, in pixels.
        expected_area: Median hand blob size seen while babbling, in pixels.
        hand_means: (2 eyes, 2 hands [left, right], 2 [x, y]) mean image position of each
            hand while babbling, in pixels; used to tell which blob is which hand.
        image_size: (H, W) of the eye images the sizes refer to.
        kernel: Side of the square morphology kernel, in pixels.
        calibration: Report of the calibration (tracks, correlations); informative only.
        position_model: Where each hand should appear given the body's posture, learned from
            the babbling hand tracks (:func:`calibration.position_model`): ``joint_mean`` and
            ``joint_scale`` (J,) standardise the joint angles (the first J proprioception
            values), ``weights`` (2 hands, 2 + J, 2) map [1, eye - 0.5, standardised angles]
            to the image position (x, y). Empty: ``hand_means`` alone attribute the blobs.
        side_hsv_ranges: Each hand's own colour boxes, [left boxes, right boxes], when
            babbling found that the hands differ in colour (``two_colour_mittens``): then a
            hand is the largest blob of its own colour, and positions are not used. Empty:
            one colour for both hands, attributed by position.
        visibility_model: Each hand's visibility per eye predicted from its own arm's posture,
            learned from one-arm babbling (:func:`attribution.fit_visibility_model`): the
            detector's ``visibility`` attribution. Empty: not learned (files before issue #39).
        contingency_model: Where each arm puts its hand in each eye and the postures babbling
            showed it in (:func:`contingency.fit_contingency_model`): the ``contingency``
            attribution (issue #58). Empty: not learned.
    """

    hsv_ranges: list[list[int]]
    min_area: float
    max_area: float
    expected_area: float
    hand_means: list[list[list[float]]]
    image_size: tuple[int, int] = (64, 64)
    kernel: int = 3
    calibration: dict[str, Any] = field(default_factory=dict)
    position_model: dict[str, Any] = field(default_factory=dict)
    side_hsv_ranges: list[list[list[int]]] = field(default_factory=list)
    visibility_model: dict[str, Any] = field(default_factory=dict)
    contingency_model: dict[str, Any] = field(default_factory=dict)

    def save(self, path: str | Path) -> Path:
        """Write the parameters as JSON; return the path."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        data = {"format_version": FORMAT_VERSION, **asdict(self)}
        # devlearn's atomic writer (synced, then renamed): a resumed run never reads half a file
        write_text_atomically(path, json.dumps(data, indent=2) + "\n")
        return path

    @classmethod
    def load(cls, path: str | Path) -> DetectorParams:
        """Read parameters written by :meth:`save` (devlearn's guarded JSON reader: a regular
        file of bounded size and nesting), checked as :meth:`from_dict` checks them.

        Raises:
            UsageError: The file is unreadable or not a JSON object.
            ValueError: Its values are not a detector's (the field named).
        """
        data = read_json_object(path, "a hand detector")
        return cls.from_dict(data, source=str(path))

    @classmethod
    def from_dict(cls, data: dict[str, Any], source: str = "stored detector") -> DetectorParams:
        """Rebuild parameters from :meth:`save`'s JSON content (e.g. stored in a policy file),
        every value checked (:func:`check_detector_values`): a NaN area or an empty colour box
        list would detect nothing, or everything, without a word.

        Raises:
            ValueError: Another format, a missing or unknown field, or a value no calibration
                writes (one line naming the field and what is valid).
        """
        if not isinstance(data, dict):
            raise ValueError(f"{source}: a hand detector is a JSON object")
        data = dict(data)
        version = data.pop("format_version", None)
        if version != FORMAT_VERSION:
            raise ValueError(
                f"{source}: hand detector format {version}, expected "
                f"{FORMAT_VERSION}; delete the file to calibrate again by babbling"
            )
        check_detector_values(data, source)
        data["image_size"] = tuple(int(n) for n in data["image_size"])
        return cls(**data)


_REQUIRED = ("hsv_ranges", "min_area", "max_area", "expected_area", "hand_means")
_OPTIONAL = (
    "image_size",
    "kernel",
    "calibration",
    "position_model",
    "side_hsv_ranges",
    "visibility_model",
    "contingency_model",
)
HSV_MAX = (179, 255, 255)
"""Largest H, S and V in OpenCV's 8-bit HSV (the bounds of a colour box)."""


def _number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _array(value: Any, field_name: str, source: str, shape: tuple[int | None, ...]) -> np.ndarray:
    """``value`` as a finite float array of ``shape`` (None: any length on that axis)."""
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        array = None
    ok = (
        array is not None
        and array.ndim == len(shape)
        and all(n is None or n == m for n, m in zip(shape, array.shape))
        and bool(np.isfinite(array).all())
    )
    if not ok:
        axes = " x ".join("N" if n is None else str(n) for n in shape)
        raise ValueError(f"{source}: {field_name} must be finite numbers, {axes}")
    assert array is not None
    return array


def _check_boxes(boxes: Any, field_name: str, source: str) -> None:
    """A non-empty list of colour boxes ``[h_lo, s_lo, v_lo, h_hi, s_hi, v_hi]``."""
    valid = (
        f"a non-empty list of colour boxes [h_lo, s_lo, v_lo, h_hi, s_hi, v_hi], whole numbers "
        f"with lo <= hi, H up to {HSV_MAX[0]}, S and V up to {HSV_MAX[1]}"
    )
    if not isinstance(boxes, list) or not boxes:
        raise ValueError(f"{source}: {field_name} must be {valid}")
    for box in boxes:
        ok = (
            isinstance(box, list)
            and len(box) == 6
            and all(_number(v) and v == int(v) for v in box)
            and all(0 <= box[i] <= box[i + 3] <= HSV_MAX[i] for i in range(3))
        )
        if not ok:
            raise ValueError(f"{source}: {field_name} holds {box!r:.60}; it must be {valid}")


def check_detector_values(data: dict[str, Any], source: str) -> None:
    """Check the fields of a saved detector (:meth:`DetectorParams.save`'s JSON without its
    ``format_version``): every field known and the required ones present, colour boxes in
    OpenCV's HSV, areas finite with ``0 <= min_area <= max_area``, positions finite and of
    their shapes, the posture and visibility models of consistent shapes.

    Raises:
        ValueError: One line naming ``source``, the field and what is valid.
    """
    unknown = sorted(set(data) - set(_REQUIRED) - set(_OPTIONAL))
    missing = [name for name in _REQUIRED if name not in data]
    if unknown or missing:
        what = [f"unknown field(s) {', '.join(unknown)}"] if unknown else []
        what += [f"missing {', '.join(missing)}"] if missing else []
        raise ValueError(f"{source}: not a hand detector ({'; '.join(what)})")
    _check_boxes(data["hsv_ranges"], "hsv_ranges", source)
    sides = data.get("side_hsv_ranges", [])
    if not isinstance(sides, list) or len(sides) not in (0, 2):
        raise ValueError(f"{source}: side_hsv_ranges must be [] or [left boxes, right boxes]")
    for side, boxes in zip(("left", "right"), sides):
        _check_boxes(boxes, f"side_hsv_ranges ({side})", source)
    areas = [data[name] for name in ("min_area", "max_area", "expected_area")]
    if not all(_number(a) and a >= 0 for a in areas) or areas[0] > areas[1]:
        raise ValueError(
            f"{source}: min_area, max_area and expected_area must be finite numbers of pixels "
            f"with 0 <= min_area <= max_area; got {areas[0]!r}, {areas[1]!r}, {areas[2]!r}"
        )
    _array(data["hand_means"], "hand_means (eyes x 2 hands x [x, y])", source, (None, 2, 2))
    size = data.get("image_size", (64, 64))
    if not (
        isinstance(size, list | tuple)
        and len(size) == 2
        and all(_number(n) and n == int(n) and 1 <= n <= 4096 for n in size)
    ):
        raise ValueError(f"{source}: image_size must be [height, width] in pixels, got {size!r}")
    kernel = data.get("kernel", 3)
    if not (_number(kernel) and kernel == int(kernel) and 1 <= kernel <= min(size)):
        raise ValueError(
            f"{source}: kernel must be a whole number of pixels from 1, got {kernel!r}"
        )
    for name in ("calibration", "position_model", "visibility_model", "contingency_model"):
        if not isinstance(data.get(name, {}), dict):
            raise ValueError(f"{source}: {name} must be a JSON object")
    model = data.get("position_model") or {}
    if model:
        mean = _array(model.get("joint_mean"), "position_model.joint_mean", source, (None,))
        joints = len(mean)
        scale = _array(model.get("joint_scale"), "position_model.joint_scale", source, (joints,))
        if not (scale != 0).all():
            raise ValueError(f"{source}: position_model.joint_scale must not hold 0")
        shape = (2, joints + 2, 2)
        _array(model.get("weights"), "position_model.weights", source, shape)
    visibility = data.get("visibility_model") or {}
    if visibility:
        _check_visibility(visibility, source)
    contingency = data.get("contingency_model") or {}
    if contingency:
        _check_contingency(contingency, source)


def _check_contingency(model: dict[str, Any], source: str) -> None:
    """The contingency model places both hands (:func:`contingency.check_contingency_model`)."""
    try:
        check_contingency_model(model)
    except ValueError as error:
        raise ValueError(f"{source}: {error}") from None
    except (KeyError, TypeError, IndexError):
        raise ValueError(
            f"{source}: contingency_model is damaged (its arrays must be finite and fit together)"
        ) from None


def _check_visibility(model: dict[str, Any], source: str) -> None:
    """The visibility model predicts finite probabilities for a posture (its arrays are read
    as :class:`~devlearn_hand_regard.attribution.VisibilityPredictor` reads them)."""
    try:
        predictor = VisibilityPredictor(model)
        joints = max((int(j.max()) for j in predictor.joints if j.size), default=-1)
        arrays = [*predictor.low, *predictor.high, *predictor.mean, *predictor.scale]
        arrays += predictor.weights
        finite = all(np.isfinite(a).all() for a in arrays)
        ok = finite and np.isfinite(predictor(np.zeros(joints + 1))).all()
    except (KeyError, TypeError, ValueError, IndexError):
        ok = False
    if not ok:
        raise ValueError(
            f"{source}: visibility_model is damaged (its arrays must be finite and fit together)"
        )


@dataclass
class Blob:
    """One connected hand-coloured region.

    Attributes:
        centroid: (x, y) in pixels.
        area: Pixels in the region.
        mask: (H, W) bool, the region's pixels.
    """

    centroid: tuple[float, float]
    area: float
    mask: np.ndarray


def colour_blobs(mask: np.ndarray, min_area: float, max_area: float, kernel: int) -> list[Blob]:
    """Clean a binary mask (opening, then closing) and return its blobs within an area range.

    Args:
        mask: (H, W) uint8 or bool.
        min_area: Smallest kept region, pixels.
        max_area: Largest kept region, pixels.
        kernel: Morphology kernel side, pixels.
    Returns:
        Blobs sorted by decreasing area.
    """
    element = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (kernel, kernel))
    clean: np.ndarray = mask.astype(np.uint8) * 255
    clean = cv2.morphologyEx(clean, cv2.MORPH_OPEN, element)  # removes specks
    clean = cv2.morphologyEx(clean, cv2.MORPH_CLOSE, element)  # fills small holes
    count, labels, stats, centroids = cv2.connectedComponentsWithStats(clean, connectivity=8)
    blobs = []
    for label in range(1, count):
        area = float(stats[label, cv2.CC_STAT_AREA])
        if min_area <= area <= max_area:
            x, y = map(float, centroids[label])
            blobs.append(Blob((x, y), area, labels == label))
    return sorted(blobs, key=lambda b: -b.area)


ATTRIBUTIONS = ("visibility", "position", "contingency")
"""How a detector says which blob is which hand when both mittens have one colour:
``visibility`` (issue #39): each hand's visibility predicted from its own arm's posture
(:mod:`devlearn_hand_regard.attribution`); ``position``: the image position each hand is
expected at (the posture model or the mean babbling positions, :meth:`HandDetector.attribute`),
the rule before issue #39; ``contingency`` (issue #58): a blob is a hand's only when it is
where that arm puts its hand and moves with that arm, else no side's
(:mod:`devlearn_hand_regard.contingency`)."""


class HandDetector:
    """Finds up to two hands per eye and says which is which.

    Args:
        params: Calibrated parameters; ``None`` gives a detector that never sees anything.
        max_hands: Most hands reported per eye (paper: 2).
        attribution: One of :data:`ATTRIBUTIONS`. ``visibility`` with parameters that have no
            visibility model (calibrated before issue #39, or babbling saw too few hands to
            learn one) falls back to ``position`` with a warning; :attr:`attribution` is the
            rule in use.
        pair_blobs: ``contingency`` only: credit two blobs to the two hands when each is
            within reach of one hand only (:data:`contingency.PAIR_BLOBS`).

    Raises:
        ValueError: An unknown attribution.
    """

    def __init__(
        self,
        params: DetectorParams | None,
        max_hands: int = 2,
        attribution: str = "position",
        pair_blobs: bool = PAIR_BLOBS,
    ) -> None:
        if attribution not in ATTRIBUTIONS:
            raise ValueError(
                f"unknown hand attribution '{attribution}'; valid: {', '.join(ATTRIBUTIONS)}"
            )
        if attribution == "visibility" and params is not None and not params.visibility_model:
            warnings.warn(
                "hand_regard: this hand detector has no visibility model (calibrated before "
                "issue #39, or babbling saw too few hands to learn one); it tells the left "
                "hand from the right by position (pair precision ~0.55 with both arms moving)",
                stacklevel=2,
            )
            attribution = "position"
        if attribution == "contingency" and params is not None and not params.contingency_model:
            raise ValueError(
                "hand attribution 'contingency' needs a detector with a contingency_model "
                "(a fresh run fits one after babbling; for a detector file: python -m "
                "devlearn_hand_regard.contingency_check fit); valid for this detector: "
                "visibility, position"
            )
        self.params = params
        self.max_hands = max_hands
        self.attribution = attribution
        self.pair_blobs = pair_blobs
        self._predictor: tuple[dict[str, Any], VisibilityPredictor] | None = None
        self._contingency = (
            ContingencyAttribution(params.contingency_model, pair_blobs=pair_blobs)
            if attribution == "contingency" and params is not None
            else None
        )

    def reset(self) -> None:
        """A new episode: the ``contingency`` rule forgets its blob tracks (no motion is
        compared across a reset)."""
        if self._contingency is not None:
            self._contingency.reset()

    def view_prior(self, proprioception: np.ndarray) -> np.ndarray | None:
        """P(eye e sees hand h | posture), (2 eyes, 2 hands), from the visibility model
        babbling learned (:mod:`attribution`); None without one. Compiled once per model."""
        model = self.params.visibility_model if self.params is not None else None
        if not model:
            return None
        if self._predictor is None or self._predictor[0] is not model:
            self._predictor = (model, VisibilityPredictor(model))
        return self._predictor[1](proprioception)

    def colour_mask(self, image: np.ndarray, side: int | None = None) -> np.ndarray:
        """Return (H, W) bool: pixels inside the learned hand colour boxes of an RGB image
        (``side`` 0 or 1: that hand's own boxes, ``side_hsv_ranges``)."""
        hsv = cv2.cvtColor(np.ascontiguousarray(image), cv2.COLOR_RGB2HSV)
        mask: np.ndarray = np.zeros(image.shape[:2], dtype=np.uint8)
        if self.params is None:
            boxes = []
        elif side is None:
            boxes = self.params.hsv_ranges
        else:
            boxes = self.params.side_hsv_ranges[side]
        for box in boxes:
            lo, hi = np.array(box[:3], np.uint8), np.array(box[3:], np.uint8)
            mask |= cv2.inRange(hsv, lo, hi)
        return mask > 0

    def blobs(self, image: np.ndarray, side: int | None = None) -> list[Blob]:
        """Return the hand blobs of one (H, W, 3) uint8 RGB image, largest first (at most
        ``max_hands``; with ``side``, the blobs of that hand's own colour)."""
        if self.params is None:
            return []
        scale = image.shape[0] * image.shape[1] / float(np.prod(self.params.image_size))
        found = colour_blobs(
            self.colour_mask(image, side),
            self.params.min_area * scale,
            self.params.max_area * scale,
            self.params.kernel,
        )
        return found[: self.max_hands]

    def expected_positions(self, eye: int, proprioception: np.ndarray | None) -> np.ndarray:
        """Return (2 hands, 2) where the left and right hand should appear in one eye, in
        pixels of the calibration image size.

        With proprioception and a learned ``position_model``: the posture's prediction (the
        hand's image position from the joint angles, learned while babbling). Otherwise the
        hands' mean babbling positions (``hand_means``).
        """
        params = self.params
        assert params is not None, "a detector without calibration expects no hand anywhere"
        model = params.position_model
        if proprioception is None or not model:
            return np.asarray(params.hand_means[eye], dtype=float)
        mean = np.asarray(model["joint_mean"])
        angles = np.asarray(proprioception, dtype=float)[: len(mean)]
        features = np.r_[1.0, eye - 0.5, (angles - mean) / np.asarray(model["joint_scale"])]
        return np.stack([features @ np.asarray(w) for w in model["weights"]])

    def attribute(
        self, blobs: list[Blob], eye: int, width: int, proprioception: np.ndarray | None = None
    ) -> list[Blob | None]:
        """Say which blob is the left and which the right hand, without ground truth.

        Rule: each hand has an expected image position (:meth:`expected_positions`: predicted
        from the posture when ``proprioception`` is given, else its mean babbling position).
        A hand whose expected position lies outside the image is never chosen: the posture
        says it is out of view, so a blob there is something else (or the other hand). Two
        blobs get the pairing with the smaller summed distance to those positions; one blob
        goes to the nearer hand. Positions are scaled from the calibration image size.

        Returns:
            [left-hand blob or None, right-hand blob or None].
        """
        if not blobs:
            return [None, None]
        height = blobs[0].mask.shape[0]
        means = self.expected_positions(eye, proprioception)
        assert self.params is not None  # blobs come only from a calibrated detector
        means = means * width / float(self.params.image_size[1])
        inside = (
            (means[:, 0] >= 0) & (means[:, 0] < width) & (means[:, 1] >= 0) & (means[:, 1] < height)
        )
        if not inside.any():
            return [None, None]
        pos = np.array([b.centroid for b in blobs])
        dist = np.linalg.norm(pos[:, None, :] - means[None, :, :], axis=-1)  # (blobs, 2 hands)
        if not inside.all():
            hand = int(np.flatnonzero(inside)[0])  # the only hand that can be in view
            out: list[Blob | None] = [None, None]
            out[hand] = blobs[int(np.argmin(dist[:, hand]))]
            return out
        if len(blobs) == 1:
            return [blobs[0], None] if dist[0, 0] <= dist[0, 1] else [None, blobs[0]]
        straight = dist[0, 0] + dist[1, 1]
        crossed = dist[0, 1] + dist[1, 0]
        return [blobs[0], blobs[1]] if straight <= crossed else [blobs[1], blobs[0]]

    def detect(
        self,
        eyes: np.ndarray,
        proprioception: np.ndarray | None = None,
        hands: list[int] | None = None,
        view_prior: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Detect and attribute the hands in both eyes: by each hand's own colour when the
        calibration learned two (``side_hsv_ranges``), else as ``attribution`` says: by the
        posture's predicted visibility (:meth:`attribute_by_visibility`), by position
        (:meth:`attribute`), or by place and motion (``contingency``: a stateful rule fed once
        per decision, :meth:`reset` at an episode's start; a blob no side is sure of is no
        hand's).

        Args:
            eyes: (2, H, W, 3) uint8 RGB, [left eye, right eye].
            proprioception: (P,) the infant's proprioception at the same step: with it the
                blobs are attributed by the posture (each hand's predicted visibility, or
                predicted position); without it by the hands' mean babbling positions.
            hands: The hands that can be in view (0 left, 1 right; default both): with one,
                the largest hand blob is that hand (a one-arm curriculum stage, the other
                arm hanging out of view).
            view_prior: :meth:`view_prior` of ``proprioception`` when the caller has it
                already (computed here otherwise).
        Returns:
            detections: (2 eyes, 2 hands) bool, hands ordered [left, right].
            masks: (2 eyes, 2 hands, H, W) bool, each detected hand's pixels.
        """
        n_eyes, height, width = eyes.shape[:3]
        detections = np.zeros((n_eyes, 2), dtype=bool)
        masks = np.zeros((n_eyes, 2, height, width), dtype=bool)
        by_colour = self.params is not None and bool(self.params.side_hsv_ranges)
        likelihood = None  # (2 eyes, 2 hands) P(eye sees hand | posture), when attributing so
        if self.attribution == "visibility" and self.params and proprioception is not None:
            likelihood = view_prior if view_prior is not None else self.view_prior(proprioception)
        credited = None  # (2 eyes, MAX_BLOBS) hand per blob, under ``contingency``
        found_by_eye: list[list[Blob]] = []
        if self._contingency is not None and proprioception is not None and not by_colour:
            found_by_eye = [self.blobs(eyes[eye])[:MAX_BLOBS] for eye in range(n_eyes)]
            rows = np.stack([blob_row(found) for found in found_by_eye])
            credited = self._contingency.step(rows, proprioception)
        for eye in range(n_eyes):
            attributed: list[list[Blob]]
            if by_colour:  # each hand is the largest blob of its own colour
                attributed = [self.blobs(eyes[eye], side)[:1] for side in range(2)]
            elif hands is not None and len(hands) == 1:
                attributed = [[], []]
                found = found_by_eye[eye] if found_by_eye else self.blobs(eyes[eye])
                attributed[hands[0]] = found[:1]
            elif credited is not None:
                attributed = [[], []]
                for blob, hand in zip(found_by_eye[eye], credited[eye]):
                    if hand >= 0:
                        attributed[hand].append(blob)
            elif likelihood is not None:
                attributed = self.attribute_by_visibility(
                    self.blobs(eyes[eye]), eye, likelihood[eye]
                )
            else:
                found = self.blobs(eyes[eye])
                single = self.attribute(found, eye, width, proprioception)
                attributed = [[blob] if blob is not None else [] for blob in single]
            for hand, blobs in enumerate(attributed):
                if blobs and (hands is None or hand in hands):
                    detections[eye, hand] = True
                    for blob in blobs:
                        masks[eye, hand] |= blob.mask
        return detections, masks

    def attribute_by_visibility(
        self, blobs: list[Blob], eye: int, likelihood: np.ndarray
    ) -> list[list[Blob]]:
        """Say which blobs are the left and which the right hand from the posture alone.

        :func:`attribution.assign` names the hands in view (the blob to the hand likelier in
        view; two blobs to both hands only when each is likelier in view than not, else both
        to the likelier hand, one hand split in two). Two hands in view take the blobs in the
        pairing closer to the hands' mean babbling positions (:meth:`attribute` without
        proprioception).

        Args:
            blobs: One eye's hand blobs, largest first.
            eye: Which eye (0 left, 1 right).
            likelihood: (2 hands,) P(this eye sees hand h) from the posture.
        Returns:
            [left-hand blobs, right-hand blobs].
        """
        in_view = assign(likelihood, len(blobs))
        if len(in_view) == 2:
            width = blobs[0].mask.shape[1]
            paired = self.attribute(blobs[:2], eye, width)
            return [[blob] if blob is not None else [] for blob in paired]
        out: list[list[Blob]] = [[], []]
        for hand in in_view:
            out[hand] = list(blobs)
        return out


class HandFlow:
    """Dense optical flow (Farneback, on grey frames) measured inside the hand regions.

    Keeps the previous step's grey frames; :meth:`reset` forgets them at episode start.
    """

    def __init__(self) -> None:
        self.previous: np.ndarray | None = None

    def reset(self) -> None:
        """Forget the previous frames (the next :meth:`update` measures no motion)."""
        self.previous = None

    def update(self, eyes: np.ndarray, masks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Measure the flow from the previous frames to ``eyes`` inside ``masks``.

        Args:
            eyes: (2, H, W, 3) uint8 RGB.
            masks: (2 eyes, 2 hands, H, W) bool hand regions in ``eyes``.
        Returns:
            flow: (2, 2) summed flow magnitude (pixels per step) over each hand's pixels.
            pixels: (2, 2) int, pixels in each hand region.
        """
        grey = np.stack([cv2.cvtColor(np.ascontiguousarray(e), cv2.COLOR_RGB2GRAY) for e in eyes])
        pixels = masks.sum(axis=(2, 3)).astype(np.int64)
        flow_sum = np.zeros(masks.shape[:2])
        if self.previous is not None and self.previous.shape == grey.shape:
            for eye in range(len(eyes)):
                if not pixels[eye].any():
                    continue
                flow = cv2.calcOpticalFlowFarneback(  # type: ignore[call-overload]  # flow=None: a new one
                    self.previous[eye], grey[eye], None, 0.5, 2, 9, 3, 5, 1.1, 0
                )
                magnitude = np.linalg.norm(flow, axis=-1)  # (H, W) pixels per step
                for hand in range(masks.shape[1]):
                    flow_sum[eye, hand] = float(magnitude[masks[eye, hand]].sum())
        else:
            pixels[:] = 0  # no previous frame: no motion measured this step
        self.previous = grey
        return flow_sum, pixels
