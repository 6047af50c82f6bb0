"""Motor babbling: random actions on the sitting infant, recording what it sees and feels.

Paper sec. II-B2: "a 10,000-step random action phase to collect a dataset of proprioception,
vision, and actions trajectories". The recording feeds :func:`calibration.calibrate`.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from devlearn import Infant

PROGRESS_SECONDS = 5.0
"""Babbling prints a progress line at most this often (it takes minutes on a CPU)."""

SIDES = ("left", "right")
PLACING_JOINTS = ("shoulder", "elbow")
"""Joints whose angles place a hand (actuator names containing these words): the shoulder
and the elbow carry the hand across the view; the wrist turns the mitten but barely moves it,
and fewer inputs need fewer babbling frames (issue #39: with the wrist's three joints added the
side attribution's pair precision fell from 0.94 to 0.91 on the same frames)."""
ARMS = ("both", "alternate", "turns")
"""Valid ``arms`` of :func:`babble`."""
TURN_STEPS = 150
"""``arms="turns"``: steps each arm babbles while the other holds its action (issue #58): a
held arm takes about 100 steps (0.5 s) to come to rest from a swing."""


@dataclass
class BabblingData:
    """One babbling recording of T steps (the state after each step).

    Attributes:
        eyes: (T, 2, H, W, 3) uint8 RGB, [left eye, right eye].
        proprioception: (T, P) float32.
        actions: (T, A) float32, the random actions taken.
        arm_speed: (T, 2) float32, [left, right] arm joint-speed magnitude: the norm of the
            arm joints' velocities (from proprioception, see :func:`joint_state`).
        episode: (T,) int, episode index (tracks never cross an episode boundary).
        head_pose: (T, 3) float32 head joint angles (from proprioception), or (T, 0).
        moving_arm: (T,) int, the arm that babbled at each step when one arm babbled at a
            time (0 left, 1 right; ``arms="alternate"`` or ``"turns"``), -1 when both did;
            None: unknown. Under ``"turns"`` the other arm is not hanging but held still.
        posture_joints: Per hand [left, right], the proprioception indices of the joint
            angles that place that hand (:func:`posture_joints`); empty when unknown.
        posture_mirror: Per position in those lists, the sign an angle takes in the body's
            mirror image (:func:`mirror_signs`); empty when unknown.
    """

    eyes: np.ndarray
    proprioception: np.ndarray
    actions: np.ndarray
    arm_speed: np.ndarray
    episode: np.ndarray
    head_pose: np.ndarray | None = None
    moving_arm: np.ndarray | None = None
    posture_joints: list[list[int]] = field(default_factory=list)
    posture_mirror: list[float] = field(default_factory=list)

    def __post_init__(self) -> None:
        if self.head_pose is None:
            self.head_pose = np.zeros((len(self.eyes), 0), np.float32)

    def __len__(self) -> int:
        return len(self.eyes)


def joint_state(proprioception: np.ndarray, groups: dict[str, np.ndarray]) -> tuple:
    """Split proprioception into arm speeds and head pose.

    The infant's proprioception is [qpos, qvel, torque, limit, action, actuator_force], each
    (J,) in actuator order (``devlearn.infant.senses.Proprioception``).

    Args:
        proprioception: (6 J,) one step's proprioception.
        groups: ``infant.actuator_groups``.
    Returns:
        arm_speed: (2,) [left, right] norm of the arm joints' velocities (rad/s).
        head_pose: (len(head),) head joint angles (rad).
    """
    n_joints = len(proprioception) // 6
    qpos, qvel = proprioception[:n_joints], proprioception[n_joints : 2 * n_joints]
    speed = np.array([np.linalg.norm(qvel[groups[f"{s}_arm"]]) for s in SIDES], np.float32)
    return speed, np.asarray(qpos[groups["head"]], np.float32)


def posture_joints(actuator_names: list[str], groups: dict[str, np.ndarray]) -> list[list[int]]:
    """Per hand [left, right], the proprioception indices of the angles that place it: that
    arm's :data:`PLACING_JOINTS`, then the head's joints (the eyes turn with the head).

    Proprioception starts with the joint angles in actuator order (:func:`joint_state`), so
    an actuator's index is its angle's index.
    """
    head = [int(i) for i in groups["head"]]
    return [
        [
            int(i)
            for i in groups[f"{side}_arm"]
            if any(word in actuator_names[int(i)] for word in PLACING_JOINTS)
        ]
        + head
        for side in SIDES
    ]


MIRRORED_HEAD_TURNS = ("swivel", "side")
"""Head joints (actuator names containing these words) whose angle changes sign in the body's
mirror image: a turn and a side tilt reverse, a nod does not."""


def mirror_signs(actuator_names: list[str], joints: list[int]) -> list[float]:
    """Per joint of one hand's :func:`posture_joints` list, the sign its angle takes when the
    body is mirrored left to right (the other hand's list then describes the mirror image).

    The arms are built as mirror images of each other (the same angle of the left and the
    right shoulder puts the hands at mirrored places: on BabyBench's infant the pixels each
    eye sees of a hand held before the eyes swap exactly, issue #39), so arm angles keep their
    sign; of the head, turns and side tilts (:data:`MIRRORED_HEAD_TURNS`) change it.
    """
    return [
        -1.0 if any(word in actuator_names[j] for word in MIRRORED_HEAD_TURNS) else 1.0
        for j in joints
    ]


def babble(
    steps: int,
    *,
    seed: int = 0,
    hold_steps: int = 8,
    head_hold_steps: int = 50,
    head_scale: float = 0.3,
    infant: Infant | None = None,
    episode_steps: int | None = None,
    appearance: str = "mittens",
    random_pose: bool = False,
    scene: str = "sitting_babybench",
    start: str = "babybench",
    progress: bool = False,
    arms: str = "both",
) -> BabblingData:
    """Move every actuator randomly and record eyes, proprioception, actions and arm speeds.

    Each actuator keeps its random action (uniform in [-1, 1]) and redraws it with probability
    ``1 / hold_steps`` per step (arms, wrists) or ``1 / head_hold_steps`` (head): the joints are
    damped, so fresh noise every 5 ms would only make them tremble; independent switching
    keeps the arms' speeds uncorrelated with the head's; a slower, gentler head (actions
    scaled by ``head_scale``) keeps the scene mostly still in view and the hands near it, while
    visiting many gaze directions. Held actions swing the hands up from their hanging pose
    into view, which i.i.d. noise never does. Every episode starts as ``start`` says (the
    training start), or from a random start (``random_pose``: for measuring a detector).

    ``arms="alternate"`` babbles one arm per episode (left in even episodes, right in odd
    ones; the other arm's action is 0, so it hangs still): in BabyBench's scene a hand rising
    from below into view moves with the whole body, and with both arms babbling its track
    correlates with both arms' speeds, so calibration cannot tell which hand it is. With one
    arm moving at a time, the infant knows which arm it moved (issue #29).

    ``arms="turns"`` (issue #58) covers two-arm postures, hands crossing the midline included:
    the arms take turns of :data:`TURN_STEPS` steps, one babbling while the other holds the
    action it had (so it settles and stays still wherever it was, in view or not), and the
    head holds one action per episode; use it with ``random_pose`` (both arms start anywhere
    in their ranges) and short episodes. Which blob is which hand then follows from
    contingency: the blob that moves while one arm moves is that arm's hand
    (:mod:`devlearn_hand_regard.contingency`).

    Args:
        steps: Steps to record (paper: 10,000).
        seed: Seed of the actions and the initial poses.
        hold_steps: Mean steps an arm action is held (>= 1).
        head_hold_steps: Mean steps a head action is held (>= 1).
        head_scale: Largest head action (the arms use the full [-1, 1]).
        infant: A sitting infant with eyes and proprioception (built and closed here if None).
        appearance: The infant's appearance when built here ("skin" or "mittens").
        random_pose: Start every episode from a random pose and toy layout
            (``Infant.reset(rng, random_pose=True)``) instead of ``start``.
        episode_steps: Steps between resets (default: the infant's episode length).
        scene: The scene when the infant is built here.
        start: How episodes start (``devlearn.infant.starts.STARTS``) unless ``random_pose``.
        progress: Print a line to stderr every :data:`PROGRESS_SECONDS` (steps done, rate).
        arms: ``both`` (every arm babbles all the time), ``alternate`` (one arm per
            episode) or ``turns`` (the arms take turns within an episode; see above).
    Returns:
        The recording.
    """
    if steps < 2 or hold_steps < 1 or head_hold_steps < 1:
        raise ValueError(
            f"babbling needs steps >= 2 and hold steps >= 1, got {steps}, "
            f"{hold_steps}, {head_hold_steps}"
        )
    if arms not in ARMS:
        raise ValueError(f"babbling arms must be one of {', '.join(ARMS)}, got {arms!r}")
    own = infant is None
    if infant is None:
        from devlearn import build_infant

        infant = build_infant(scene, senses=("proprioception", "eyes"), appearance=appearance)
    try:
        began = shown = time.monotonic()
        rng = np.random.default_rng(seed)
        length = int(episode_steps or infant.episode_steps)
        switch = np.full(infant.action_dim, 1.0 / hold_steps)
        switch[infant.actuator_groups["head"]] = 1.0 / head_hold_steps
        scale = np.ones(infant.action_dim)
        scale[infant.actuator_groups["head"]] = head_scale
        groups = {k: np.asarray(v) for k, v in infant.actuator_groups.items()}
        names = list(infant.actuator_names)
        eyes, proprio, actions, speeds, heads, episode, moving = [], [], [], [], [], [], []
        action = np.zeros(infant.action_dim)
        still = np.zeros(infant.action_dim, bool)
        for t in range(steps):
            if t % length == 0:
                if arms == "alternate":  # this episode's other arm hangs still
                    still[:] = False
                    still[groups[f"{SIDES[1 - (t // length) % 2]}_arm"]] = True
                if random_pose:
                    infant.reset(rng, random_pose=True)
                else:
                    infant.reset(rng, start=start)
            if progress and time.monotonic() - shown >= PROGRESS_SECONDS:
                shown = time.monotonic()
                rate = t / max(shown - began, 1e-9)
                print(
                    f"babbling: {t:,} / {steps:,} steps ({rate:.0f} steps/s, "
                    f"{(steps - t) / max(rate, 1e-9):.0f} s left)",
                    file=sys.stderr,
                    flush=True,
                )
            redraw = rng.random(infant.action_dim) < switch
            if arms == "turns":
                turn = ((t % length) // TURN_STEPS + (t // length)) % 2  # the babbling arm
                redraw[groups[f"{SIDES[1 - turn]}_arm"]] = False  # the other arm holds
                redraw[groups["head"]] = t % length == 0  # one head action per episode
            action = np.where(redraw, rng.uniform(-scale, scale), action)
            action[still] = 0.0
            infant.step(action)
            p = np.asarray(infant.proprioception(), dtype=np.float32)
            speed, head = joint_state(p, groups)
            eyes.append(infant.eyes())
            proprio.append(p)
            actions.append(action.astype(np.float32))
            speeds.append(speed)
            heads.append(head)
            episode.append(t // length)
            if arms == "turns":
                moving.append(((t % length) // TURN_STEPS + (t // length)) % 2)
            else:
                moving.append((t // length) % 2 if arms == "alternate" else -1)
        return BabblingData(
            eyes=np.stack(eyes),
            proprioception=np.stack(proprio),
            actions=np.stack(actions),
            arm_speed=np.stack(speeds),
            episode=np.asarray(episode),
            head_pose=np.stack(heads),
            moving_arm=np.asarray(moving),
            posture_joints=posture_joints(names, groups),
            posture_mirror=mirror_signs(names, posture_joints(names, groups)[0]),
        )
    finally:
        if own:
            infant.close()
