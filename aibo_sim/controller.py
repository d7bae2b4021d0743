"""The 2005-08 Webots C API for Aibo controllers, under its own names, for Python.

A controller does ``from aibo_sim.controller import *`` and is run by ``aibo-sim run``
(or by the OPEN-R wrapper on the robot): one robot per controller process, as in Webots.
Device tags are small positive integers (0 is never a valid tag). Units: radians, rad/s,
rad/s^2, N m, millimetres for distance sensors, m/s^2 for the accelerometer.

Choices where the Webots 5 API is unconfirmed (spec section F): numeric results are Python
floats; ``camera_get_image`` returns the RGB bytes (3 per pixel, row-major from the top
left) that the OPEN-R wrapper's ``camera_get_image`` fills, on both backends; ``led_set``
takes 0 (off), 1 (on) or a Sony intensity 2..255; ``robot_step`` returns 0, and both it and
``robot_run`` end the controller with ``SimulationEnd`` when the run's duration is over.

Extension (not in Webots): ``camera_set_white_balance``, ``camera_set_gain`` and
``camera_set_shutter_speed`` (camera tag, Sony's value 1..3: the ``CAMERA_WB_*``,
``CAMERA_GAIN_*``, ``CAMERA_SHUTTER_*`` constants, equal to OPEN-R's ``ocamparam*``, also
exported) change the camera's settings from its next frame on; the picture already taken
keeps its settings. On the ``openr`` backend they go through the wrapper's
``OPENR::ControlPrimitive`` with ``oprmreqCAM_SET_*``, as on the robot; on ``sim`` they set
the simulated camera directly. They need no ``camera_enable``. Another value raises
``DeviceError`` naming the function and the allowed values.
"""

from __future__ import annotations

import sys
import threading
import time

import numpy as np

from openr_bridge.errors import ImageAccessError
from openr_bridge.ers7_camera import (
    ocamparamGAIN_HIGH,
    ocamparamGAIN_LOW,
    ocamparamGAIN_MID,
    ocamparamSHUTTER_FAST,
    ocamparamSHUTTER_MID,
    ocamparamSHUTTER_SLOW,
    ocamparamWB_FL_MODE,
    ocamparamWB_INDOOR_MODE,
    ocamparamWB_OUTDOOR_MODE,
)
from openr_bridge.wrapper import camera_image_get_blue, camera_image_get_green, camera_image_get_red

from .mtn import Motion, MtnError, format_motion_info, motion_info
from .robot import (
    Accelerometer,
    Camera,
    Device,
    DeviceError,
    DistanceSensor,
    Led,
    Robot,
    Servo,
    SimulationEnd,
    TouchSensor,
    sampling_period,
    short_repr,
    whole_ms,
)
from .sim import FRAME_MS


class _Installed:
    """What the API functions drive: the robot, the thread that runs its controller (the camera
    renders there), the device tags handed out, the reset and exit functions registered, and
    when the controller last called the API (``time.monotonic()``: the runner's wait notices)."""

    def __init__(self, robot: Robot | None):
        self.robot, self.thread = robot, threading.current_thread()
        self.tags: list[Device] = []
        self.reset_fn = None
        self.die_fns: list = []
        self.last_call_s = time.monotonic()


_installed = _Installed(None)  # the run's controller
_match: dict[int, _Installed] = {}  # in a match, each robot's, by the thread running its controller


def install(robot: Robot | None, match: bool = False) -> None:
    """Make ``robot`` the one the API functions drive, from this thread (the runner calls this).
    ``match=True``: one of several robots, each controller in its own thread; its API calls
    must come from that thread (another gets the robot ``install`` gave it without ``match``)."""
    global _installed
    if not match:
        _installed = _Installed(robot)
    elif robot is not None:
        _match[threading.get_ident()] = _Installed(robot)
    else:
        _match.pop(threading.get_ident(), None)


def installed() -> _Installed:
    """What ``install`` gave this thread (the runner reads its ``last_call_s`` from another)."""
    return _match.get(threading.get_ident(), _installed) if _match else _installed


