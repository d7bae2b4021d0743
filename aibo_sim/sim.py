"""The simulated ERS-7: model loading, 8 ms joint frames, servos, sensors, head camera.

Time is kept as OPEN-R keeps it: the robot advances in 8 ms joint frames (``FRAME_MS``),
each a whole number of MuJoCo steps; the head camera produces a frame whenever the
simulated time reaches the next multiple of 1/30 s.
"""

from __future__ import annotations

import collections
import ctypes
import logging
import math
import numbers
import os
import threading
from collections.abc import Callable, Iterable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from xml.etree import ElementTree

import mujoco
import numpy as np

from openr_bridge import FRAME_RATE_HZ, FRAME_TICK_MS

from .camera import CameraFrame, HeadCamera, scene_light
from .camera.head import BEHIND_CAMERA_GROUP, HEAD_CAMERA_GROUPS
from .config import CameraConfig, ParameterError, configs, is_seed
from .ers7 import (
    DISTANCE_SENSORS,
    HEAD_CAMERA,
    JOINTS,
    LED_BY_NAME,
    LED_OFF_RGBA,
    LEDS_BY_GEOM,
    SENSORS,
    TOUCH_SENSORS,
)
from .field import BALL_TYPES, COLOURS, DEFAULT_BALL_TYPE, PINK_BALL_MASS, PINK_BALL_RADIUS, SPECULAR, UNIFORM_COLOURS
from .lod import add_levels_of_detail

FRAME_MS = FRAME_TICK_MS  # OPEN-R joint frame, 8 ms
MAX_LATENCY_FRAMES = 125  # command_latency_frames: at most a second (OPEN-R's is 4 frames)
GRAVITY = 9.80665
ACCEL_RANGE = 2 * GRAVITY  # Sony: +-19 613 300 um/s^2
IR_NOISE = 0.1  # Webots lookup tables: 10 % noise at mid-range, none at the ends


class ModelError(ValueError):
    """A model or scene file is missing or invalid; the message names the file."""


try:
    _malloc_trim = ctypes.CDLL(None).malloc_trim  # glibc's
except (OSError, AttributeError):
    _malloc_trim = None


def release_freed_memory() -> None:
    """Give the memory freed so far back to the system (glibc's ``malloc_trim``; nothing
    elsewhere): glibc keeps freed blocks for reuse, so without it the resident memory of a
    process that closed simulations (their models, buffers, renderers) would not fall."""
    if _malloc_trim is not None:
        _malloc_trim(0)


def _log_mujoco_warning(text: str) -> None:
    """MuJoCo's warnings (a diverging state, a full contact buffer) go to the logger
    ``aibo_sim.mujoco`` (stderr unless configured). MuJoCo's own handler appends them to
    MUJOCO_LOG.TXT in the working directory, through any link found there, and prints them
    on standard output."""
    logging.getLogger("aibo_sim.mujoco").warning("MuJoCo: %s", text)


if mujoco.get_mju_user_warning() is None:
    mujoco.set_mju_user_warning(_log_mujoco_warning)


def ball_joint(model: mujoco.MjModel) -> int:
    """The free joint that moves the scene's ball; ModelError when the scene has no body named
    'ball' or that body cannot be placed."""
    body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "ball")
    if body < 0:
        raise ModelError("this scene has no body named 'ball' to place")
    joint = model.body_jntadr[body]
    if model.body_jntnum[body] != 1 or model.jnt_type[joint] != mujoco.mjtJoint.mjJNT_FREE:
        raise ModelError("this scene's body 'ball' cannot be placed: it needs one free joint (a freejoint)")
    return int(joint)


class SimulationDiverged(RuntimeError):
    """The physics produced NaN or unbounded accelerations."""


def models_dir() -> Path:
    """The bundled ``models/`` folder (source checkout or installed wheel)."""
    here = Path(__file__).resolve().parent
    for candidate in (here / "models", here.parent / "models"):
        if (candidate / "ers7.xml").is_file():
            return candidate
    raise ModelError(f"bundled models not found next to {here}")


def _named_in(table: dict, name, what: str):
    """``table[name]``; a ValueError listing the names of the ``what``s for an unknown one."""
    try:
        return table[name]
    except (KeyError, TypeError):  # TypeError: a name that cannot be a key (a list)
        raise ValueError(f"no {what} named {name!r}; the {what}s: {', '.join(table)}") from None


def default_scene() -> Path:
    """The bundled RoboCup field, ``models/scene.xml``: the scene where none is given."""
    return models_dir() / "scene.xml"


