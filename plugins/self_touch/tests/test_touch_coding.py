"""Touches as a video coder counts them (issue #57): scripted contact sequences whose coded
touches are known by hand."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest
from devlearn_self_touch import SelfTouch, SelfTouchEvaluator
from devlearn_self_touch.coding import (
    AREAS,
    LIMBS,
    CodedTouches,
    body_codes,
    filled,
    limb_contacts,
    region_areas,
)
from devlearn_self_touch.evaluation import Likeness
from self_touch_fakes import ScriptedInfant

from devlearn import StepContext
from devlearn.testing import check_evaluator_merge, evaluate_policy, registry_for

DT = 0.005  # 200 Hz: physics step s falls in 30 Hz frame floor(0.15 s)
LAYOUT = (
    ("face", ("forehead", "cheek", "mouth", "ear", "back_of_head")),
    ("torso", ("chest", "upper_back", "flank", "belly", "lower_back", "pelvis", "buttock")),
    ("arm", ("shoulder", "upper_arm_inner", "upper_arm_outer", "forearm_inner", "forearm_outer",
             "palm", "back_of_hand", "fingers_inner", "fingers_outer")),
    ("leg", ("thigh_front", "thigh_back", "thigh_inner", "thigh_outer", "knee", "shin", "calf",
             "lower_leg_inner", "lower_leg_outer")),
    ("foot", ("sole", "heel", "top_of_foot", "toes")),
)  # fmt: skip
"""The infant's region layout (``devlearn.infant.regions``): 34 parts per side, in order."""


def layout_regions() -> SimpleNamespace:
    """A region table with the infant's layout: region j = side * 34 + part."""
    parts = [p for _, ps in LAYOUT for p in ps]
    categories = [c for c, ps in LAYOUT for _ in ps]
    return SimpleNamespace(
        names=np.array([f"{s}_{parts[j % 34]}" for s in ("left", "right") for j in range(34)]),
        sides=np.repeat(np.array(["left", "right"]), 34),
        parts=np.tile(np.arange(34), 2),
        part_names=np.array(parts),
        categories=np.array(categories * 2),
    )


REGIONS = layout_regions()
CHEEK, CHEST, FOREARM, THIGH = (
    int(np.flatnonzero(REGIONS.names == f"left_{name}")[0])
    for name in ("cheek", "chest", "forearm_inner", "thigh_front")
)


def play(coder: CodedTouches, left_on, steps: int, dt: float = DT, region: int = FOREARM):
    """One episode of ``steps`` coded steps: the left hand touches ``region`` on the steps in
    ``left_on`` (a set, or step -> region), nothing else touches."""
    for s in range(steps):
        contacts = np.zeros((2, 68), dtype=bool)
        if s in left_on:
            contacts[0, left_on[s] if isinstance(left_on, dict) else region] = True
        coder.record(contacts, None, dt)
    coder.end_episode()
    return coder.summary()


def test_chattering_at_200_hz_is_one_coded_touch():
    # On and off at every physics step from step 20 to 199 (frames 3 to 29), then still:
    # 90 onsets at 200 Hz, one touch in 30 Hz frames, lasting frames 3-29 (27 frames).
    chatter = set(range(20, 200, 2))
    coded = play(CodedTouches(), chatter, 300)  # 1.5 s: frames 0-44
    assert coded["touches"] == 1
    assert coded["bout_seconds_mean"] == pytest.approx(27 / 30)
    assert coded["bout_seconds_std"] is None  # one bout: no spread
    assert coded["contact_time_share"] == pytest.approx(27 / 45)
    assert coded["touches_per_minute"] == pytest.approx(1 / (1.5 / 60))
    assert coded["coded_seconds"] == pytest.approx(1.5)
    assert coded["limbs"]["left_hand"]["body"]["touches"] == 1
    assert coded["limbs"]["right_hand"]["body"]["touches"] == 0
    assert not coded["surfaces_and_feet"] and coded["all_touches_per_minute"] is None
    # the 200 Hz onset count sees 90 touches in the same steps
    likeness = Likeness()
    for s in range(300):
        contacts = np.zeros((2, 68), dtype=bool)
        contacts[0, FOREARM] = s in chatter
        likeness.record(contacts, counted=True)
    likeness.end_episode(DT)
    assert likeness.summary(None)["touches"] == 90


