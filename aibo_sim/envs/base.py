"""The shared base of the ERS-7 environments (``AiboEnv``): simulation, observations, actions, rendering.

One environment step is one frame of the head camera at the robot's 30 fps: the 8 ms joint
frames run until the camera's next frame is due (4 or 5 of them), then one image is taken.
``AiboEnv``'s docstring holds the tables: the observation (a ``Dict`` of the head camera's
image and the robot's sensors, or the image alone), the action (one number in [-1, 1] per
actuated joint) and the constructor's arguments (camera mode and layer, the camera's profile
and settings, domain randomisation, rendering). The tasks are its subclasses:
``head_track.HeadTrackBallEnv`` and ``reach_ball.ReachBallEnv``.
"""

from __future__ import annotations

import copy
import math
import numbers
from collections.abc import Mapping

import gymnasium as gym
import mujoco
import numpy as np

import openr_bridge

from ..camera import CameraSettings, RobotColour
from ..camera.backends import OpenRCamera
from ..camera.sensor import box_average
from ..config import CameraConfig
from ..ers7 import DISTANCE_SENSORS, JOINT_INDEX, JOINTS, LEGS, TOUCH_SENSORS
from ..placement import ball_start_problem
from ..render import Renderer
from ..sim import ACCEL_RANGE, MAX_PLACEMENT, Simulation, release_freed_memory

CAMERA_MODES = ("rgb", "ycrcb", "openr", None)
LAYERS = {name: layer for layer, name in enumerate(openr_bridge.LAYER_NAMES[:3])}  # the YCrCb layers H, M, L
YCRCB_BANDS = (openr_bridge.ofbkimageBAND_Y, openr_bridge.ofbkimageBAND_Cr, openr_bridge.ofbkimageBAND_Cb)
RANDOMIZATIONS = ("lighting", "ball_start", "camera_robot")
BALL_DRAWS = 100  # randomised ball starts drawn at most (drawn_ball_start)
RENDER_SIZE = (480, 360)  # third-person view, width x height
HEAD_JOINTS = ("neck_tilt", "head_pan", "head_tilt")
LEG_JOINTS = tuple(j.name for j in JOINTS if j.name.split("_")[0] in LEGS)


def check_options(camera, camera_layer, render_mode, randomize, image_only) -> dict:
    """ValueError naming the first environment option that cannot be used (``AiboEnv``'s and
    ``MatchEnv``'s); returns ``randomize`` as a dict."""
    if camera not in CAMERA_MODES:
        raise ValueError(f"camera must be one of {CAMERA_MODES}, not {camera!r}")
    if not isinstance(image_only, bool) or image_only and camera is None:
        raise ValueError(f"image_only must be True or False, and False with camera=None, not {image_only!r}")
    if camera_layer not in LAYERS:
        raise ValueError(f"camera_layer must be one of {tuple(LAYERS)}, not {camera_layer!r}")
    if render_mode not in (None, "rgb_array"):
        raise ValueError(f"render_mode must be None or 'rgb_array', not {render_mode!r}")
    if randomize is not None and not isinstance(randomize, Mapping):
        raise ValueError(f"randomize must be a dict of {RANDOMIZATIONS} to numbers, not {randomize!r}")
    randomize = dict(randomize or {})
    unknown = set(randomize) - set(RANDOMIZATIONS)
    if unknown:
        raise ValueError(f"unknown randomisations {sorted(unknown)}; known: {RANDOMIZATIONS}")
    for name, value in randomize.items():
        largest = {"lighting": 1.0, "ball_start": MAX_PLACEMENT}.get(name, math.inf)
        if (
            isinstance(value, bool)
            or not isinstance(value, numbers.Real)
            or not (0 <= value <= largest and math.isfinite(value))
        ):
            raise ValueError(
                f"randomize[{name!r}] = {value!r}: must be a finite number >= 0"
                + (f" and at most {largest:g}" if math.isfinite(largest) else "")
            )
    if camera == "openr" and camera_layer != "H":
        raise ValueError(
            "camera='openr' serves layer H, as the wrapper's camera_get_image does; "
            "use camera='ycrcb' or 'rgb' for layers M and L"
        )
    return randomize