def load_model(
    scene: str | Path | None = None, ball: bool = True, ball_type: str = DEFAULT_BALL_TYPE, robots=None
) -> mujoco.MjModel:
    """Compile a scene file (default: the RoboCup field), with an error that names the file
    (also for its light's custom numerics out of range, ``SceneLight``, and a timestep that is
    not a positive divisor of the 8 ms joint frame); ``ball=False`` leaves out its body named
    ``ball``, ``ball_type="pink"`` makes it Sony's pink ball (``field.PINK_BALL_RADIUS``);
    ``robots`` (``team.RobotSpec``s, the first the scene's own robot) adds the others and the
    uniforms (``add_robots``)."""
    match = robots is not None and (len(robots) > 1 or any(robot.team is not None for robot in robots))
    if ball_type not in BALL_TYPES:
        raise ParameterError.at("ball_type", repr(ball_type), f"must be one of {', '.join(BALL_TYPES)}")
    path = Path(scene) if scene is not None else default_scene()
    try:
        if not path.is_file():
            raise ModelError(f"{path}: " + ("not a regular file" if path.exists() else "no such model file"))
        with open(path, "rb"):  # readable: MuJoCo calls a file it cannot open empty
            pass
    except OSError as exc:  # a name too long, a folder or the file without permission
        raise ModelError(f"{path}: cannot read: {exc.strerror or exc}") from None
    if path.suffix != ".xml":  # MuJoCo's MjSpec (a match, a pink ball, no ball) finds its reader by it
        raise ModelError(f"{path}: not an MJCF file's name: a scene is read by its extension, .xml")
    _check_included_files(path, path.parent)
    try:
        if ball and ball_type == DEFAULT_BALL_TYPE and not match:
            model = mujoco.MjModel.from_xml_path(str(path))
        else:
            spec = mujoco.MjSpec.from_file(str(path))
            body = spec.body("ball")
            if body is not None and not ball:
                spec.delete(body)
            elif body is not None and ball_type == "pink" and spec.geom("ball") is not None:
                geom = spec.geom("ball")
                geom.size, geom.mass = [PINK_BALL_RADIUS, 0, 0], PINK_BALL_MASS
                body.pos = [body.pos[0], body.pos[1], PINK_BALL_RADIUS]
                if spec.material("pink_ball") is None:  # the generated field has it; other scenes may not
                    spec.add_material(name="pink_ball", rgba=COLOURS["pink_ball"], specular=SPECULAR["pink_ball"])
                geom.material = "pink_ball"
            if match and spec.body("body") is not None:  # without the robot: check_robot's error
                add_robots(spec, robots)
            model = spec.compile()
        scene_light(model)  # its custom numerics in range
        timestep = model.opt.timestep
        steps = FRAME_MS / 1000 / timestep if timestep > 0 else 0.0
        if steps < 1 or abs(steps - round(steps)) > 1e-9:
            raise ValueError(f"the timestep ({timestep} s) must be positive and divide the 8 ms joint frame")
        return model
    except ValueError as exc:  # MuJoCo's message spans lines (the element and line on the second): one line
        lines = (line.strip().rstrip(":") for line in str(exc).splitlines())
        raise ModelError(f"{path}: " + "; ".join(line for line in lines if line)) from None


def _check_included_files(path: Path, folder: Path, seen: frozenset = frozenset()) -> None:
    """ModelError naming ``path`` and the file where a file it includes (``<include file>``, found
    as MuJoCo finds it: in ``folder``, the top scene's, else beside ``path``) exists but is not a
    regular file: MuJoCo would wait for good on a FIFO. Other faults are MuJoCo's to name."""
    try:
        root = ElementTree.parse(path).getroot()
    except (ElementTree.ParseError, OSError):
        return
    for include in root.iter("include"):
        name = include.get("file")
        if not name:
            continue
        included = next((f / name for f in (folder, path.parent) if os.path.lexists(f / name)), None)
        if included is None or included in seen:
            continue
        if not included.is_file():
            raise ModelError(f"{path}: includes {name}: not a regular file")
        _check_included_files(included, folder, seen | {included})


def check_robot(model: mujoco.MjModel, path, keyframe: str = "stand") -> None:
    """ModelError naming ``path`` unless ``model`` holds the ERS-7 (``models/ers7.xml``: its
    body, joints, actuators, sensors, head and tracking cameras), a body ``ball`` has its geom
    ``ball``, and, when ``keyframe`` is ``"stand"``
    (the start pose every command uses), a keyframe of that name. Another keyframe a caller
    asks for is looked up when it is used (``reset``), whose KeyError lists the scene's."""

    def missing(kind: mujoco.mjtObj, names) -> list[str]:
        return [name for name in names if mujoco.mj_name2id(model, kind, name) < 0]

    absent = {
        "body": missing(mujoco.mjtObj.mjOBJ_BODY, ["body"]),
        "joints": missing(mujoco.mjtObj.mjOBJ_JOINT, [j.name for j in JOINTS]),
        "actuators": missing(mujoco.mjtObj.mjOBJ_ACTUATOR, [j.name for j in JOINTS]),
        "sensors": missing(mujoco.mjtObj.mjOBJ_SENSOR, [s.name for s in SENSORS if s.kind != "camera"]),
        "camera": missing(mujoco.mjtObj.mjOBJ_CAMERA, [HEAD_CAMERA, "tracking"]),  # tracking: render's, the envs'
        "LED geoms": missing(mujoco.mjtObj.mjOBJ_GEOM, list(LEDS_BY_GEOM)),
    }
    absent = {kind: names for kind, names in absent.items() if names}
    if absent:
        listed = "; ".join(
            f"{kind} {', '.join(map(repr, names[:3]))}" + (f" and {len(names) - 3} more" if len(names) > 3 else "")
            for kind, names in absent.items()
        )
        raise ModelError(
            f"{path}: no ERS-7 robot in this scene (missing {listed}); "
            'a scene must <include file="ers7.xml"/> (see models/scene.xml)'
        )
    ball = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "ball")
    geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "ball")
    if ball >= 0 and (geom < 0 or model.geom_bodyid[geom] != ball):
        raise ModelError(f"{path}: the body 'ball' needs its geom named 'ball' (its radius places it, labels name it)")
    if keyframe == "stand" and mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, keyframe) < 0:
        keys = [model.key(i).name for i in range(model.nkey)]
        raise ModelError(
            f"{path}: no keyframe 'stand' (the robot's start pose, in models/ers7.xml); the scene's "
            f"keyframes: {', '.join(repr(k) for k in keys) if keys else 'none'}"
        )


