"""ReachBall: walk to the ball, with joint targets for the 12 leg joints and the 3 head joints.

The robot starts standing at the centre spot facing +X; the ball lies ahead (a free body that
the robot can push). Reward per step: ``PROGRESS_REWARD`` times the decrease of the
horizontal distance (m) from the body to the ball; on reaching it (distance below
``REACH_DISTANCE``) +1 and the episode ends; on falling -1 and the episode ends.
``info``: ``ball_distance`` (m), ``reached``, ``fallen``.
"""

from __future__ import annotations

import numpy as np

from .base import HEAD_JOINTS, LEG_JOINTS, AiboEnv

BALL_START = (0.8, 0.0)
REACH_DISTANCE = 0.2  # m, body centre to ball centre: the ball touches the chest at ~0.17 m
PROGRESS_REWARD = 10.0  # per metre


class ReachBallEnv(AiboEnv):
    """``aibo_sim/ReachBall-v0``: actions for the 12 leg joints, then the 3 head joints."""

    actuated_joints = LEG_JOINTS + HEAD_JOINTS

    def _reset_task(self) -> None:
        self.sim.place_ball(*self.ball_start(BALL_START))
        self._distance = self._ball_distance()

    def _ball_distance(self) -> float:
        body, _, _ = self.sim.body_pose()
        return float(np.linalg.norm(self.sim.ball_position()[:2] - body[:2]))

    def _evaluate(self) -> tuple[float, bool]:
        distance = self._ball_distance()
        reward = PROGRESS_REWARD * (self._distance - distance)
        self._distance = distance
        if distance < REACH_DISTANCE:
            return reward + 1.0, True
        if self.sim.fallen():
            return reward - 1.0, True
        return reward, False

    def _info(self) -> dict:
        distance = self._ball_distance()
        return {"ball_distance": distance, "reached": distance < REACH_DISTANCE, "fallen": self.sim.fallen()}