@pytest.mark.parametrize(
    ("gap", "touches", "bouts", "between"),
    [
        (range(67, 74), 1, [16], []),  # frame 10 empty: merged into one touch, frames 3-18
        (range(67, 80), 2, [7, 7], [2]),  # frames 10-11 empty: two touches, 3-9 and 12-18
        (range(67, 87), 2, [7, 6], [3]),  # frames 10-12 empty: two touches, 3-9 and 13-18
    ],
)
def test_a_one_frame_gap_merges_and_wider_gaps_do_not(gap, touches, bouts, between):
    # In contact from step 20 (frame 3) to step 120 (frame 18) but for the steps of ``gap``.
    on = set(range(20, 121)) - set(gap)
    coded = play(CodedTouches(), on, 200)  # frames 0-29
    assert coded["touches"] == touches
    assert coded["bout_seconds_mean"] == pytest.approx(np.mean(bouts) / 30)
    if len(bouts) > 1:
        assert coded["bout_seconds_std"] == pytest.approx(np.std(bouts, ddof=1) / 30)
    left = coded["limbs"]["left_hand"]["body"]
    assert left["seconds_between_touches_mean"] == (between[0] / 30 if between else None)
    assert left["between_touches_time_share"] == pytest.approx(sum(between) / 30)
    assert left["contact_time_share"] == pytest.approx(sum(bouts) / 30)


def test_gap_filling_by_hand():
    on = np.array([0, 1, 0, 1, 0, 0, 1, 0, 0, 0, 1, 0], dtype=bool)
    assert filled(on, 2).astype(int).tolist() == [0, 1, 1, 1, 0, 0, 1, 0, 0, 0, 1, 0]
    assert filled(on, 3).astype(int).tolist() == [0, 1, 1, 1, 1, 1, 1, 0, 0, 0, 1, 0]


def test_a_contact_there_when_coding_starts_is_no_touch_but_is_contact_time():
    coded = play(CodedTouches(), set(range(0, 100)), 200)  # frames 0-14 of 0-29
    assert coded["touches"] == 0 and coded["bout_seconds_mean"] is None
    assert coded["contact_time_share"] == pytest.approx(15 / 30)
    # a touch still going at the episode's end is counted, its duration cut there
    coded = play(CodedTouches(), set(range(100, 200)), 200)  # frames 15-29
    assert coded["touches"] == 1 and coded["limbs"]["left_hand"]["body"]["bouts_cut_by_end"] == 1
    assert coded["bout_seconds_mean"] == pytest.approx(15 / 30)


def test_areas_locations_and_transitions_on_the_coarse_coding():
    # One step per frame (dt = 1/30 s): the cheek (frames 2-4), the chest (8-9), then a slide
    # from the forearm (12) to the thigh (13-15) in one bout, whose location is the thigh.
    script = {2: CHEEK, 3: CHEEK, 4: CHEEK, 8: CHEST, 9: CHEST, 12: FOREARM}
    script |= {13: THIGH, 14: THIGH, 15: THIGH}
    coder = CodedTouches()
    coder.see_infant(SimpleNamespace(regions=REGIONS))
    coded = play(coder, script, 20, dt=1 / 30)
    assert coded["touches"] == 3
    assert coded["touches_by_area"] == {a: int(a in ("head_face", "trunk", "legs")) for a in AREAS}
    assert coded["touch_share_by_area"]["legs"] == pytest.approx(1 / 3)
    assert coded["time_share_by_area"]["head_face"] == pytest.approx(3 / 20)
    assert coded["time_share_by_area"]["arms"] == pytest.approx(1 / 20)
    moves = {(a, b): n for a, row in coded["transitions"].items() for b, n in row.items() if n}
    assert moves == {("head_face", "trunk"): 1, ("trunk", "legs"): 1}
    assert coded["limbs"]["left_hand"]["body"]["touches_by_region"] == {
        "left_cheek": 1,
        "left_chest": 1,
        "left_thigh_front": 1,
    }