MAX_PLACEMENT = 1e6  # metres (or radians of yaw): beyond this a placement is a typo, as on the command line


def placement_values(function: str, **values) -> list[float]:
    """The values as floats; ValueError naming the argument when one is not a finite number of
    magnitude at most MAX_PLACEMENT."""
    numbers = []
    for name, value in values.items():
        try:
            if isinstance(value, (str, bytes)):
                raise TypeError
            number = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"{function}: {name} must be a number, not {value!r}") from None
        if not math.isfinite(number) or abs(number) > MAX_PLACEMENT:
            raise ValueError(
                f"{function}: {name} = {value!r} must be a finite number of magnitude at most {MAX_PLACEMENT:g}"
            )
        numbers.append(number)
    return numbers


class Servos:
    """Webots/OPEN-R style position servos in front of MuJoCo's position actuators.

    Each 8 ms frame the commanded set-point moves towards the target no faster than the
    joint's velocity limit (Sony's maximum speed by default) and, when an acceleration
    limit is set, with bounded acceleration; targets are clipped to the joint range.
    """

    def __init__(self, model: mujoco.MjModel, prefix: str = ""):
        ids = [model.actuator(prefix + j.name).id for j in JOINTS]
        if ids != list(range(ids[0], ids[0] + len(JOINTS))):
            raise ModelError("actuators must follow the order of ers7.JOINTS")
        self.ctrl = slice(ids[0], ids[0] + len(JOINTS))  # the robot's actuators in MjData.ctrl
        self.low, self.high = (
            model.actuator_ctrlrange[self.ctrl, 0].copy(),
            model.actuator_ctrlrange[self.ctrl, 1].copy(),
        )
        self.max_velocity = np.array([j.max_speed for j in JOINTS])
        self.velocity = self.max_velocity.copy()
        self.acceleration = np.full(len(JOINTS), np.inf)
        self.target = np.zeros(len(JOINTS))
        self.command = np.zeros(len(JOINTS))
        self._speed = np.zeros(len(JOINTS))

    def reset(self, positions: np.ndarray) -> None:
        """Targets and set-points to ``positions`` (clipped to the joint ranges), at rest."""
        self.target[:] = self.command[:] = np.clip(positions, self.low, self.high)
        self._speed[:] = 0

    def set_target(self, index, position) -> None:
        """Target of the joints ``index`` (an index, slice or array), clipped to their ranges."""
        self.target[index] = np.minimum(np.maximum(position, self.low[index]), self.high[index])

    def advance(self, dt: float) -> np.ndarray:
        """Move the set-points one frame towards the targets; returns them."""
        error = self.target - self.command
        if not error.any():  # at rest: speeds are zero on arrival
            return self.command
        limit = np.minimum(self.velocity, self.max_velocity)
        if np.isinf(self.acceleration).all():
            # Full speed until arrival: what the general case below gives bit for bit (its
            # stopping speed exceeds the limit wherever the target is not reached this frame).
            self._speed = np.copysign(limit, error)
        else:
            accel = np.minimum(self.acceleration, 1e9)  # "unlimited" stays finite arithmetic
            # Speed that still stops at the target under the acceleration limit.
            stop = np.sqrt(2 * accel * np.abs(error))
            wanted = np.sign(error) * np.minimum(limit, stop)
            self._speed = np.clip(wanted, self._speed - accel * dt, self._speed + accel * dt)
        step = self._speed * dt
        arrived = np.abs(step) >= np.abs(error)
        self.command = np.where(arrived, self.target, self.command + step)
        self._speed[arrived] = 0
        return self.command

    def advance_frames(self, frames: int, dt: float) -> np.ndarray:
        """The set-points of the next ``frames`` frames, one row each: what as many calls of
        ``advance`` return, bit for bit, computed in one pass when no joint has an
        acceleration limit (each moving joint then steps by the same amount every frame
        until it arrives; numpy's cumulative sum adds the steps in order, as frame after
        frame does)."""
        if frames == 1:
            return self.advance(dt)[np.newaxis]
        error = self.target - self.command
        if not error.any() or not np.isinf(self.acceleration).all():
            return np.array([self.advance(dt) for _ in range(frames)])
        speed = np.copysign(np.minimum(self.velocity, self.max_velocity), error)
        step = speed * dt
        path = np.empty((frames + 1, len(step)))  # the set-points before each frame and after the last
        path[0], path[1:] = self.command, step
        path.cumsum(axis=0, out=path)
        # Arrived in a frame: the step covers what was left before it; set-points stay there.
        arrived = np.logical_or.accumulate(np.abs(step) >= np.abs(self.target - path[:-1]), axis=0)
        commands = np.where(arrived, self.target, path[1:])
        self.command = commands[-1].copy()
        self._speed = np.where(arrived[-1], 0.0, speed)
        return commands