def current_robot() -> Robot:
    """The robot the API functions drive in this thread.

    :raises RuntimeError: no robot installed (the controller was not started by ``aibo-sim run``).
    """
    state = installed()
    robot = state.robot
    if robot is None:
        if _match:
            raise RuntimeError(
                f"no robot in thread {threading.current_thread().name!r}: in a match, a controller's API calls "
                "must come from the thread that runs it"
            )
        raise RuntimeError("no robot: run the controller with `aibo-sim run CONTROLLER`")
    state.last_call_s = time.monotonic()
    return robot


def _rendering(function: str) -> Robot:
    """The robot, for a call that may render the camera: DeviceError from any thread but the
    controller's (an OpenGL context is current in one thread; another's call would break it)."""
    robot, thread, own = current_robot(), threading.current_thread(), installed().thread
    if thread is not own:
        raise DeviceError(
            f"{function} called from thread {thread.name!r}: the camera renders in the thread that "
            f"runs the controller ({own.name!r}) only; call {function} there"
        )
    return robot


def _device(tag, kind: type) -> Device:
    state = installed()
    state.last_call_s = time.monotonic()
    tags = state.tags
    if isinstance(tag, bool) or not isinstance(tag, (int, np.integer)) or not 0 < tag <= len(tags):
        raise DeviceError(f"invalid device tag {tag!r}: use the value robot_get_device returned")
    device = tags[tag - 1]
    if not isinstance(device, kind):
        raise DeviceError(f"device {device.locator} is a {device.kind}, not a {kind.kind}")
    return device


# ------------------------------------------------------------------------- robot


def robot_live(reset_fn=None) -> None:
    """Register the reset (initialisation) function and call it once."""
    if reset_fn is not None and not callable(reset_fn):
        raise TypeError(f"robot_live({short_repr(reset_fn)}): the reset function must be callable (or None)")
    current_robot()
    installed().reset_fn = reset_fn
    if reset_fn is not None:
        reset_fn()


def robot_die(exit_fn) -> None:
    """Register a function called when the controller quits (after its run ends, it raised,
    it called ``sys.exit`` or it was interrupted)."""
    if not callable(exit_fn):
        raise TypeError(f"robot_die({short_repr(exit_fn)}): the exit function must be callable")
    installed().die_fns.append(exit_fn)


def call_die_functions() -> list[tuple[object, BaseException]]:
    """Call each registered exit function once, in order, even when an earlier one raised;
    returns ``(function, exception)`` for those that raised (the runner reports them beside the
    controller's own exception rather than instead of it). ``SimulationEnd`` (an exit function
    that steps past the run's end) and ``sys.exit(0)`` are not errors; KeyboardInterrupt
    propagates."""
    state = installed()
    functions, failures = list(state.die_fns), []
    state.die_fns.clear()
    for fn in functions:
        try:
            fn()
        except SimulationEnd:
            pass
        except SystemExit as exc:
            if exc.code not in (None, 0):
                failures.append((fn, exc))
        except Exception as exc:
            failures.append((fn, exc))
    return failures


def robot_run(run_fn) -> None:
    """Call ``run_fn(ms)`` until the run ends: ``ms`` is the step just simulated (0 on the
    first call, before any sample), the return value the duration of the next step."""
    if not callable(run_fn):
        raise TypeError(f"robot_run({short_repr(run_fn)}): the run function must be callable")
    ms = 0
    while True:
        returned = run_fn(ms)
        ms = whole_ms(returned)
        if ms is None or ms <= 0:
            raise ValueError(f"run function returned {returned!r}: it must return the next step in ms (e.g. TIME_STEP)")
        _rendering("robot_run").step(ms)


def robot_step(ms: int) -> int:
    """Advance ``ms`` of simulated time (a positive multiple of 8 ms); returns 0.

    :raises SimulationEnd: the run's duration is over.
    :raises ValueError: ``ms`` is not a positive multiple of 8.
    :raises DeviceError: called from another thread than the controller's.
    """
    _rendering("robot_step").step(ms)
    return 0


