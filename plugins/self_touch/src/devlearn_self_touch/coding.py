"""Touches as an infant researcher's video coder counts them (issue #57): each limb's contacts
seen in 30 Hz frames, gaps shorter than two frames merged, one touch per contact bout.

Studies of infants' self-touch (DiMercurio, Connell, Clark and Corbetta 2018, *Frontiers in
Psychology* 9:2613) code touches from video: a coder steps through the frames of a 5-minute
session and notes each contact of a hand with the body or the supporting surface and where it
lands. The evaluation sees contacts at 200 Hz on 68 regions
(:class:`~devlearn_self_touch.evaluation.Likeness`), where a hand chattering in and out of
contact, or sliding over a region border, makes many onsets that a coder sees as one touch.
:class:`CodedTouches` counts them as the coder would:

1. **Frames.** The period after the settle steps is cut into frames of 1 / ``frame_rate`` s
   (30 Hz: physics step s falls in frame floor(s dt 30), computed in exact fractions); a
   frame shows a contact that held on any physics step within it (a frame integrates over its
   exposure, so a 5 ms brush shows as one frame).
2. **Bouts.** For each limb and kind of contact (``body``: the limb on the infant's own body;
   ``surface``: on the mattress or the crib, anything without skin; ``any``: either), a bout is
   a run of frames showing contact, after gaps shorter than ``min_gap_frames`` frames (2: a
   single empty frame, 33 ms) between two contact frames were filled.
3. **Touches.** One per bout that begins inside the coded period; a contact already there
   when coding starts is not one (as for :class:`Likeness`), though its frames count as time
   in contact. A touch's duration runs to its bout's end, or to the episode's end
   (``bouts_cut_by_end`` counts those). Its location is the area it touched in most frames
   (ties: the one touched first), on the coders' coarse areas (:data:`AREAS`) and, for the
   hands, on our 68 regions; successive touches of a limb give the transitions between areas.

Limbs (:data:`LIMBS`): both hands, their body contacts from ``facts["hand_contacts"]`` (palm
or fingers, the 68 regions the evaluation scores); their surface contacts and both feet from
the infant's MuJoCo contact list (:func:`contact_bodies`), which stand-in infants lack (then
only the hands' body contacts are coded). Everything is accumulated per episode and merged by
concatenation (:meth:`CodedTouches.merge`), so several envs summarise as one.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any

import numpy as np

from devlearn_self_touch.body_map import HANDS, NUM_REGIONS

FRAME_RATE = 30
"""Frames per second of the coder's video (30 Hz, the usual camera rate)."""
MIN_GAP_FRAMES = 2
"""Gaps shorter than this many frames between two contact frames are merged into one bout
(2: a single empty frame is coding noise, two or more part touches)."""
AREAS = ("head_face", "trunk", "arms", "hands", "legs", "feet")
"""The coarse body areas infant researchers code touches on (head and face, trunk, arms,
hands, legs, feet)."""
LIMBS = ("left_hand", "right_hand", "left_foot", "right_foot")
"""Limbs whose touches are coded: the hands (rows 0, 1, as ``HANDS``) and the feet."""
KINDS = ("body", "surface", "any")
"""What a limb touches: its own body, the surface (mattress, crib), or either."""
HAND_PARTS = ("palm", "back_of_hand", "fingers_inner", "fingers_outer")
"""Arm parts of the region table that the coders' ``hands`` area holds."""
CATEGORY_AREA = {
    "face": "head_face",
    "torso": "trunk",
    "arm": "arms",
    "leg": "legs",
    "foot": "feet",
}
"""Area of each region category of the infant's table (arm parts in :data:`HAND_PARTS`:
``hands``)."""
BODY_AREA = {
    "head": "head_face",
    "eye": "head_face",
    "hip": "trunk",
    "lower_body": "trunk",
    "upper_body": "trunk",
    "upper_arm": "arms",
    "lower_arm": "arms",
    "hand": "hands",
    "fingers": "hands",
    "upper_leg": "legs",
    "lower_leg": "legs",
    "foot": "feet",
    "toes": "feet",
}
"""Area of each of the infant's bodies (side-free MuJoCo body names); any other body (the
world: mattress, crib) is surface."""
LIMB_BODIES = {"hand": "hand", "fingers": "hand", "foot": "foot", "toes": "foot"}
"""Bodies that make up a limb: a hand is its palm and fingers, a foot its foot and toes."""


