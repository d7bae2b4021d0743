"""ReachBall: walk to the ball, with joint targets for the 12 leg joints and the 3 head joints.

``ReachBallEnv`` (``aibo_sim/ReachBall-v0``); its docstring holds the action, observation and
reward tables.
"""

from __future__ import annotations

import numpy as np

from .base import HEAD_JOINTS, LEG_JOINTS, AiboEnv

BALL_START = (0.8, 0.0)
REACH_DISTANCE = 0.2  # m, body centre to ball centre: the ball between the front paws' reach, not touching
# (the chest's sphere ends 87 mm above the floor, the 84 mm ball passes under it, between the front legs)
START_CLEARANCE = 0.3  # m: a randomised start nearer the body is drawn again (not reached, not under it)
PROGRESS_REWARD = 10.0  # per metre


class ReachBallEnv(AiboEnv):
    """``aibo_sim/ReachBall-v0``: walk to the ball, with joint targets for the 12 leg joints and the 3 head joints.

    ## Description

    The robot starts standing on the centre spot facing +X; the ball lies 0.8 m ahead, a free
    body that the robot can push. The policy walks the robot to the ball (its head free to look
    for it) without falling.

    ## Action Space

    ``Box(-1, 1, (15,), float32)``: each number mapped affinely onto its joint's range (-1 the
    lower limit, 1 the upper) and given to the servo as its target (``AiboEnv``). Per leg
    (``lf`` left front, ``lh`` left hind, ``rf`` right front, ``rh`` right hind): ``j1`` swings
    the leg forwards and backwards, ``j2`` lifts it sideways, ``j3`` is the knee (elbow).

    | Num | Joint         | Min | Max | Target range, rad | Target range, deg |
    |-----|---------------|-----|-----|-------------------|-------------------|
    | 0   | ``lf_j1``     | -1  | 1   | -2.094 .. 2.356   | -120 .. 135       |
    | 1   | ``lf_j2``     | -1  | 1   | -0.262 .. 1.623   | -15 .. 93         |
    | 2   | ``lf_j3``     | -1  | 1   | -0.524 .. 2.217   | -30 .. 127        |
    | 3   | ``lh_j1``     | -1  | 1   | -2.356 .. 2.094   | -135 .. 120       |
    | 4   | ``lh_j2``     | -1  | 1   | -0.262 .. 1.623   | -15 .. 93         |
    | 5   | ``lh_j3``     | -1  | 1   | -0.524 .. 2.217   | -30 .. 127        |
    | 6   | ``rf_j1``     | -1  | 1   | -2.094 .. 2.356   | -120 .. 135       |
    | 7   | ``rf_j2``     | -1  | 1   | -0.262 .. 1.623   | -15 .. 93         |
    | 8   | ``rf_j3``     | -1  | 1   | -0.524 .. 2.217   | -30 .. 127        |
    | 9   | ``rh_j1``     | -1  | 1   | -2.356 .. 2.094   | -135 .. 120       |
    | 10  | ``rh_j2``     | -1  | 1   | -0.262 .. 1.623   | -15 .. 93         |
    | 11  | ``rh_j3``     | -1  | 1   | -0.524 .. 2.217   | -30 .. 127        |
    | 12  | ``neck_tilt`` | -1  | 1   | -1.396 .. 0.052   | -80 .. 3          |
    | 13  | ``head_pan``  | -1  | 1   | -1.623 .. 1.623   | -93 .. 93         |
    | 14  | ``head_tilt`` | -1  | 1   | -0.349 .. 0.873   | -20 .. 50         |

    ## Observation Space

    ``AiboEnv``'s ``Dict`` (there: the image by camera mode, the keys' details, ``image_only``):

    | Key                 | Shape         | Dtype   | Range               | Observation                             |
    |---------------------|---------------|---------|---------------------|-----------------------------------------|
    | ``image``           | (160, 208, 3) | uint8   | 0 .. 255            | the head camera at layer H (below)      |
    | ``joint_positions`` | (20,)         | float32 | -pi .. pi           | rad, every joint, ``ers7.JOINTS`` order |
    | ``acceleration``    | (3,)          | float32 | -19.61 .. 19.61     | m/s^2, body frame, clipped to +-2 g     |
    | ``distance_mm``     | (3,)          | float32 | 0 .. 500, 1500, 900 | mm: IR head near, head far, chest       |
    | ``touch``           | (9,)          | int8    | 0 or 1              | pressed, ``ers7.TOUCH_SENSORS`` order   |

    ``image`` is (80, 104, 3) at ``camera_layer="M"``, (40, 52, 3) at ``"L"``; absent with
    ``camera=None``; ``image_only=True`` makes it the whole observation.

    ## Rewards

    Per step, with d the horizontal distance (m) from the body's centre to the ball's:

    - progress: ``PROGRESS_REWARD`` (10) times the decrease of d since the previous step
      (negative when the robot moves away or the ball rolls off);
    - +1 on the step that reaches the ball (d below ``REACH_DISTANCE``, 0.2 m: the ball just before
      the front paws, ~7 cm from the nearest part of the robot; standing, the robot can also let it
      roll under its chest, between its front legs);
    - -1 on the step the robot falls (unless it reached the ball on that step).

    From the start, reaching the ball earns about 10 x 0.6 + 1 = 7.

    ## Starting State

    ``AiboEnv``'s (standing on the centre spot facing +X); the ball at rest at (0.8, 0) m
    (``BALL_START``), moved by up to r m in each horizontal direction with
    ``randomize={"ball_start": r}``, drawn again while it falls within 0.3 m of the robot's centre
    (``START_CLEARANCE``: an episode never starts reached, nor with the ball under the robot), off
    the default field's carpet or inside something (a wall, a goal), at most 100 times
    (``BALL_DRAWS``), then at (0.8, 0).

    ## Episode End

    - Termination: the ball reached (d < 0.2 m), or the robot fell (its body tilted more than 60
      degrees from upright).
    - Truncation: after 450 steps (15 s), ``max_episode_steps`` of ``aibo_sim.envs.ENV_SPECS``
      (``gymnasium.make``'s ``TimeLimit``; a ``ReachBallEnv`` made directly never truncates).

    ## Info

    ``ball_distance``: d (m, a float); ``reached``: d < 0.2 m; ``fallen``: the body tilted more
    than 60 degrees.

    ## Arguments

    ``AiboEnv``'s (``camera``, ``camera_layer``, ``render_mode``, ``randomize``, ``scene``,
    ``camera_profile``, ``camera_wb``, ``camera_gain``, ``camera_shutter``, ``image_only``).
    """

    actuated_joints = LEG_JOINTS + HEAD_JOINTS

    def _reset_task(self) -> None:
        body, _, _ = self.sim.body_pose()

        def near(ball) -> bool:  # the episode would start reached, or with the ball under the robot
            return np.linalg.norm(ball - body[:2]) < START_CLEARANCE

        self.sim.place_ball(*self.drawn_ball_start(BALL_START, near))
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