def robot_get_device(name: str) -> int:
    """The tag (1, 2, ...) of the device with OPEN-R locator ``name``; the same device always gets
    the same tag.

    :raises DeviceError: no such device; the message names the nearest locators.
    """
    device, tags = current_robot().get_device(name), installed().tags
    if device not in tags:
        tags.append(device)
    return tags.index(device) + 1


def robot_get_time() -> float:
    """Simulated time in seconds."""
    return current_robot().time_ms / 1000.0


def robot_get_name() -> str:
    """The robot's name: ``"ERS-7"``; in a match its team and number, ``"red 2"`` (so that one
    controller run by several robots knows which it drives)."""
    spec = current_robot().sim.spec
    return "ERS-7" if spec.team is None else spec.name


def robot_get_mode() -> int:
    """Where the controller runs, as Webots 5 numbers it: 0 in the simulator (``aibo-sim run``, on
    either backend); 1, cross-compiled on the robot, is what a memory stick's build (``build-ms``)
    answers, on the robot and on aibo-sim's OPEN-R runtime alike."""
    current_robot()
    return 0


def robot_get_basic_time_step() -> float:
    """The simulation's step in ms, of which every ``robot_step`` is a whole number: the 8 ms joint frame."""
    current_robot()
    return float(FRAME_MS)


def robot_get_synchronization() -> int:
    """1: the simulation waits for the controller at every step (Webots' synchronized mode); a
    memory stick's build answers 0, as the robot, whose time goes on, does."""
    current_robot()
    return 1


# Webots' keyboard codes, for controllers that test keys: a key's code, SHIFT, CONTROL and ALT or'ed
# in. Names: Webots 5's (ROBOT_KEYBOARD_*, as Webots 6's WB_ROBOT_KEYBOARD_* without wb_); values:
# Webots' reference for its later WB_KEYBOARD_* (Webots 5's header is not at hand: UNCONFIRMED).
# No key is ever pressed here: robot_keyboard_get_key is 0. include/device/robot.h has them too
# (python -m aibo_sim.cbind.headers).
KEYBOARD_KEYS = {
    "END": 312,
    "HOME": 313,
    "LEFT": 314,
    "UP": 315,
    "RIGHT": 316,
    "DOWN": 317,
    "PAGEUP": 366,
    "PAGEDOWN": 367,
    "NUMPAD_HOME": 375,
    "NUMPAD_LEFT": 376,
    "NUMPAD_UP": 377,
    "NUMPAD_RIGHT": 378,
    "NUMPAD_DOWN": 379,
    "NUMPAD_END": 382,
    "KEY": 0xFFFF,
    "SHIFT": 0x10000,
    "CONTROL": 0x20000,
    "ALT": 0x40000,
}
globals().update({f"ROBOT_KEYBOARD_{name}": value for name, value in KEYBOARD_KEYS.items()})


def robot_keyboard_enable(ms: int) -> None:
    """Read the keyboard every ``ms``; runs are headless, so no key is ever pressed.

    :raises DeviceError: ``ms`` is not a positive whole number.
    """
    sampling_period(ms, "robot_keyboard_enable")
    current_robot()


def robot_keyboard_disable() -> None:
    """Stop reading the keyboard."""
    current_robot()


def robot_keyboard_get_key() -> int:
    """The key pressed: always 0 (none), as runs are headless."""
    current_robot()
    return 0


def robot_console_printf(fmt: str, *args) -> None:
    """Write ``fmt % args`` to stdout, as C's printf (``%%`` is ``%`` without ``args`` too), and
    flush it; a format its ``args`` do not fill, or one that is not a str, is a TypeError naming it."""
    if not isinstance(fmt, str):  # b"..." % () is bytes, which stdout refuses
        raise TypeError(f"robot_console_printf({short_repr(fmt)}): the format must be a str")
    try:
        text = fmt % args
    except (TypeError, ValueError) as exc:
        raise TypeError(f"robot_console_printf({short_repr(fmt)}): {exc}") from None
    sys.stdout.write(text)
    sys.stdout.flush()