def robot_prefix(index: int) -> str:
    """Prefix of the names of a world's robot ``index`` (from 0): none for the first (the scene's
    own ERS-7), ``robot2/``, ``robot3/``, ... for the robots a match adds."""
    return f"robot{index + 1}/" if index else ""


def add_robots(spec: mujoco.MjSpec, robots) -> None:
    """Add to a scene's ``spec`` the robots after its own (``robots[1:]``, each a copy of
    ``models/ers7.xml`` named with ``robot_prefix``) and each team's uniform on every robot
    that has a team: patches on the flanks in the team's colour (``field.UNIFORM_COLOURS``), visual only
    (no mass, no contact: the physics stays that of the bare robot). The robots collide with
    each other, never with themselves. With several robots, the coarser copies of their visual
    geoms their cameras draw the other robots with (``lod.add_levels_of_detail``)."""
    for index, robot in enumerate(robots):
        prefix = robot_prefix(index)
        if index:
            copy = mujoco.MjSpec.from_file(str(models_dir() / "ers7.xml"))
            for key in list(copy.keys):  # the robot's poses are set per robot at reset
                copy.delete(key)
            spec.worldbody.add_frame().attach_body(copy.body("body"), prefix, "")
        # Robots touch each other as they touch the field: robot k's collision geoms have
        # contype bit k + 1 and affinity with the field's bit 0 and every other robot's bit.
        own_bit, all_bits = 2 << index, sum(2 << k for k in range(len(robots)))
        for geom in spec.body(prefix + "body").find_all(mujoco.mjtObj.mjOBJ_GEOM):
            if geom.contype or geom.conaffinity:
                geom.contype, geom.conaffinity = own_bit, 1 | (all_bits & ~own_bit)
        if robot.team is not None:
            body = spec.body(prefix + "body")
            for side in (1, -1):
                body.add_geom(
                    name=f"{prefix}uniform_{'left' if side > 0 else 'right'}",
                    type=mujoco.mjtGeom.mjGEOM_BOX,
                    size=UNIFORM_PATCH,
                    pos=[0, side * UNIFORM_FLANK_Y, 0.012],
                    rgba=UNIFORM_COLOURS[robot.team],
                    group=2,
                    contype=0,
                    conaffinity=0,
                    density=0,
                )
    if len(robots) > 1:  # the robots' cameras see each other: coarser copies of what they draw
        bodies = [robot_prefix(index) + "body" for index in range(len(robots))]
        add_levels_of_detail(spec, bodies, (*HEAD_CAMERA_GROUPS, BEHIND_CAMERA_GROUP))


UNIFORM_PATCH = (0.05, 0.002, 0.028)  # half sizes: a 10 x 5.6 cm patch on each flank (the league's uniforms)
UNIFORM_FLANK_Y = 0.051  # just outside the body shell's 5 cm half width


