"""HeadTrackBall: keep a moving ball centred in the head camera with the three head joints.

``HeadTrackBallEnv`` (``aibo_sim/HeadTrackBall-v0``); its docstring holds the action,
observation and reward tables.
"""

from __future__ import annotations

import math

import numpy as np

from .base import HEAD_JOINTS, AiboEnv

BALL_START = (0.9, 0.0)  # metres ahead of the robot, on the ground
AMPLITUDE = np.array([0.2, 0.4])  # m, forward and sideways
FREQUENCY_HZ = (0.1, 0.4)
NEAREST_X = 0.4  # the path never comes closer than this to the robot's centre


class HeadTrackBallEnv(AiboEnv):
    """``aibo_sim/HeadTrackBall-v0``: keep a moving ball centred in the head camera with the three head joints.

    ## Description

    The body stands (keyframe ``stand``, the leg servos holding it) while the ball moves over
    the ground in front of it, kinematically (set every 8 ms joint frame, not pushed by
    physics), along a seeded random path: per horizontal axis ``amplitude * (sin(w t + phase) -
    sin(phase))`` added to its start, so that it starts there. The amplitude is 0.2 m forward
    and 0.4 m sideways (``AMPLITUDE``); each axis's frequency (0.1 to 0.4 Hz, ``FREQUENCY_HZ``)
    and phase (0 to 2 pi) are drawn at reset. The ball comes no nearer than 0.4 m ahead of the
    robot's centre (``NEAREST_X``). The policy moves the head to keep the ball in the middle of
    the image.

    ## Action Space

    ``Box(-1, 1, (3,), float32)``: each number mapped affinely onto its joint's range (-1 the
    lower limit, 1 the upper) and given to the servo as its target (``AiboEnv``):

    | Num | Joint         | Min | Max | Target range, rad | Target range, deg |
    |-----|---------------|-----|-----|-------------------|-------------------|
    | 0   | ``neck_tilt`` | -1  | 1   | -1.396 .. 0.052   | -80 .. 3          |
    | 1   | ``head_pan``  | -1  | 1   | -1.623 .. 1.623   | -93 .. 93         |
    | 2   | ``head_tilt`` | -1  | 1   | -0.349 .. 0.873   | -20 .. 50         |

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

    Per step, in [0, 1]: ``1 - max(|x|, |y|)``, where (x, y) is the ball centre's offset from the
    image centre in half-widths and half-heights (found by projecting the ball centre through
    the camera's pose and lens, not from pixels); 0 when the centre is outside the image or
    behind the camera. An episode scores at most 300.

    ## Starting State

    ``AiboEnv``'s (standing on the centre spot facing +X); the ball at (0.9, 0) m
    (``BALL_START``), moved by up to r m in each horizontal direction with
    ``randomize={"ball_start": r}`` (drawn again where ``run`` would refuse that ball: off the
    default field's carpet or inside a wall; ``drawn_ball_start``), and its path drawn (it may
    pass through a wall: the ball is moved, not pushed).

    ## Episode End

    - Termination: none.
    - Truncation: after 300 steps (10 s), ``max_episode_steps`` of ``aibo_sim.envs.ENV_SPECS``
      (``gymnasium.make``'s ``TimeLimit``; a ``HeadTrackBallEnv`` made directly never truncates).

    ## Info

    ``ball_offset``: (x, y) above, a float64 array of shape (2,), clipped to +-2;
    ``ball_visible``: whether the ball centre is in front of the camera and inside the image.

    ## Arguments

    ``AiboEnv``'s, as keywords (``camera``, ``camera_layer``, ``render_mode``, ``randomize``,
    ``scene``, ``camera_profile``, ``camera_wb``, ``camera_gain``, ``camera_shutter``,
    ``image_only``):

        gymnasium.make("aibo_sim/HeadTrackBall-v0", camera="rgb", camera_layer="L")
    """

    actuated_joints = HEAD_JOINTS

    def __init__(self, **options):
        super().__init__(**options)
        self._ball_qpos, self._ball_qvel = self.sim.ball_state()  # views into MjData
        self._ball_radius = float(self.sim.model.geom("ball").size[0])  # the scene's ball, on the ground

    def _reset_task(self) -> None:
        rng = self.np_random
        start = self.drawn_ball_start(BALL_START)
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
        self._ball_qpos[:] = (x, y, self._ball_radius, 1.0, 0.0, 0.0, 0.0)
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