# ------------------------------------------------------------------------- servo


def servo_enable_position(tag, ms: int) -> None:
    """Sample the servo's position every ``ms`` milliseconds."""
    _device(tag, Servo).enable(ms)


def servo_disable_position(tag) -> None:
    """Stop sampling the servo's position."""
    _device(tag, Servo).disable()


def servo_get_position(tag) -> float:
    """The joint angle in radians at the last sample.

    :raises DeviceError: not enabled, or before its first sample.
    """
    return _device(tag, Servo).get_position()


def servo_enable_motor_force_feedback(tag, ms: int) -> None:
    """Sample the torque the servo's motor applies every ``ms`` milliseconds."""
    _device(tag, Servo).force_feedback.enable(ms)


def servo_disable_motor_force_feedback(tag) -> None:
    """Stop sampling the servo's motor torque."""
    _device(tag, Servo).force_feedback.disable()


def servo_get_motor_force_feedback(tag) -> float:
    """The torque in N m the servo's motor applied at the last sample (signed along the joint).

    :raises DeviceError: not enabled, or before its first sample.
    """
    return _device(tag, Servo).force_feedback.value()


def servo_set_position(tag, radians: float) -> None:
    """Target angle in radians, clipped to the joint's range."""
    _device(tag, Servo).set_position(radians)


def servo_set_velocity(tag, rad_per_s: float) -> None:
    """Speed limit in rad/s (its absolute value); never above Sony's maximum for the joint."""
    _device(tag, Servo).set_velocity(rad_per_s)


def servo_set_acceleration(tag, rad_per_s2: float) -> None:
    """Acceleration limit in rad/s^2, above 0; -1 (Webots') means unlimited."""
    _device(tag, Servo).set_acceleration(rad_per_s2)


def servo_set_motor_force(tag, newton_metres: float) -> None:
    """Torque limit in N m (its absolute value)."""
    _device(tag, Servo).set_motor_force(newton_metres)


def servo_set_control_p(tag, p: float) -> None:
    """Proportional gain of the servo's position control."""
    _device(tag, Servo).set_control_p(p)


# ------------------------------------------------------------------------- camera


def camera_enable(tag, ms: int) -> None:
    """Take a picture every ``ms`` milliseconds (at most 30 a second)."""
    _device(tag, Camera).enable(ms)


def camera_disable(tag) -> None:
    """Stop taking pictures."""
    _device(tag, Camera).disable()


def camera_get_image(tag) -> np.ndarray:
    """The last picture: row-major RGB from the top left, 3 bytes a pixel, a flat uint8 array.

    :raises DeviceError: not enabled, before its first picture, or called from another thread than
        the controller's.
    """
    _rendering("camera_get_image")
    return _device(tag, Camera).get_image()


def camera_save_image(tag, filename: str, quality: int, *, folder: str | None = None) -> int:
    """Write the last picture to ``filename``: PNG, or JPEG of ``quality`` 1-100 (.jpg, .jpeg).
    A relative name is in ``folder`` (default the working folder; the C binding's controller's own).

    :returns: 0 when written, -1 when it cannot be (the reason on stderr), as in Webots.
    :raises DeviceError: a name that is not a string; not enabled, before its first picture.
    """
    _rendering("camera_save_image")
    return _device(tag, Camera).save_image(filename, quality, folder)


def camera_get_width(tag) -> int:
    """Image width in pixels."""
    return _device(tag, Camera).width


def camera_get_height(tag) -> int:
    """Image height in pixels."""
    return _device(tag, Camera).height


def camera_get_fov(tag) -> float:
    """Horizontal field of view in radians."""
    return _device(tag, Camera).fov


