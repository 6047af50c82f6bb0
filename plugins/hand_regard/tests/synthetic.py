"""Synthetic babbling recordings: numpy-drawn discs for hands, squares for toy blocks."""

from __future__ import annotations

import cv2
import numpy as np
from devlearn_hand_regard.babbling import BabblingData

SKIN = (230, 180, 150)
MAGENTA = (220, 50, 160)
BLOCKS = ((200, 40, 40), (40, 70, 200), (230, 210, 40))


def draw(
    hands: np.ndarray,
    blocks: np.ndarray,
    size: int = 64,
    radius: int = 5,
    colours: tuple = (SKIN, SKIN),
) -> np.ndarray:
    """Render one (size, size, 3) RGB frame: floor, blocks (squares) and hands (discs).

    Args:
        hands: (2, 2) [left, right] hand centres (x, y), pixels; NaN rows are not drawn.
        blocks: (3, 2) block centres, pixels.
        colours: RGB of the [left, right] hand.
    """
    image = np.zeros((size, size, 3), np.uint8)
    image[:] = (90, 110, 90)
    image[: size // 3] = (150, 150, 160)  # a wall
    for colour, (x, y) in zip(BLOCKS, blocks):
        cv2.rectangle(image, (int(x) - 4, int(y) - 4), (int(x) + 4, int(y) + 4), colour, -1)
    for (x, y), colour in zip(hands, colours):
        if np.isfinite(x):
            cv2.circle(image, (int(round(x)), int(round(y))), radius, colour, -1)
    return image


def synthetic_babbling(
    steps: int = 1500,
    seed: int = 0,
    hold: int = 8,
    colours: tuple = (SKIN, SKIN),
    alternate: int = 0,
) -> BabblingData:
    """A recording where hand discs move with 'arm joints' and everything moves with the head.

    Each arm has 3 joints whose velocities are random, held ``hold`` steps; the hand's image
    velocity is a fixed linear map of them. The head adds a slow shared drift to everything.
    ``colours``: the [left, right] hands' RGB. ``alternate`` > 0: one arm babbles per episode
    of that many steps (left first), while the other, jostled, turns at 1% of its speed in
    the same rhythm (a still arm's speed follows the moving one's, as on the infant).
    """
    rng = np.random.default_rng(seed)
    size = 64
    # Per hand: image velocity = J @ joint velocity, J with orthogonal rows (a hand moves
    # in the image about as fast as its joints turn).
    jac = np.stack([np.linalg.qr(rng.normal(size=(3, 2)))[0].T for _ in range(2)]) * 0.8
    pos = np.array([[20.0, 40.0], [44.0, 40.0]])
    blocks = np.array([[12.0, 52.0], [32.0, 56.0], [52.0, 50.0]])
    eyes, speeds, joint_v = [], [], np.zeros((2, 3))
    head_v = np.zeros(2)
    for t in range(steps):
        if t % hold == 0:
            joint_v = rng.uniform(-1, 1, (2, 3)) * rng.uniform(0, 1.5, (2, 1))
            head_v = rng.normal(0, 0.15, 2)
            if alternate:
                moving = (t // alternate) % 2
                joint_v[1 - moving] = 0.01 * joint_v[moving]
        for h in range(2):
            pos[h] += jac[h] @ joint_v[h] + head_v
        blocks += head_v
        pos = np.clip(pos, 6, size - 7)  # hands stop at the edges of the view
        blocks = np.clip(blocks, 5, size - 6)
        frame = draw(pos, blocks, colours=colours)
        shifted = draw(pos + [2.0, 0.0], blocks + [2.0, 0.0], colours=colours)  # the other eye
        eyes.append(np.stack([frame, shifted]))
        speeds.append(np.linalg.norm(joint_v, axis=1))
    return BabblingData(
        eyes=np.stack(eyes),
        proprioception=np.zeros((steps, 4), np.float32),
        actions=np.zeros((steps, 4), np.float32),
        arm_speed=np.asarray(speeds, np.float32),
        episode=np.arange(steps) // alternate if alternate else np.zeros(steps, int),
    )