def test_region_areas_follow_the_coders_coarse_coding():
    areas = [AREAS[a] for a in region_areas(REGIONS)[:34]]
    assert areas[:5] == ["head_face"] * 5 and areas[5:12] == ["trunk"] * 7
    assert areas[12:17] == ["arms"] * 5 and areas[17:21] == ["hands"] * 4
    assert areas[21:30] == ["legs"] * 9 and areas[30:] == ["feet"] * 4


NAMES = ["world", "hip", "head", "left_upper_arm", "left_hand", "left_fingers", "right_hand",
         "right_fingers", "right_lower_leg", "left_foot", "left_toes", "right_foot"]  # fmt: skip
B = {name: b for b, name in enumerate(NAMES)}


def test_limb_contacts_tell_body_from_surface_and_code_the_feet():
    limb, area = body_codes(NAMES)
    assert [LIMBS[i] for i in limb[limb >= 0]] == [
        "left_hand", "left_hand", "right_hand", "right_hand", "left_foot", "left_foot",
        "right_foot",
    ]  # fmt: skip
    pairs = np.array(
        [
            [B["world"], B["left_fingers"]],  # the left hand on the mattress
            [B["left_hand"], B["left_fingers"]],  # its own fingers: nothing
            [B["right_hand"], B["left_upper_arm"]],  # the right hand on the left arm
            [B["left_toes"], B["right_lower_leg"]],  # the left foot on the right leg
            [B["head"], B["left_foot"]],  # and on the head
            [B["right_foot"], B["world"]],  # the right foot on the mattress
        ]
    )
    areas, surface = limb_contacts(pairs, limb, area)
    touched = {(LIMBS[i], AREAS[a]) for i, a in zip(*np.nonzero(areas))}
    assert touched == {
        ("right_hand", "arms"),
        ("left_foot", "legs"),
        ("left_foot", "head_face"),
    }
    assert surface.tolist() == [True, False, False, True]


class ContactListInfant:
    """A stand-in with a MuJoCo-like contact list (geom g is body g), set per step."""

    def __init__(self) -> None:
        self.model = SimpleNamespace(
            nbody=len(NAMES),
            body=lambda b: SimpleNamespace(name=NAMES[b]),
            geom_bodyid=np.arange(len(NAMES)),
        )
        self.regions = REGIONS
        self.touching([])

    def touching(self, pairs: list[tuple[str, str]]) -> None:
        geom = np.array([[B[a], B[b]] for a, b in pairs], dtype=np.int64).reshape(-1, 2)
        self.data = SimpleNamespace(
            contact=SimpleNamespace(geom=geom, efc_address=np.zeros(len(geom), dtype=np.int64))
        )


def test_surface_touches_and_feet_are_coded_apart_from_body_touches():
    # One step per frame. The left hand: on the mattress (frames 2-5), then on the chest
    # (frames 8-10). The left foot: on the right leg (frames 4-6).
    infant = ContactListInfant()
    coder = CodedTouches()
    coder.see_infant(infant)
    for frame in range(20):
        pairs = [("world", "left_fingers")] if 2 <= frame <= 5 else []
        if 4 <= frame <= 6:
            pairs.append(("left_toes", "right_lower_leg"))
        infant.touching(pairs)
        contacts = np.zeros((2, 68), dtype=bool)
        contacts[0, CHEST] = 8 <= frame <= 10
        coder.record(contacts, infant, 1 / 30)
    coder.end_episode()
    coded = coder.summary()
    assert coded["surfaces_and_feet"]
    left = coded["limbs"]["left_hand"]
    assert left["body"]["touches"] == 1 and left["surface"]["touches"] == 1
    assert left["any"]["touches"] == 2  # frames 2-5 and 8-10: two bouts
    assert left["surface"]["bout_seconds_mean"] == pytest.approx(4 / 30)
    assert left["any"]["contact_time_share"] == pytest.approx(7 / 20)
    foot = coded["limbs"]["left_foot"]["body"]
    assert foot["touches"] == 1 and foot["touches_by_area"]["legs"] == 1
    assert coded["touches"] == 1  # the headline: both hands on the body
    assert coded["surface_touches_per_minute"] == pytest.approx(1 / (20 / 30 / 60))
    assert coded["all_touches_per_minute"] == pytest.approx(2 / (20 / 30 / 60))