# Sony's camera settings values (OPrimitiveControl.h's ocamparam*), by Webots-style names.
CAMERA_WB_INDOOR, CAMERA_WB_OUTDOOR, CAMERA_WB_FL = (
    ocamparamWB_INDOOR_MODE,
    ocamparamWB_OUTDOOR_MODE,
    ocamparamWB_FL_MODE,
)
CAMERA_GAIN_LOW, CAMERA_GAIN_MID, CAMERA_GAIN_HIGH = ocamparamGAIN_LOW, ocamparamGAIN_MID, ocamparamGAIN_HIGH
CAMERA_SHUTTER_SLOW, CAMERA_SHUTTER_MID, CAMERA_SHUTTER_FAST = (
    ocamparamSHUTTER_SLOW,
    ocamparamSHUTTER_MID,
    ocamparamSHUTTER_FAST,
)


def camera_set_white_balance(tag, value: int) -> None:
    """CAMERA_WB_INDOOR (1), CAMERA_WB_OUTDOOR (2) or CAMERA_WB_FL (3, the default), from the next
    camera frame; the presets' colour temperatures: ``aibo_sim.camera.sensor.WHITE_BALANCE_K``."""
    _device(tag, Camera).set_white_balance(value)


def camera_set_gain(tag, value: int) -> None:
    """CAMERA_GAIN_LOW (1), CAMERA_GAIN_MID (2, the default) or CAMERA_GAIN_HIGH (3), from the
    next camera frame; each step doubles the signal (``aibo_sim.camera.sensor.GAIN_STEPS``)."""
    _device(tag, Camera).set_gain(value)


def camera_set_shutter_speed(tag, value: int) -> None:
    """CAMERA_SHUTTER_SLOW (1), CAMERA_SHUTTER_MID (2, the default) or CAMERA_SHUTTER_FAST (3),
    from the next camera frame; the exposures: ``aibo_sim.camera.sensor.SHUTTER_S``."""
    _device(tag, Camera).set_shutter_speed(value)


def camera_image_get_grey(image, width: int, x: int, y: int) -> int:
    """Mean of the three channels, as Webots' camera_image_get_grey."""
    red, green = camera_image_get_red(image, width, x, y), camera_image_get_green(image, width, x, y)
    return (red + green + camera_image_get_blue(image, width, x, y)) // 3


camera_image_get_gray = camera_image_get_grey  # the later Webots spelling


# ------------------------------------------------------------------------- sensors, LEDs


def distance_sensor_enable(tag, ms: int) -> None:
    """Sample the IR distance sensor every ``ms`` milliseconds."""
    _device(tag, DistanceSensor).enable(ms)


def distance_sensor_disable(tag) -> None:
    """Stop sampling the distance sensor."""
    _device(tag, DistanceSensor).disable()


def distance_sensor_get_value(tag) -> float:
    """The range in millimetres at the last sample; DeviceError before one."""
    return _device(tag, DistanceSensor).value()


def touch_sensor_enable(tag, ms: int) -> None:
    """Sample the touch sensor every ``ms`` milliseconds."""
    _device(tag, TouchSensor).enable(ms)


def touch_sensor_disable(tag) -> None:
    """Stop sampling the touch sensor."""
    _device(tag, TouchSensor).disable()


def touch_sensor_get_value(tag) -> float:
    """1.0 when pressed at the last sample, else 0.0; DeviceError before one."""
    return _device(tag, TouchSensor).value()


def accelerometer_enable(tag, ms: int) -> None:
    """Sample the accelerometer every ``ms`` milliseconds."""
    _device(tag, Accelerometer).enable(ms)


def accelerometer_disable(tag) -> None:
    """Stop sampling the accelerometer."""
    _device(tag, Accelerometer).disable()


def accelerometer_get_values(tag) -> tuple[float, float, float]:
    """(x, y, z) in m/s^2 at the last sample (x forward, y left, z up); DeviceError before one."""
    return _device(tag, Accelerometer).value()