class AiboEnv(gym.Env):
    """An ERS-7 in the RoboCup scene, seen through its head camera: the base of the single-robot environments.

    ## Description

    The robot starts standing on the field; a subclass names the joints its actions drive
    (``actuated_joints``) and sets the task: its start (``_reset_task``), what moves between
    joint frames (``_before_frame``), its reward and termination (``_evaluate``) and ``info``
    (``_info``). ``head_track.HeadTrackBallEnv`` and ``reach_ball.ReachBallEnv`` are the two
    here; their docstrings hold their actions' tables, rewards and episode ends. One step is one
    frame of the head camera at 30 fps: the 8 ms joint frames run until the camera's next frame
    is due (4 or 5 of them), then one image is taken.

    ## Action Space

    ``Box(-1, 1, (len(actuated_joints),), float32)``: one number per actuated joint, in the order
    of ``actuated_joints``, clipped to [-1, 1] and mapped affinely onto the joint's control range
    (its hardware range in ``ers7.JOINTS``, rad: -1 the lower limit, 1 the upper), then given to
    the servos as their target. A NaN or infinite number raises ValueError. The joints not
    actuated hold the keyframe's targets. ``action_to_targets`` and ``targets_to_action``
    convert between actions and targets (rad).

    ## Observation Space

    A ``Dict``:

    | Key                 | Shape         | Dtype   | Range               | Observation                             |
    |---------------------|---------------|---------|---------------------|-----------------------------------------|
    | ``image``           | (160, 208, 3) | uint8   | 0 .. 255            | the head camera (below); layer H        |
    | ``joint_positions`` | (20,)         | float32 | -pi .. pi           | rad, every joint, ``ers7.JOINTS`` order |
    | ``acceleration``    | (3,)          | float32 | -19.61 .. 19.61     | m/s^2, body frame, clipped to +-2 g     |
    | ``distance_mm``     | (3,)          | float32 | 0 .. 500, 1500, 900 | mm: IR head near, head far, chest       |
    | ``touch``           | (9,)          | int8    | 0 or 1              | pressed, ``ers7.TOUCH_SENSORS`` order   |

    - ``image``: (80, 104, 3) at layer M, (40, 52, 3) at layer L; absent with ``camera=None``.
    - ``joint_positions``: all 20 joints, not only the actuated ones: ``neck_tilt``, ``head_pan``,
      ``head_tilt``, ``mouth``, ``ear_l``, ``ear_r``, ``lf_j1`` .. ``rh_j3`` (legs lf, lh, rf,
      rh), ``tail_tilt``, ``tail_pan``.
    - ``acceleration``: the body's proper acceleration, x forward, y left, z up.
    - ``distance_mm``: each sensor's maximum (500, 1500, 900 mm) when nothing is in its range;
      noise of up to 10 % mid-range, none at the ends of the range.
    - ``touch``: a ``MultiBinary(9)``: head, chin, paws lf, lh, rf, rh, back rear, middle, front.

    The image (``camera_layer``: H 208x160, M 104x80, L 52x40 pixels), by ``camera``:

    | ``camera``  | Channels  | Image                                                                       |
    |-------------|-----------|-----------------------------------------------------------------------------|
    | ``"rgb"``   | R, G, B   | the camera model's rendered RGB; M and L as 2x2 / 4x4 block means           |
    | ``"ycrcb"`` | Y, Cr, Cb | the bands of that layer of the OPEN-R message                               |
    | ``"openr"`` | R, G, B   | layer H only: what the wrapper ``Controller``'s ``camera_get_image`` serves |
    | ``None``    | -         | no ``image`` key                                                            |

    The block means of ``"rgb"`` are the Haar low band the robot computes. ``"ycrcb"`` is
    ``openr_bridge.encode_frame``'s message; ``"openr"`` that message once it has gone through
    CONNECT.CFG's wiring. Both are bytes as the robot has them, OPEN-R's tag in the first 12 Y
    bytes of the last row included; the last message is ``camera_message``.
    ``image_only=True``: the observation is the image alone, ``Box(0, 255, (height, width, 3),
    uint8)``, as Gymnasium's image wrappers (``ResizeObservation``, ``GrayscaleObservation``,
    ``FrameStackObservation``) and CNN policies take it.

    ## Starting State

    ``reset`` puts the world back to the scene's keyframe ``stand``: in the default scene the
    robot stands on the centre spot facing +X (body 0.147 m high; neck tilt -30 deg, head tilt
    15 deg), its servo targets the keyframe's. Then the randomisations are drawn and the task
    places the ball. A seed reproduces an episode bit for bit (the sensors' and the camera's
    noise included).

    ## Rewards and Episode End

    The task's (the subclasses'). ``step`` itself never truncates: ``gymnasium.make`` adds a
    ``TimeLimit`` of the id's ``max_episode_steps`` (``aibo_sim.envs.ENV_SPECS``).

    ## Arguments

    | Argument           | Default    | Meaning                                                       |
    |--------------------|------------|---------------------------------------------------------------|
    | ``camera``         | ``"rgb"``  | ``"rgb"``, ``"ycrcb"``, ``"openr"`` or ``None`` (no image)    |
    | ``camera_layer``   | ``"H"``    | ``"H"``, ``"M"`` or ``"L"`` (``"openr"``: H only)             |
    | ``render_mode``    | ``None``   | ``None`` or ``"rgb_array"`` (below)                           |
    | ``randomize``      | ``None``   | domain randomisation at each reset (below)                    |
    | ``scene``          | ``None``   | an MJCF scene file; ``None``: ``models/scene.xml``, the field |
    | ``camera_profile`` | ``"ers7"`` | ``"ers7"`` (the calibrated sensor) or ``"ideal"``             |
    | ``camera_wb``      | ``"fl"``   | white balance: ``"indoor"``, ``"outdoor"`` or ``"fl"``        |
    | ``camera_gain``    | ``"mid"``  | ``"low"``, ``"mid"`` or ``"high"``                            |
    | ``camera_shutter`` | ``"mid"``  | ``"slow"``, ``"mid"`` or ``"fast"``                           |
    | ``image_only``     | ``False``  | the observation is the image alone (not with ``camera=None``) |

    The arguments from ``scene`` on are keyword-only; the camera's settings are named as on the
    command line (``aibo_sim.camera``).
    ``randomize={"lighting": m, "ball_start": r, "camera_robot": s}`` (any subset, each a finite
    number >= 0, m at most 1), drawn at each reset from the environment's RNG, scales each
    light's intensity by a factor in [1-m, 1+m], moves the ball's start by up to r metres in
    each horizontal direction, and draws the camera's per-robot colour deviation (per-channel
    gain and offset of Y, Cr, Cb: ``camera_robot``) from s times the spread measured over real
    robots (without it, the camera profile's own ``robot``). ``render_mode="rgb_array"``:
    ``render`` returns the ``tracking`` camera's view,
    480x360 RGB, with shadows and reflections (``quality="high"``): about 68 ms a frame in Mesa's
    software OpenGL on one thread (54 ms with ``LP_NUM_THREADS=2`` on 2 cores), against 5 ms
    without. A bad argument raises ValueError naming it. An environment cannot be pickled or
    copied (TypeError): make another with the same arguments and reset it with the same seed.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": openr_bridge.FRAME_RATE_HZ}
    actuated_joints: tuple[str, ...] = ()

    def __init__(
        self,
        camera: str | None = "rgb",
        camera_layer: str = "H",
        render_mode: str | None = None,
        randomize: dict[str, float] | None = None,
        *,
        scene=None,
        camera_profile: str = "ers7",
        camera_wb: str = "fl",
        camera_gain: str = "mid",
        camera_shutter: str = "mid",
        image_only: bool = False,
    ):
        self.randomize = check_options(camera, camera_layer, render_mode, randomize, image_only)
        self.camera, self.camera_layer, self.render_mode, self.image_only = (
            camera,
            camera_layer,
            render_mode,
            image_only,
        )
        self.camera_message: openr_bridge.OFbkImageVectorData | None = None  # the last one encoded
        self.camera_config = CameraConfig(
            camera_profile, settings=CameraSettings(camera_wb, camera_gain, camera_shutter)
        )
        self.sim = Simulation(scene, camera=self.camera_config)
        self._openr = OpenRCamera(self.sim) if camera == "openr" else None
        model = self.sim.model
        self._actuated = np.array([JOINT_INDEX[name] for name in self.actuated_joints])
        self._target_low, target_high = model.actuator_ctrlrange[self._actuated].T
        self._target_span = target_high - self._target_low
        self._nominal_lights = (
            model.light_diffuse.copy(),
            model.vis.headlight.diffuse.copy(),
            model.vis.headlight.ambient.copy(),
        )
        self.camera_robot = RobotColour()  # this episode's camera colour deviation
        self._renderer: Renderer | None = None
        self._reset_done = False

        self.action_space = gym.spaces.Box(-1.0, 1.0, (len(self._actuated),), np.float32)
        spaces = {
            "joint_positions": gym.spaces.Box(-np.pi, np.pi, (len(JOINTS),), np.float32),
            "acceleration": gym.spaces.Box(-ACCEL_RANGE, ACCEL_RANGE, (3,), np.float32),
            "distance_mm": gym.spaces.Box(0.0, np.array([s.range_mm[1] for s in DISTANCE_SENSORS], np.float32)),
            "touch": gym.spaces.MultiBinary(len(TOUCH_SENSORS)),
        }
        if camera is not None:
            width, height = openr_bridge.LAYER_SIZE[LAYERS[camera_layer]]
            spaces["image"] = gym.spaces.Box(0, 255, (height, width, 3), np.uint8)
        self._image_shape = spaces["image"].shape if camera is not None else None
        self.observation_space = spaces["image"] if image_only else gym.spaces.Dict(spaces)
        self._distance_high = spaces["distance_mm"].high.tolist()

    # ---------------------------------------------------------------- task hooks

    def _reset_task(self) -> None:
        """Place the ball and draw the task's random parameters (from ``self.np_random``)."""

    def _before_frame(self) -> None:
        """Called before each 8 ms joint frame (e.g. to move the ball kinematically; not to
        command the servos, whose set-points for the step are planned before its first frame)."""

    def _evaluate(self) -> tuple[float, bool]:
        """Reward and termination for the state after a step."""
        raise NotImplementedError

    def _info(self) -> dict:
        return {}

    # ---------------------------------------------------------------- gymnasium API

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode: the keyframe ``stand``, the randomisations drawn, the task's start.

        :param seed: seeds the environment's RNG, from which the simulation's noise streams, the
            randomisations and the task's draws come; ``None`` goes on with the current RNG.
        :param options: not used by these tasks.
        :returns: ``(observation, info)``.
        :raises gymnasium.error.ClosedEnvironmentError: after ``close``.
        """
        super().reset(seed=seed)
        self.sim.reset(seed=int(self.np_random.integers(2**63)))
        self._randomize_scene()
        self._reset_task()
        mujoco.mj_forward(self.sim.model, self.sim.data)
        self._reset_done = True
        return self._observation(), self._info()

    def step(self, action):
        """Give ``action`` to the servos as targets and run the joint frames up to the camera's
        next frame (4 or 5 of 8 ms).

        :returns: ``(observation, reward, terminated, truncated, info)``; ``truncated`` is always
            False (``gymnasium.make``'s ``TimeLimit`` truncates).
        :raises ValueError: an action of the wrong shape, or not finite.
        :raises gymnasium.error.ResetNeeded: before the first ``reset``.
        :raises gymnasium.error.ClosedEnvironmentError: after ``close``.
        """
        check_open(self, "step")
        if not self._reset_done:
            raise gym.error.ResetNeeded(f"{type(self).__name__}.step before reset(): reset the environment first")
        targets = self.action_to_targets(action)
        self.sim.servos.set_target(self._actuated, targets)
        self.sim.step_frames(self.sim.frames_to_camera_frame(), self._before_frame)
        observation = self._observation()
        reward, terminated = self._evaluate()
        return observation, reward, terminated, False, self._info()

    def render(self):
        """The ``tracking`` camera's view of the robot, a (360, 480, 3) uint8 RGB array, with
        ``render_mode="rgb_array"``; ``None`` otherwise.

        :raises gymnasium.error.ClosedEnvironmentError: after ``close``, whatever the render mode.
        """
        check_open(self, "render")
        if self.render_mode != "rgb_array":
            return None
        if self._renderer is None:
            self._renderer = Renderer(self.sim.model, *RENDER_SIZE, quality="high")
        return self._renderer.render(self.sim.data, "tracking")

    def __reduce_ex__(self, protocol):
        raise TypeError(
            f"{type(self).__name__} cannot be pickled or copied (it holds a MuJoCo simulation and OpenGL "
            "renderers): make a new environment with the same arguments and reset it with the same seed"
        )

    def close(self):
        """Free the renderers; the environment is then spent: ``step``, ``reset`` and ``render``
        raise ``gymnasium.error.ClosedEnvironmentError``. Closing again does nothing."""
        if getattr(self, "_closed", False):
            return
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        self.sim.close()
        self._closed = True
        self.sim = _ClosedSimulation(type(self).__name__)
        release_freed_memory()

    # ---------------------------------------------------------------- actions

    def action_to_targets(self, action) -> np.ndarray:
        """Joint targets (rad) for a normalised action; NaN or infinity raises ValueError."""
        action = self._per_joint(action, "action", "actions")
        action = np.minimum(np.maximum(action, -1.0), 1.0)
        return self._target_low + (action + 1) / 2 * self._target_span

    def targets_to_action(self, targets) -> np.ndarray:
        """The normalised action that commands ``targets`` (rad, clipped to the joint ranges);
        NaN or infinity raises ValueError."""
        scaled = 2 * (self._per_joint(targets, "targets", "targets") - self._target_low) / self._target_span - 1
        return np.clip(scaled, -1, 1).astype(np.float32)

    def _per_joint(self, values, what: str, all_of_them: str) -> np.ndarray:
        """``values`` as floats, one per actuated joint; ValueError naming ``what`` otherwise."""
        try:
            values = np.asarray(values, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError(f"{what} must be numbers, one per actuated joint, not {values!r}") from None
        if values.shape != self.action_space.shape:
            raise ValueError(f"{what} has shape {values.shape}, expected {self.action_space.shape}")
        if not np.isfinite(values).all():
            i = np.flatnonzero(~np.isfinite(values))[0]
            raise ValueError(f"{what}[{i}] ({self.actuated_joints[i]}) is {values[i]}: {all_of_them} must be finite")
        return values

    # ---------------------------------------------------------------- scene

    def _randomize_scene(self) -> None:
        model, rng = self.sim.model, self.np_random
        lights, headlight, ambient = self._nominal_lights
        spread = self.randomize.get("lighting", 0.0)
        model.light_diffuse[:] = lights * rng.uniform(1 - spread, 1 + spread, (len(lights), 1))
        factor = rng.uniform(1 - spread, 1 + spread)  # the headlight's light and the ambient light
        model.vis.headlight.diffuse[:] = headlight * factor
        model.vis.headlight.ambient[:] = ambient * factor
        spread = self.randomize.get("camera_robot", 0.0)
        self.camera_robot = RobotColour.draw(rng, spread) if spread else self.sim.camera.profile.robot
        self.sim.camera.set_robot(self.camera_robot)

    def ball_start(self, nominal_xy) -> np.ndarray:
        """The ball's start on the ground: ``nominal_xy`` moved by the ``ball_start`` randomisation."""
        reach = self.randomize.get("ball_start", 0.0)
        return np.asarray(nominal_xy, dtype=np.float64) + self.np_random.uniform(-reach, reach, 2)

    def drawn_ball_start(self, nominal_xy, refuse=lambda ball: False, state: mujoco.MjData | None = None) -> np.ndarray:
        """``ball_start`` about ``nominal_xy``, drawn again while the ball would lie off the default
        field or sink into something with everything else as in ``state`` (changed here; default a
        copy of the live state), as run refuses a ball (``placement.ball_start_problem``), or while
        ``refuse(ball)``; at most ``BALL_DRAWS`` times, then ``nominal_xy``. Not randomised:
        ``nominal_xy`` unchecked (drawn all the same, so the random stream stays one draw a reset)."""
        nominal_xy = np.asarray(nominal_xy, dtype=np.float64)
        if not self.randomize.get("ball_start"):
            return self.ball_start(nominal_xy)
        state = copy.copy(self.sim.data) if state is None else state
        for _ in range(BALL_DRAWS):
            ball = self.ball_start(nominal_xy)
            if not refuse(ball) and ball_start_problem(self.sim, ball, state) is None:
                return ball
        return nominal_xy

    def image_position(self, point) -> tuple[np.ndarray, bool]:
        """Where a world point lies in the head camera's current frame, by projection through
        the camera's lens (not from pixels).

        Returns the offset from the image centre in half-widths and half-heights (x right,
        y down; -1 and 1 at the edges, clipped to +-2) and whether the point is in front of
        the camera and inside the image.
        """
        offset, visible = self.sim.camera.image_offset(point)
        return np.array([min(max(v, -2.0), 2.0) for v in offset]), visible

    # ---------------------------------------------------------------- observations

    def _observation(self) -> dict | np.ndarray:
        if self.image_only:
            return self._camera_image()
        sim = self.sim
        # Noise can overshoot the range; clamped in Python floats (the bounds are float32 values).
        distances = [min(max(d, 0.0), high) for d, high in zip(sim.distances_mm(), self._distance_high)]
        observation = {
            "joint_positions": sim.joint_positions().astype(np.float32),
            "acceleration": sim.acceleration().astype(np.float32),
            "distance_mm": np.array(distances, np.float32),
            "touch": sim.touches().astype(np.int8),
        }
        if self.camera is not None:
            observation["image"] = self._camera_image()
        return observation

    def _camera_image(self) -> np.ndarray:
        frame = self.sim.camera.frame()
        if self.camera == "rgb":
            rgb = frame.rgb
            height, width, _ = self._image_shape
            if rgb.shape[0] == height:
                return rgb.copy()  # the frame's picture is shared and read-only
            return box_average(rgb, rgb.shape[0] // height)
        self.camera_message = frame.message
        if self.camera == "openr":
            return self._openr.serve(frame)
        layer = LAYERS[self.camera_layer]
        return np.stack([self.camera_message.band(layer, band) for band in YCRCB_BANDS], axis=-1)


def check_open(env, what: str) -> None:
    """ClosedEnvironmentError for ``env.what`` (a call) after the environment's ``close``."""
    if getattr(env, "_closed", False):
        raise gym.error.ClosedEnvironmentError(f"{type(env).__name__}.{what} after close(): make a new environment")


class _ClosedSimulation:
    """What a closed environment's ``sim`` becomes: any use (``reset``, ``render``, the task's
    hooks) raises ClosedEnvironmentError, instead of stepping a simulation whose renderer is freed."""

    def __init__(self, env_name: str):
        self._env_name = env_name

    def __getattr__(self, name):
        if name.startswith("__") or name == "_env_name":  # copy, pickle and repr probe for these
            raise AttributeError(name)
        raise gym.error.ClosedEnvironmentError(
            f"{self._env_name} is closed (its simulation's {name!r} was used after close()): make a new environment"
        )