class World:
    """A scene and its robots, advanced together in 8 ms frames (see ``Simulation``, each robot's
    view of it). Made by ``Simulation``; ``robots`` lists the views, the first being robot 1."""

    def __init__(self, first: Simulation, scene, robots, *, seed, keyframe, camera, ball, ball_type, latency):
        if isinstance(latency, bool) or not isinstance(latency, int) or not 0 <= latency <= MAX_LATENCY_FRAMES:
            raise ValueError(
                f"command_latency_frames must be a whole number from 0 to {MAX_LATENCY_FRAMES}, not {latency!r}"
            )
        self.command_latency_frames = latency
        self.scene = scene  # as given: None for the RoboCup field
        # The bundled field, named or not: its carpet bounds a pose and a ball (placement.place).
        self.default_field = scene is None or Path(scene).resolve() == default_scene().resolve()
        self.robot_specs = tuple(robots)
        if self.default_field:
            from .team import check_on_the_carpet

            check_on_the_carpet(self.robot_specs)
        self.model = load_model(scene, ball, ball_type, self.robot_specs)
        check_robot(self.model, scene if scene is not None else default_scene(), keyframe)
        self.keyframe = keyframe
        self._keyframe_id(keyframe)  # a ValueError naming the scene's keyframes, before any work
        self.data = mujoco.MjData(self.model)
        self.steps_per_frame = round(FRAME_MS / 1000 / self.model.opt.timestep)
        # Views of the divergence counters, read after every frame (bad positions and velocities:
        # MuJoCo resets the state silently and counts them here).
        self._divergence_warnings = [
            self.data.warning[w]
            for w in (
                mujoco.mjtWarning.mjWARN_BADQACC,
                mujoco.mjtWarning.mjWARN_BADCTRL,
                mujoco.mjtWarning.mjWARN_BADQPOS,
                mujoco.mjtWarning.mjWARN_BADQVEL,
            )
        ]
        self.ball_body = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, "ball")  # -1: no ball
        self.frame = 0
        self.lockstep = None  # a Lockstep while robots' controllers step the world together
        # Renders and labels change the model for their time (geom groups, the lens's intrinsics):
        # a match's cameras build their scenes one at a time (Renderer; a dump's labels hold it
        # too), and with a software OpenGL draw them in parallel.
        self.render_lock = threading.RLock()
        self._frame_makers: ThreadPoolExecutor | None = None
        self.robots: list[Simulation] = []
        for index, spec in enumerate(self.robot_specs):
            robot = first if index == 0 else Simulation.__new__(Simulation)
            robot._attach(self, index, spec, camera)
            self.robots.append(robot)
        self.reset(seed)

    def _keyframe_id(self, name) -> int:
        """The id of the scene's keyframe ``name``; a ValueError naming the keyframes there are."""
        key = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_KEY, name) if isinstance(name, str) else -1
        if key < 0:
            names = [self.model.key(k).name for k in range(self.model.nkey)]
            raise ParameterError.at(
                "keyframe", repr(name), f"no such keyframe; the scene's: {', '.join(names) or 'none'}"
            )
        return key

    def reset(self, seed: int | None = None, keyframe: str | None = None) -> None:
        """Every robot back to the keyframe (robot 1 where the keyframe has it, the others beside it
        in the same posture at their own poses); a new ``seed`` restarts the noise streams."""
        if seed is not None:
            if not is_seed(seed):
                raise ValueError(f"seed must be a whole number from 0 to 2**64 - 1, not {seed!r}")
            self.seed = int(seed)
        mujoco.mj_resetDataKeyframe(self.model, self.data, self._keyframe_id(keyframe or self.keyframe))
        first = self.robots[0]
        for robot in self.robots:
            robot._take_posture(first)
        mujoco.mj_forward(self.model, self.data)
        self.frame = 0  # 8 ms frames since reset
        for robot in self.robots:
            robot._reset(seed is not None)

    @property
    def cameras(self) -> list[HeadCamera]:
        """Each robot's head camera, in robot order."""
        return [robot.camera for robot in self.robots]

    def step_frames(self, frames: int, before_frame: Callable[[], None] | None = None, sensors: bool = True) -> None:
        """``Simulation.step_frames`` for every robot at once."""
        if not isinstance(frames, int) or frames < 1:
            raise ValueError(f"frames must be a whole number >= 1, not {frames!r}")
        plans = [(robot.servos.ctrl, robot._planned(frames)) for robot in self.robots]
        model, data, options, cameras = self.model, self.data, self.model.opt, self.cameras
        steps = [self.steps_per_frame] * frames
        steps[-1] -= sensors  # the last step, with sensors, after the loop
        flags = options.disableflags
        options.disableflags = flags | mujoco.mjtDisableBit.mjDSBL_SENSOR
        try:
            for k, nstep in enumerate(steps, start=1):
                for camera in cameras:
                    camera.before_frame()
                if before_frame is not None:
                    before_frame()
                for actuators, commands in plans:
                    data.ctrl[actuators] = commands[k - 1]
                if self.command_latency_frames:  # LED commands on their way (none without a latency)
                    for robot in self.robots:
                        robot._light_queued()
                if nstep:
                    mujoco.mj_step(model, data, nstep=nstep)
                self.frame += 1
                if k < frames:
                    for camera in cameras:
                        camera.after_frame()
        finally:
            options.disableflags = flags
        if sensors:
            mujoco.mj_step(model, data)
        for camera in cameras:
            camera.after_frame()
        if any(w.number for w in self._divergence_warnings) or not np.isfinite(data.qpos).all():
            raise SimulationDiverged(f"physics diverged at t = {data.time:.3f} s (by frame {self.frame})")

    def camera_frame_index(self, frame: int | None = None) -> int:
        """Index of the newest 30 fps camera frame (frame k at k/30 s) now, or after the 8 ms
        joint frame ``frame``."""
        return (self.frame if frame is None else frame) * FRAME_MS * FRAME_RATE_HZ // 1000

    def frames(self, cameras: Iterable[HeadCamera] | None = None) -> list[CameraFrame]:
        """The current frames (``HeadCamera.frame``) of ``cameras`` (default every robot's, in robot
        order), made in parallel threads (one a camera, up to the machine's cores) where the
        cameras draw in parallel (a software OpenGL, ``Renderer``), else one after another."""
        cameras = self.cameras if cameras is None else list(cameras)
        if len(cameras) < 2 or not all(camera.draws_in_parallel() for camera in cameras):
            return [camera.frame() for camera in cameras]
        if self._frame_makers is None:
            workers = min(len(cameras), os.cpu_count() or 1)
            self._frame_makers = ThreadPoolExecutor(workers, thread_name_prefix="camera")
        return list(self._frame_makers.map(HeadCamera.frame, cameras))

    def close(self) -> None:
        """Free every robot's camera renderer."""
        if self._frame_makers is not None:
            self._frame_makers.shutdown()
            self._frame_makers = None
        for camera in self.cameras:
            camera.close()