@pytest.mark.slow
def test_the_real_infants_contact_list_at_rest():
    # Lying still, both hands rest on the mattress (their outer fingers) and touch no body.
    from devlearn import build_infant

    infant = build_infant("crib", senses=("touch", "proprioception"))
    try:
        for _ in range(50):
            infant.step(np.zeros(infant.action_dim))
        coder = CodedTouches()
        coder.see_infant(infant)
        from devlearn_self_touch.coding import contact_bodies

        limb, area = coder._bodies[1:]  # the infant's body names coded
        assert {LIMBS[i] for i in limb[limb >= 0]} == set(LIMBS)
        areas, surface = limb_contacts(contact_bodies(infant), limb, area)
        assert surface[:2].all() and not areas[:2].any()
        assert not infant.hand_contacts().any()
    finally:
        infant.close()


def ctx(step: int, contacts: np.ndarray, infant, last: bool = False) -> StepContext:
    return StepContext(
        infant=infant,
        observations={},
        facts={"hand_contacts": contacts, "hand_parts": np.zeros((2, 34), dtype=bool)},
        step=step,
        last_step=last,
    )


def test_the_evaluator_reports_and_merges_the_coded_touches():
    """eval.json's ``likeness_coded``: after the 10 settle steps; episodes merged as one."""
    infant = SimpleNamespace(regions=REGIONS, physics_timestep=DT)

    def episode(evaluator, start: int) -> None:
        for step in range(210):  # 200 coded steps: frames 0-29
            contacts = np.zeros((2, 68), dtype=bool)
            contacts[1, CHEEK] = start <= step < start + 60  # right hand, 9-10 frames
            evaluator.record(ctx(step, contacts, infant, step == 209))
        evaluator.end_episode()

    whole, first, second = (SelfTouchEvaluator(training=False) for _ in range(3))
    for evaluator, starts in ((whole, (40, 80, 150)), (first, (40, 80)), (second, (150,))):
        for start in starts:
            episode(evaluator, start)
    check_evaluator_merge([first, second], whole)
    coded = json.loads(json.dumps(whole.summary()))["likeness_coded"]
    # coded steps 30-89, 70-129, 140-199: frames 4-13, 10-19, 21-29 (10, 10, 9 frames)
    assert coded["touches"] == 3 and coded["episodes"] == 3
    assert coded["touches_per_minute"] == pytest.approx(3 / (3 * 200 * DT / 60))
    assert coded["bout_seconds_mean"] == pytest.approx(29 / 3 / 30)
    assert coded["contact_time_share"] == pytest.approx(29 / 90)
    assert coded["limbs"]["right_hand"]["body"]["touches_by_region"] == {"left_cheek": 3}
    assert coded["touches_by_area"]["head_face"] == 3
    assert whole.protocol()["criteria"]["coded_touch"].startswith("a bout")


def test_devlearn_eval_writes_the_coded_touches_with_any_number_of_envs():
    """``devlearn eval``'s path: a scripted infant's hands touch one region per step (steps
    10-11 left, 10 right after the settle period, ScriptedInfant), every episode alike."""
    registry = registry_for(SelfTouch)
    kwargs = dict(policy="zero", infant_factory=ScriptedInfant, progress=False)
    one = evaluate_policy("self_touch", None, 4, registry, envs=1, **kwargs)
    two = evaluate_policy("self_touch", None, 4, registry, envs=2, **kwargs)
    assert one["likeness_coded"] == two["likeness_coded"]
    coded = one["likeness_coded"]
    # 10 coded steps (steps 10-19: frames 0-1) an episode; the left hand's contact (steps 10
    # and 11, frame 0) was there when coding began: no touch, half the frames in contact
    assert coded["episodes"] == 4 and coded["touches"] == 0
    assert coded["contact_time_share"] == 0.5
    assert coded["coded_seconds"] == pytest.approx(4 * 10 * 0.005)