def accelerometer_value_x(values) -> float:
    """The x (forward) component of ``accelerometer_get_values``' result."""
    return values[0]


def accelerometer_value_y(values) -> float:
    """The y (left) component of ``accelerometer_get_values``' result."""
    return values[1]


def accelerometer_value_z(values) -> float:
    """The z (up) component of ``accelerometer_get_values``' result."""
    return values[2]


def led_set(tag, value: int) -> None:
    """0 switches the LED off, 1 on at full intensity, 2..255 a Sony intensity (value / 255)."""
    _device(tag, Led).set(value)


# ------------------------------------------------------------------------- MTN
#
# An MTN argument is what mtn_new returned: None (a failed mtn_new) raises MtnError quoting
# mtn_get_error(), anything else that is not a motion raises MtnError naming the function and
# the argument, and a motion that mtn_delete deleted raises MtnError saying so. mtn_new itself
# returns None on any failure, a file name that is not a str or path included, with the reason
# in mtn_get_error() (names cut to 200 characters, control characters escaped). mtn_play on a
# motion that is playing restarts it from its start.


def mtn_new(filename: str):
    """Load a motion file; returns None and sets ``mtn_get_error()`` on failure, as Webots."""
    try:
        return current_robot().mtn_new(filename)
    except MtnError:
        return None


def mtn_get_error() -> str:
    """The text of this robot's last ``mtn_new`` error ("" before any, as Webots')."""
    return current_robot().mtn_error


def mtn_delete(motion) -> None:
    """Stop ``motion`` and delete it: a call on it after that raises MtnError (in Webots' C API
    it would read freed memory); ``mtn_delete(None)`` does nothing, as in Webots."""
    if motion is not None:
        current_robot().mtn_delete(motion)


def mtn_play(motion) -> None:
    """Play ``motion`` from its start (again from its start if it is playing)."""
    current_robot().mtn_play(_motion(motion, "mtn_play"))


def mtn_is_over(motion) -> bool:
    """Whether ``motion`` is not playing (never started, or ended)."""
    return current_robot().mtn_is_over(_motion(motion, "mtn_is_over"))


def mtn_get_length(motion) -> int:
    """The motion's length in ms (its last keyframe lasts 0 ms)."""
    return int(_motion(motion, "mtn_get_length").length_ms)


def mtn_get_time(motion) -> int:
    """Milliseconds ``motion`` has played (0 when it is not playing)."""
    return current_robot().mtn_get_time(_motion(motion, "mtn_get_time"))


def mtn_fprint(file, motion) -> None:
    """A debug dump of a motion (aibo-sim's layout, not Webots'): name, creator, design, frame
    time, keyframes, length, locators (control characters in them escaped); a TypeError for a
    ``file`` that cannot be written (C's FILE *: ``sys.stdout``, or a file opened for writing)."""
    text = format_motion_info(motion_info(_motion(motion, "mtn_fprint"))) + "\n"
    if not callable(getattr(file, "write", None)):
        raise TypeError(f"mtn_fprint({short_repr(file)}, ...): the file must be writable (sys.stdout, an open file)")
    file.write(text)


def mtn_get_name(motion) -> str:
    """Not in Webots (spec: no such function found); the name is in the file's section 1."""
    return _motion(motion, "mtn_get_name").name


def _motion(motion, function: str = "mtn") -> Motion:
    if motion is None:
        raise MtnError(
            None, None, f"{function}: MTN is NULL: mtn_new failed (" + (mtn_get_error() or "no error recorded") + ")"
        )
    return current_robot()._motion(function, motion)  # MtnError unless a motion (not deleted)


__all__ = (
    [
        name
        for name in dir()
        if name.split("_")[0] in {"robot", "servo", "camera", "distance", "touch", "accelerometer", "led", "mtn"}
    ]
    + [name for name in dir() if name.startswith(("CAMERA_", "ROBOT_KEYBOARD_", "ocamparam"))]
    + ["SimulationEnd", "DeviceError", "MtnError", "ImageAccessError"]
)