def region_areas(regions: Any) -> np.ndarray:
    """Coarse area index (into :data:`AREAS`) of each of the 68 regions, (68,) int.

    Args:
        regions: The infant's region table: ``names`` ("left_palm") and ``categories`` (face,
            torso, arm, leg or foot) of every region.
    """
    areas = [
        AREAS.index("hands" if str(n).partition("_")[2] in HAND_PARTS else CATEGORY_AREA[str(c)])
        for c, n in zip(regions.categories, regions.names)
    ]
    return np.asarray(areas, dtype=np.int64)


def body_codes(body_names: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Limb and area of every MuJoCo body, from its name.

    Returns:
        ``limb`` (nbody,) int, index into :data:`LIMBS` (-1: not a limb) and ``area``
        (nbody,) int, index into :data:`AREAS` (-1: not the infant's: surface).
    """
    limb = np.full(len(body_names), -1, dtype=np.int64)
    area = np.full(len(body_names), -1, dtype=np.int64)
    for b, name in enumerate(body_names):
        side, _, rest = name.partition("_")
        free = rest if side in HANDS else name
        if free in BODY_AREA:
            area[b] = AREAS.index(BODY_AREA[free])
        if side in HANDS and free in LIMB_BODIES:
            limb[b] = LIMBS.index(f"{side}_{LIMB_BODIES[free]}")
    return limb, area


def model_body_codes(model: Any) -> tuple[np.ndarray, np.ndarray]:
    """:func:`body_codes` of every body of a MuJoCo model, by their names."""
    return body_codes([model.body(b).name for b in range(model.nbody)])


def contact_bodies(infant: Any) -> np.ndarray | None:
    """The bodies of this step's active contacts, (m, 2) int, from the infant's MuJoCo
    contact list (contacts without force, excluded or gap contacts, left out); None for an
    infant without one (a stand-in)."""
    model, data = getattr(infant, "model", None), getattr(infant, "data", None)
    if model is None or data is None or not hasattr(data, "contact"):
        return None
    contact = data.contact
    geom = np.asarray(contact.geom).reshape(-1, 2)
    active = np.asarray(contact.efc_address).reshape(-1) >= 0
    return np.asarray(model.geom_bodyid)[geom[active]]


def limb_contacts(
    pairs: np.ndarray, limb_of_body: np.ndarray, area_of_body: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """What each limb touches in one step's contacts.

    Args:
        pairs: (m, 2) body ids in contact (:func:`contact_bodies`).
        limb_of_body, area_of_body: :func:`body_codes`.

    Returns:
        ``areas`` (4, 6) bool: limb (:data:`LIMBS`) touches a body in area (:data:`AREAS`),
        its own bodies left out; ``surface`` (4,) bool: limb touches a body that is not the
        infant's.
    """
    areas = np.zeros((len(LIMBS), len(AREAS)), dtype=bool)
    surface = np.zeros(len(LIMBS), dtype=bool)
    for side in (0, 1):
        limb = limb_of_body[pairs[:, side]]
        other = pairs[:, 1 - side]
        use = (limb >= 0) & (limb_of_body[other] != limb)
        area = area_of_body[other]
        on_body = use & (area >= 0)
        areas[limb[on_body], area[on_body]] = True
        surface[limb[use & (area < 0)]] = True
    return areas, surface


def filled(on: np.ndarray, shorter_than: int) -> np.ndarray:
    """``on`` (frames,) bool with every run of empty frames shorter than ``shorter_than``
    between two contact frames set (merged into one bout); runs at either end stay."""
    out = np.array(on, dtype=bool)
    frames = np.flatnonzero(out)
    for before, after in zip(frames[:-1], frames[1:]):
        if 1 < after - before <= shorter_than:  # after - before - 1 empty frames between
            out[before + 1 : after] = True
    return out


def bouts(on: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Runs of contact frames: their first frames and stops (exclusive), (n,) int each."""
    edges = np.diff(np.concatenate([[0], np.asarray(on, dtype=np.int8), [0]]))
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)


def dominant(where: np.ndarray) -> int:
    """The column ``where`` ((frames, k) bool, one bout's frames) is set in most often; ties:
    the one set first. -1 when none is set."""
    counts = where.sum(axis=0)
    if not counts.any():
        return -1
    best = np.flatnonzero(counts == counts.max())
    first = [int(np.argmax(where[:, j])) for j in best]
    return int(best[int(np.argmin(first))])


class _Stream:
    """The coded figures of one limb and kind of contact, summed over episodes (integers and
    frame counts in episode order, so that :meth:`merge` is exact)."""

    def __init__(self, areas: int = 0, regions: int = 0) -> None:
        self.frames = self.on_frames = self.touches = self.cut_by_end = 0
        self.durations: list[int] = []  # frames of each touch, in order
        self.gaps: list[int] = []  # empty frames between successive bouts of an episode
        self.touch_areas = np.zeros(areas, dtype=np.int64)
        self.area_frames = np.zeros(areas, dtype=np.int64)
        self.transitions = np.zeros((areas, areas), dtype=np.int64)
        self.touch_regions = np.zeros(regions, dtype=np.int64)

    def code(
        self, on: np.ndarray, shorter_than: int, areas: Any = None, regions: Any = None
    ) -> np.ndarray:
        """Code one episode's frames: ``on`` (F,) bool, ``areas`` (F, 6) and ``regions``
        (F, 68) bool where known. Returns the bouts' frames (gaps filled), (F,) bool."""
        coded = filled(on, shorter_than)
        starts, stops = bouts(coded)
        self.frames += len(on)
        self.on_frames += int(coded.sum())
        self.gaps += (starts[1:] - stops[:-1]).tolist()
        seen = starts > 0  # a contact there when coding began is not a touch
        self.touches += int(seen.sum())
        self.cut_by_end += int((stops[seen] == len(on)).sum())
        self.durations += (stops[seen] - starts[seen]).tolist()
        if areas is not None and self.touch_areas.size:
            self.area_frames += areas.sum(axis=0)
            located = [dominant(areas[a:b]) for a, b in zip(starts[seen], stops[seen])]
            for here in located:
                if here >= 0:
                    self.touch_areas[here] += 1
            for here, there in zip(located[:-1], located[1:]):
                if here >= 0 and there >= 0:
                    self.transitions[here, there] += 1
        if regions is not None and self.touch_regions.size:
            for a, b in zip(starts[seen], stops[seen]):
                if (j := dominant(regions[a:b])) >= 0:
                    self.touch_regions[j] += 1
        return coded

    def merge(self, later: _Stream) -> None:
        self.frames += later.frames
        self.on_frames += later.on_frames
        self.touches += later.touches
        self.cut_by_end += later.cut_by_end
        self.durations += later.durations
        self.gaps += later.gaps
        self.touch_areas += later.touch_areas
        self.area_frames += later.area_frames
        self.transitions += later.transitions
        self.touch_regions += later.touch_regions


def _seconds(frames: list[int], rate: int) -> tuple[float | None, float | None]:
    """Mean and sample standard deviation of frame counts, in seconds (None where undefined)."""
    x = np.asarray(frames, dtype=np.float64) / rate
    mean = float(x.mean()) if x.size else None
    return mean, float(x.std(ddof=1)) if x.size > 1 else None


def _figures(streams: list[_Stream], minutes: float, rate: int) -> dict[str, Any]:
    """Touch figures of one or more streams pooled (touches summed, bouts and gaps joined)."""
    touches = sum(s.touches for s in streams)
    frames = sum(s.frames for s in streams)
    durations = [d for s in streams for d in s.durations]
    gaps = [g for s in streams for g in s.gaps]
    mean, std = _seconds(durations, rate)
    between = _seconds(gaps, rate)[0]
    return {
        "touches": touches,
        "touches_per_minute": touches / minutes if minutes else None,
        "contact_time_share": sum(s.on_frames for s in streams) / frames if frames else None,
        "bout_seconds_mean": mean,
        "bout_seconds_std": std,
        "bouts_cut_by_end": sum(s.cut_by_end for s in streams),
        "seconds_between_touches_mean": between,
        "between_touches_time_share": sum(gaps) / frames if frames else None,
    }


def _by_area(counts: np.ndarray) -> dict[str, int]:
    return {area: int(n) for area, n in zip(AREAS, counts)}


def _shares(counts: np.ndarray, total: int) -> dict[str, float | None]:
    return {area: (int(n) / total if total else None) for area, n in zip(AREAS, counts)}


class CodedTouches:
    """Touches as a video coder counts them (module docstring): frames at ``frame_rate``,
    gaps shorter than ``min_gap_frames`` merged, one touch per bout, per limb and kind.

    Feed it every recorded step (:meth:`record`), close each episode (:meth:`end_episode`),
    then read :meth:`summary` (eval.json's ``likeness_coded``).

    Args:
        frame_rate: Frames per second (Hz).
        min_gap_frames: Gaps shorter than this many frames are merged.
    """

    def __init__(self, frame_rate: int = FRAME_RATE, min_gap_frames: int = MIN_GAP_FRAMES) -> None:
        if frame_rate < 1 or min_gap_frames < 1:
            raise ValueError(
                f"frame_rate and min_gap_frames must be at least 1, got {frame_rate}, "
                f"{min_gap_frames}"
            )
        self.frame_rate, self.min_gap_frames = int(frame_rate), int(min_gap_frames)
        self.streams = {
            (limb, kind): _Stream(len(AREAS), NUM_REGIONS if limb.endswith("hand") else 0)
            for limb in LIMBS
            for kind in KINDS
        }
        self.either_hand = _Stream(len(AREAS))  # frames where either hand touches the body
        self.steps = self.episodes = 0
        self.dt: float | None = None  # seconds per recorded step (the physics step)
        self.blind_steps = 0  # coded steps without a contact list (no surface, no feet)
        self.region_area: np.ndarray | None = None  # (68,) area of each region, when known
        self.region_names: list[str] | None = None  # the 68 regions' names, when known
        self._bodies: tuple[int, np.ndarray, np.ndarray] | None = None  # (model id, limb, area)
        self._open()

    def _open(self) -> None:
        """Start an episode: no frame yet."""
        self._step = 0  # coded steps of this episode
        self._frame = -1  # index of the frame being filled
        self._rows: list[np.ndarray] = []  # closed frames' hand regions (2, 68)
        self._limbs: list[np.ndarray] = []  # closed frames' (4, 6 areas + surface)
        self._regions = np.zeros((len(HANDS), NUM_REGIONS), dtype=bool)
        self._areas = np.zeros((len(LIMBS), len(AREAS) + 1), dtype=bool)
        self._per_step: Fraction | None = None
        self._blind = False

    def see_infant(self, infant: Any) -> None:
        """Take the region table's areas and the body names of the infant recorded (once per
        body: a growing body is rebuilt)."""
        regions = getattr(infant, "regions", None)
        if self.region_names is None and regions is not None:
            self.region_names = [str(n) for n in regions.names]
            if hasattr(regions, "categories"):
                self.region_area = region_areas(regions)
        model = getattr(infant, "model", None)
        if model is not None and (self._bodies is None or self._bodies[0] != id(model)):
            self._bodies = (id(model), *model_body_codes(model))

    def record(self, hand_contacts: np.ndarray, infant: Any, dt: float) -> None:
        """One coded step: the hands' (2, 68) region contacts, the infant (for its contact
        list; None or a stand-in: hands' body contacts only) and the step's length (s)."""
        if self._per_step is None:  # frames per step, exact: 0.005 s at 30 Hz is 3/20
            self._per_step = Fraction(dt).limit_denominator(10**9) * self.frame_rate
            self.dt = float(dt)
        frame = int(self._step * self._per_step)
        if frame != self._frame:
            self._close_frame()
            self._frame = frame
        self._regions |= hand_contacts
        pairs = contact_bodies(infant) if infant is not None else None
        if pairs is None or self._bodies is None:
            self._blind = True
        else:
            areas, surface = limb_contacts(pairs, self._bodies[1], self._bodies[2])
            self._areas[2:, :-1] |= areas[2:]  # the feet; the hands' body areas: their regions
            self._areas[:, -1] |= surface
        self._step += 1

    def _close_frame(self) -> None:
        if self._frame < 0:
            return
        self._rows.append(self._regions.copy())
        self._limbs.append(self._areas.copy())
        self._regions[:] = False
        self._areas[:] = False

    def end_episode(self) -> None:
        """Code the episode's frames into every stream."""
        self._close_frame()
        if self._rows:
            self._code(np.stack(self._rows), np.stack(self._limbs))
            self.steps += self._step
            self.episodes += 1
            self.blind_steps += self._step if self._blind else 0
        self._open()

    def _code(self, regions: np.ndarray, limbs: np.ndarray) -> None:
        """Code frames ``regions`` (F, 2, 68) and ``limbs`` (F, 4, 7: areas, then surface)."""
        gap = self.min_gap_frames
        if self.region_area is not None:  # the hands' areas from the regions they touch
            for h in range(len(HANDS)):
                for a in range(len(AREAS)):
                    limbs[:, h, a] = regions[:, h, self.region_area == a].any(axis=1)
        areas = None if self.region_area is None else limbs[:, :, :-1]
        either = np.zeros(len(regions), dtype=bool)
        for i, limb in enumerate(LIMBS):
            hand = i < len(HANDS)
            body = np.asarray((regions[:, i] if hand else limbs[:, i, :-1]).any(axis=1))
            where = None if areas is None else areas[:, i]
            coded = self.streams[limb, "body"].code(
                body, gap, where, regions[:, i] if hand else None
            )
            if hand:
                either |= coded
            surface = limbs[:, i, -1]
            self.streams[limb, "surface"].code(surface, gap)
            self.streams[limb, "any"].code(body | surface, gap)
        both = None if areas is None else areas[:, : len(HANDS)].any(axis=1)
        self.either_hand.frames += len(either)
        self.either_hand.on_frames += int(either.sum())
        if both is not None:
            self.either_hand.area_frames += both.sum(axis=0)

    def merge(self, later: CodedTouches) -> None:
        """Add ``later``'s episodes after this one's (neither has an episode open)."""
        for key, stream in self.streams.items():
            stream.merge(later.streams[key])
        self.either_hand.merge(later.either_hand)
        self.steps += later.steps
        self.episodes += later.episodes
        self.blind_steps += later.blind_steps
        if self.region_names is None:
            self.region_area, self.region_names = later.region_area, later.region_names
        if self.dt is None:
            self.dt = later.dt

    def summary(self) -> dict[str, Any]:
        """The coded figures (eval.json's ``likeness_coded``).

        Headline figures are both hands' body touches: ``touches_per_minute`` (left + right
        touches per coded minute), ``contact_time_share`` (share of frames in which either hand
        touches the body), ``bout_seconds_mean`` / ``_std`` (over both hands' touches),
        ``seconds_between_touches_mean`` and ``between_touches_time_share`` (each hand's time
        between two of its bouts, over both hands' time), ``touches_by_area``,
        ``touch_share_by_area``, ``time_share_by_area`` (frames in which either hand touches
        the area) and ``transitions`` (from one touch's area to the same hand's next touch's,
        both hands summed). ``surface_touches_per_minute`` and ``all_touches_per_minute`` (body
        or surface: comparable with the infants' counts, which include the surface) need the
        contact list. ``limbs`` has every limb's ``body``, ``surface`` and ``any`` figures
        (the feet's only with the contact list), the hands' touches by region.
        """
        rate = self.frame_rate
        seconds = self.steps * (self.dt or 0.0)  # one step length for every episode
        minutes = seconds / 60
        seen = self.blind_steps == 0 and self.steps > 0  # surfaces and feet were coded
        hands = [self.streams[h, "body"] for h in LIMBS[: len(HANDS)]]
        out: dict[str, Any] = {
            "frame_rate": rate,
            "merge_gaps_shorter_than_frames": self.min_gap_frames,
            "episodes": self.episodes,
            "coded_seconds": seconds,
            "surfaces_and_feet": seen,
        }
        both = _figures(hands, minutes, rate)
        out.update(
            touches=both["touches"],
            touches_per_minute=both["touches_per_minute"],
            contact_time_share=(
                self.either_hand.on_frames / self.either_hand.frames
                if self.either_hand.frames
                else None
            ),
            bout_seconds_mean=both["bout_seconds_mean"],
            bout_seconds_std=both["bout_seconds_std"],
            seconds_between_touches_mean=both["seconds_between_touches_mean"],
            between_touches_time_share=(
                sum(sum(s.gaps) for s in hands) / sum(s.frames for s in hands)
                if self.either_hand.frames
                else None
            ),
        )
        for kind, key in (("surface", "surface"), ("any", "all")):
            streams = [self.streams[h, kind] for h in LIMBS[: len(HANDS)]]
            out[f"{key}_touches_per_minute"] = (
                _figures(streams, minutes, rate)["touches_per_minute"] if seen else None
            )
        if self.region_area is not None:
            areas = hands[0].touch_areas + hands[1].touch_areas
            out["touches_by_area"] = _by_area(areas)
            out["touch_share_by_area"] = _shares(areas, int(areas.sum()))
            out["time_share_by_area"] = _shares(
                self.either_hand.area_frames, self.either_hand.frames
            )
            out["transitions"] = {
                here: _by_area(row)
                for here, row in zip(AREAS, hands[0].transitions + hands[1].transitions)
            }
        names = self.region_names or [f"region_{j:02d}" for j in range(NUM_REGIONS)]
        limbs: dict[str, Any] = {}
        for limb in LIMBS if seen else LIMBS[: len(HANDS)]:
            figures: dict[str, Any] = {}
            for kind in KINDS if seen else ("body",):
                stream = self.streams[limb, kind]
                figures[kind] = _figures([stream], minutes, rate)
            body = self.streams[limb, "body"]
            if self.region_area is not None:
                figures["body"]["touches_by_area"] = _by_area(body.touch_areas)
                figures["body"]["time_share_by_area"] = _shares(body.area_frames, body.frames)
                figures["body"]["transitions"] = {
                    here: _by_area(row) for here, row in zip(AREAS, body.transitions)
                }
            if body.touch_regions.size:
                figures["body"]["touches_by_region"] = {
                    names[j]: int(n) for j, n in enumerate(body.touch_regions) if n
                }
            limbs[limb] = figures
        out["limbs"] = limbs
        return out