class Simulation:
    """An ERS-7 in a scene, advanced in 8 ms frames, with its head camera (``camera``, set up
    as ``camera``, a ``config.CameraConfig``, says: default the ``ers7`` profile); ``ball=False``
    leaves the scene's ball out, ``ball_type`` chooses it (``field.BALL_TYPES``).

    ``robots`` (``team.RobotSpec``s; default one robot, the scene's own) puts several robots on
    the field: this object is robot 1, ``world.robots`` lists them all, each a ``Simulation``
    of its own robot (servos, sensors, LEDs, camera and noise streams) sharing the world (model,
    data, time, ball): stepping any of them steps the world. They are checked as
    ``team.check_robots`` does (a TeamError names the robot: a duplicate; a pose off the default field's carpet).

    ``command_latency_frames``: 8 ms frames between a set-point and the servo acting on it (or
    an LED command and the LED). On the robot, OPEN-R plays joint and LED commands from a queue
    of 4-frame command vectors, so a command waits 32 ms or more; how many vectors the Webots-era
    wrapper kept in flight is UNCONFIRMED, so the default is 0 (the set-point acts in the next
    frame); at most ``MAX_LATENCY_FRAMES``."""

    def __init__(
        self,
        scene=None,
        *,
        seed: int = 0,
        keyframe: str = "stand",
        camera: CameraConfig | None = None,
        ball: bool = True,
        ball_type: str = DEFAULT_BALL_TYPE,
        command_latency_frames: int = 0,
        robots=None,
    ):
        from .team import DEFAULT_ROBOTS, check_robots

        World(
            self,
            scene,
            DEFAULT_ROBOTS if robots is None else check_robots(robots, "robots"),
            seed=seed,
            keyframe=keyframe,
            camera=configs(camera=camera)[1],
            ball=ball,
            ball_type=ball_type,
            latency=command_latency_frames,
        )

    def _attach(self, world: World, index: int, spec, camera: CameraConfig) -> None:
        """Become robot ``index`` (``spec``) of ``world``."""
        model, prefix = world.model, robot_prefix(index)
        self.world, self.index, self.spec, self.prefix = world, index, spec, prefix
        self.servos = Servos(model, prefix)
        self._sensor_slices = {
            s.name: slice(
                model.sensor(prefix + s.name).adr[0],
                model.sensor(prefix + s.name).adr[0] + model.sensor(prefix + s.name).dim[0],
            )
            for s in SENSORS
            if s.kind != "camera"
        }
        self._distance_adr = np.array([self._sensor_slices[s.name].start for s in DISTANCE_SENSORS])
        self._distance_index = {s.name: i for i, s in enumerate(DISTANCE_SENSORS)}
        self._distance_ranges_mm = [s.range_mm for s in DISTANCE_SENSORS]
        self._touch_adr = np.array([self._sensor_slices[s.name].start for s in TOUCH_SENSORS])
        self._touch_threshold = np.array([s.threshold for s in TOUCH_SENSORS])
        self._joint_qpos = np.array([model.joint(prefix + j.name).qposadr[0] for j in JOINTS])
        self._body = model.body(prefix + "body").id
        self._root_qpos = model.jnt_qposadr[model.body_jntadr[self._body]]
        self._led_geoms = {geom: model.geom(prefix + geom).id for geom in LEDS_BY_GEOM}
        self._lit: dict[str, tuple[float, bool]] = {}  # LED name: (level, B face) as last set
        self.camera = HeadCamera(self, camera.size, camera.profile, camera.settings, camera_name=prefix + HEAD_CAMERA)

    # ---------------------------------------------------------------- the world, shared

    model = property(lambda self: self.world.model)
    data = property(lambda self: self.world.data)
    frame = property(lambda self: self.world.frame)
    scene = property(lambda self: self.world.scene)
    default_field = property(lambda self: self.world.default_field)
    keyframe = property(lambda self: self.world.keyframe)
    steps_per_frame = property(lambda self: self.world.steps_per_frame)
    command_latency_frames = property(lambda self: self.world.command_latency_frames)

    @property
    def seed(self) -> int:
        """The world's seed; this robot's noise streams are drawn from it (``robot_seed``)."""
        return self.world.seed

    # ---------------------------------------------------------------- time and state

    def reset(self, seed: int | None = None, keyframe: str | None = None) -> None:
        """The world back to ``keyframe`` (default the start keyframe), every robot with it."""
        self.world.reset(seed, keyframe)

    def _take_posture(self, first: Simulation) -> None:
        """After a keyframe reset: robot 1's posture at this robot's pose (``spec.pose``: x, y
        metres, yaw degrees; robot 1 without one stays where the keyframe has it)."""
        qpos, root = self.data.qpos, self._root_qpos
        if self is not first:
            qpos[self._joint_qpos] = qpos[first._joint_qpos]
            qpos[root : root + 7] = qpos[first._root_qpos : first._root_qpos + 7]
        if self.spec.pose is not None:
            x, y, yaw = self.spec.pose
            pitch_quat = qpos[root + 3 : root + 7].copy()
            qpos[root : root + 2] = x, y
            yaw_quat = np.array([math.cos(math.radians(yaw) / 2), 0, 0, math.sin(math.radians(yaw) / 2)])
            mujoco.mju_mulQuat(qpos[root + 3 : root + 7], yaw_quat, pitch_quat)

    def _reset(self, reseed: bool) -> None:
        """After the world's reset: servos at the posture, noise streams restarted on a new seed."""
        if reseed:  # the world is made with its seed, so every robot gets one at the start
            self.rng = np.random.default_rng(self.robot_seed)  # IR noise; the camera's noise has its own stream
        self.servos.reset(self.joint_positions())
        self._queued_leds = collections.deque()  # (frame due, set_led's arguments) with a command latency
        for name in list(self._lit):  # LEDs off
            self._light(name, 0.0, False)
        self._queued = np.tile(self.servos.command, (self.command_latency_frames, 1))  # set-points on their way
        self.camera.reset(self.robot_seed)

    @property
    def robot_seed(self) -> int:
        """The seed of this robot's noise streams (IR, camera): the world's for robot 1, one drawn
        from the world's seed and the robot's number for each other robot."""
        if self.index == 0:
            return self.seed
        return int(np.random.SeedSequence([self.seed, self.index]).generate_state(1, np.uint64)[0])

    def _planned(self, frames: int) -> np.ndarray:
        """The set-points the servos act on in the next ``frames`` frames, one row each."""
        commands = self.servos.advance_frames(frames, FRAME_MS / 1000)
        if self.command_latency_frames:
            queue = np.concatenate((self._queued, commands))
            commands, self._queued = queue[:frames], queue[frames:]
        return commands

    def place_robot(self, x: float, y: float, yaw: float) -> None:
        """Put the robot at (x, y) on the field heading ``yaw`` (rad), keeping its height and pitch.
        Each must be a finite number of magnitude at most ``MAX_PLACEMENT`` (else ValueError
        naming it, nothing moved): MuJoCo would otherwise silently reset the whole state."""
        x, y, yaw = placement_values("place_robot", x=x, y=y, yaw=yaw)
        root = self._root_qpos
        qpos = self.data.qpos
        pitch_quat = qpos[root + 3 : root + 7].copy()
        yaw_quat = np.array([math.cos(yaw / 2), 0, 0, math.sin(yaw / 2)])
        qpos[root : root + 2] = x, y
        mujoco.mju_mulQuat(qpos[root + 3 : root + 7], yaw_quat, pitch_quat)
        mujoco.mj_forward(self.model, self.data)
        self._moved()

    def _moved(self) -> None:
        for camera in self.world.cameras:
            camera.moved()

    @property
    def has_ball(self) -> bool:
        """Whether the scene has a ball."""
        return self.world.ball_body >= 0

    def place_ball(self, x: float, y: float) -> None:
        """Put the ball at rest on the carpet at (x, y); finite numbers of magnitude at most
        ``MAX_PLACEMENT`` metres, as for ``place_robot``."""
        x, y = placement_values("place_ball", x=x, y=y)
        position, velocity = self.ball_state()
        position[:] = (x, y, self.model.geom("ball").size[0], 1, 0, 0, 0)
        velocity[:] = 0
        mujoco.mj_forward(self.model, self.data)
        self._moved()

    def ball_state(self) -> tuple[np.ndarray, np.ndarray]:
        """Views into ``data`` of the ball's free joint: position and quaternion (7), velocity
        (6); ModelError as ``ball_joint``."""
        joint = ball_joint(self.model)
        qpos, dof = self.model.jnt_qposadr[joint], self.model.jnt_dofadr[joint]
        return self.data.qpos[qpos : qpos + 7], self.data.qvel[dof : dof + 6]

    def ball_position(self, data: mujoco.MjData | None = None) -> np.ndarray | None:
        """The ball's centre (in ``data``, default the live state), or None in a scene without a ball."""
        return (self.data if data is None else data).xpos[self.world.ball_body].copy() if self.has_ball else None

    def overlaps(self, depth: float, data: mujoco.MjData | None = None) -> list[tuple[str, str, float]]:
        """Pairs that penetrate each other deeper than ``depth`` metres in the current state (in
        ``data``, default the live one: MuJoCo's contacts), deepest first: (first, second,
        metres), each "the robot" (with several robots, each by its name: "red 2"), "the ball"
        or the other geom's name (its body's, or its number, when it has none)."""
        model, contacts, world = self.model, (self.data if data is None else data).contact, self.world
        robots = {model.body_rootid[robot._body]: robot for robot in world.robots}

        def name(geom: int) -> str:
            body = model.geom_bodyid[geom]
            robot = robots.get(model.body_rootid[body])
            if robot is not None:
                return "the robot" if len(robots) == 1 else robot.spec.name
            if body == world.ball_body:
                return "the ball"
            return model.geom(geom).name or model.body(body).name or f"geom {geom}"

        order = np.argsort(contacts.dist)
        return [
            (name(contacts.geom1[i]), name(contacts.geom2[i]), -float(contacts.dist[i]))
            for i in order
            if contacts.dist[i] < -depth
        ]

    @property
    def time_ms(self) -> int:
        """Simulated time in ms since reset (8 ms joint frames)."""
        return self.frame * FRAME_MS

    def step_frame(self, sensors: bool = True) -> None:
        """Advance one 8 ms joint frame; raises SimulationDiverged on NaN physics. See
        ``step_frames``."""
        self.step_frames(1, sensors=sensors)

    def step_frames(self, frames: int, before_frame: Callable[[], None] | None = None, sensors: bool = True) -> None:
        """Advance ``frames`` 8 ms joint frames, calling ``before_frame()`` (which must leave
        the servos alone: their set-points are planned for all the frames at once) before
        each; raises SimulationDiverged if the physics went NaN or unbounded. In a world whose
        robots' controllers step together (``world.lockstep``), each frame waits for them all.

        Sensors are read after the frames, so MuJoCo computes them only in the last step,
        and in none with ``sensors=False`` (for a caller that reads no sensor now): they do
        not feed back into the dynamics, so the trajectory and the readings are those of
        plain stepping, and each step without them saves the ~9 us (of ~30 us) that the IR
        rays, touch sensors and accelerometer cost.
        """
        if self.world.lockstep is not None:
            self.world.lockstep.step(self, frames, before_frame)
        else:
            self.world.step_frames(frames, before_frame, sensors)

    def camera_frame_index(self, frame: int | None = None) -> int:
        """Index of the newest 30 fps camera frame (frame k at k/30 s) now, or after the 8 ms
        joint frame ``frame``."""
        return self.world.camera_frame_index(frame)

    def frames_to_camera_frame(self) -> int:
        """8 ms joint frames until the camera's next frame is due (4 or 5 at 30 fps)."""
        now, frames = self.camera_frame_index(), 1
        while self.camera_frame_index(self.frame + frames) == now:
            frames += 1
        return frames

    # ---------------------------------------------------------------- readings

    def joint_positions(self, data: mujoco.MjData | None = None) -> np.ndarray:
        """Joint angles in radians (in ``data``, default the live state), in ``ers7.JOINTS`` order
        (a copy)."""
        return (self.data if data is None else data).qpos[self._joint_qpos]  # indexing copies

    def sensor(self, name: str) -> np.ndarray:
        """The MuJoCo sensor ``name``'s reading, a view of ``data.sensordata``."""
        return self.data.sensordata[_named_in(self._sensor_slices, name, "sensor")]

    def distances_mm(self, which: slice = slice(None)) -> list[float]:
        """IR ranges in mm of ``ers7.DISTANCE_SENSORS[which]`` as Webots' lookup tables give them:
        clamped to the sensor's range, 10 % noise mid-range (one draw per sensor, in order)."""
        metres = self.data.sensordata[self._distance_adr[which]].tolist()
        noise = self.rng.standard_normal(len(metres)).tolist()
        values = []
        for reading, (low, high), draw in zip(
            metres, self._distance_ranges_mm[which], noise
        ):  # a few sensors: scalar math is cheapest
            mm = high if reading < 0 else min(max(reading * 1000, low), high)  # < 0: no hit
            values.append(mm * (1 + IR_NOISE * (1 - abs(2 * (mm - low) / (high - low) - 1)) * draw))
        return values

    def distance_mm(self, name: str) -> float:
        """One IR range in mm (see ``distances_mm``)."""
        i = _named_in(self._distance_index, name, "distance sensor")
        return self.distances_mm(slice(i, i + 1))[0]

    def touches(self) -> np.ndarray:
        """Whether each of ``ers7.TOUCH_SENSORS`` is pressed beyond its threshold."""
        return self.data.sensordata[self._touch_adr] > self._touch_threshold

    def touched(self, name: str, threshold: float) -> bool:
        """Whether the touch sensor ``name`` reads more than ``threshold``."""
        return float(self.sensor(name)[0]) > threshold

    def acceleration(self) -> np.ndarray:
        """Body-frame proper acceleration (x forward, y left, z up), m/s^2, within +-2 g."""
        return np.minimum(
            np.maximum(self.sensor("accelerometer"), -ACCEL_RANGE), ACCEL_RANGE
        )  # np.clip's overhead is 5x

    def body_pose(self) -> tuple[np.ndarray, float, float]:
        """Body position, yaw (rad) and the angle between the body's up axis and vertical."""
        xmat = self.data.xmat[self._body].reshape(3, 3)
        yaw = math.atan2(xmat[1, 0], xmat[0, 0])
        tilt = math.acos(max(-1.0, min(1.0, xmat[2, 2])))
        return self.data.xpos[self._body].copy(), yaw, tilt

    def fallen(self) -> bool:
        """Whether the body is tilted more than 60 degrees from upright."""
        return self.body_pose()[2] > math.radians(60)

    # ---------------------------------------------------------------- LEDs

    def set_led(self, name: str, level: float, face_b: bool = False) -> None:
        """Light an LED at ``level`` in 0..1 of its colour (0: off); ``face_b``: a face light on its
        B face. Lights that share a spot (A9 and A13) add up there (Model Information 3.1.1). With
        a command latency, it lights ``command_latency_frames`` frames later, as a set-point acts
        (OPEN-R's LEDs travel in the joints' command vectors). A ValueError for a ``level`` that is
        no finite number (it would colour the geom NaN); it is clipped to 0..1."""
        _named_in(LED_BY_NAME, name, "LED")
        if isinstance(level, bool) or not isinstance(level, numbers.Real) or not math.isfinite(level):
            raise ValueError(f"set_led({name!r}): level must be a finite number in 0..1, not {level!r}")
        level = min(max(float(level), 0.0), 1.0)
        if self.command_latency_frames:
            self._queued_leds.append((self.frame + self.command_latency_frames, name, level, face_b))
        else:
            self._light(name, level, face_b)

    def _light_queued(self) -> None:
        """The LED commands due by the frame about to be simulated."""
        while self._queued_leds and self._queued_leds[0][0] <= self.frame:
            self._light(*self._queued_leds.popleft()[1:])

    def _light(self, name: str, level: float, face_b: bool) -> None:
        led = LED_BY_NAME[name]
        self._lit[name] = (level, face_b)
        for geom in led.all_geoms:
            rgb = list(LED_OFF_RGBA[:3])
            for other in LEDS_BY_GEOM[geom]:
                other_level, other_b = self._lit.get(other.name, (0.0, False))
                if other_level and geom in other.lit_geoms(other_b):
                    for k, (lit, off) in enumerate(zip(other.lit_colour(other_b), LED_OFF_RGBA)):
                        rgb[k] += other_level * (lit - off)
            self.model.geom_rgba[self._led_geoms[geom], :3] = [min(value, 1.0) for value in rgb]

    def close(self) -> None:
        """Free the world's renderers (every robot's camera)."""
        self.world.close()
