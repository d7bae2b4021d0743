"""HeadTrackBall: keep a moving ball centred in the head camera with the three head joints.

The body stands (keyframe ``stand``, leg servos holding it). The ball is moved kinematically
over the ground in front of the robot along a seeded random path: per horizontal axis a sine
``amplitude * (sin(w t + phase) - sin(phase))`` added to its start, so that it starts there,
with frequency and phase drawn at reset.

Reward per step, in [0, 1]: ``1 - max(|x|, |y|)`` where (x, y) is the ball centre's offset
from the image centre in half-widths and half-heights, found by projecting the ball centre
through the camera pose and intrinsics; 0 when the centre is outside the image or behind the
camera. ``info``: ``ball_offset`` (x, y) and ``ball_visible``.
"""

from __future__ import annotations

import math

import numpy as np

from ..field import BALL_RADIUS
from .base import HEAD_JOINTS, AiboEnv

BALL_START = (0.9, 0.0)  # metres ahead of the robot, on the ground
AMPLITUDE = np.array([0.2, 0.4])  # m, forward and sideways
FREQUENCY_HZ = (0.1, 0.4)
NEAREST_X = 0.4  # the path never comes closer than this to the robot's centre


class HeadTrackBallEnv(AiboEnv):
    """``aibo_sim/HeadTrackBall-v0``: actions for neck_tilt, head_pan and head_tilt."""

    actuated_joints = HEAD_JOINTS

    def __init__(self, **options):
        super().__init__(**options)
        self._ball_qpos, self._ball_qvel = self.sim.ball_state()  # views into MjData

    def _reset_task(self) -> None:
        rng = self.np_random
        start = self.ball_start(BALL_START)
        omega = 2 * np.pi * rng.uniform(*FREQUENCY_HZ, 2)
        phase = rng.uniform(0, 2 * np.pi, 2)
        # Per axis (start, amplitude, angular frequency, phase), in Python floats: scalar math
        # is the cheapest for what runs every 8 ms frame.
        self._paths = [tuple(map(float, axis)) for axis in zip(start, AMPLITUDE, omega, phase)]
        self._ball_seen_at = -1  # the frame counter starts again at 0
        self._before_frame()

    def _before_frame(self) -> None:
        t = self.sim.data.time
        (x, vx), (y, vy) = (
            (s + a * (math.sin(w * t + p) - math.sin(p)), a * w * math.cos(w * t + p)) for s, a, w, p in self._paths
        )
        if x < NEAREST_X:
            x, vx = NEAREST_X, 0.0
        self._ball_qpos[:] = (x, y, BALL_RADIUS, 1.0, 0.0, 0.0, 0.0)
        self._ball_qvel[:] = (vx, vy, 0.0, 0.0, 0.0, 0.0)

    def _ball_in_image(self) -> tuple[np.ndarray, bool]:
        """The ball's projected offset and visibility, computed once per joint frame."""
        if self._ball_seen_at != self.sim.frame:
            self._ball_seen = self.image_position(self.sim.ball_position())
            self._ball_seen_at = self.sim.frame
        return self._ball_seen

    def _evaluate(self) -> tuple[float, bool]:
        offset, visible = self._ball_in_image()
        return (1.0 - float(np.max(np.abs(offset)))) if visible else 0.0, False

    def _info(self) -> dict:
        offset, visible = self._ball_in_image()
        return {"ball_offset": offset, "ball_visible": visible}
