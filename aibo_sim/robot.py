"""The Pythonic face of the Webots-era Aibo controller API: a robot and its devices.

Devices are addressed by their OPEN-R locators. Sensors follow Webots' sampling rules:
``enable(ms)`` starts sampling, the value refreshes at every multiple of the period
after the call, reading before the first sample or after ``disable`` is an error.
The camera delivers at most 30 frames a second.

Backends differ only in where camera images come from:
- ``sim``: the rendered RGB frame, as the Webots simulator's camera gives it;
- ``openr``: each frame is encoded into an ``OFbkImageVectorData``, published by
  ``OVirtualRobotComm``, routed by a memory stick's CONNECT.CFG to the wrapper object
  ``Controller`` and read back through its ``camera_get_image``.
"""

from __future__ import annotations

import difflib
import math
import numbers
import os
import sys
import threading
import weakref
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from . import ers7
from .files import named_file, png, temporary_path, write_file_atomic
from .mtn import MODES as MTN_MODES
from .mtn import Motion, MotionPlayer, MtnError, check_joint, mtn_new, whole_ms
from .sim import FRAME_MS, Simulation

BACKENDS = ("sim", "openr")
MAX_SAMPLING_PERIOD_MS = 0xFFFF  # Webots 5 passes periods as unsigned short


class DeviceError(RuntimeError):
    """Misuse of a device: unknown name, wrong kind, not enabled, no value yet."""


class SimulationEnd(BaseException):
    """Raised inside the controller when the run's duration is over (Webots ends it too). Not an
    ``Exception``, as ``SystemExit`` is not: a controller's ``except Exception`` lets it through."""


def sampling_period(ms, what: str) -> int:
    """``ms`` as a whole number of milliseconds; DeviceError naming ``what`` (a device, a call)
    unless it is a positive whole number up to 65535 (Webots 5's periods are unsigned shorts)."""
    period = whole_ms(ms)
    if period is None or not 0 < period <= MAX_SAMPLING_PERIOD_MS:
        raise DeviceError(
            f"{what}: sampling period must be a whole number of ms from 1 to {MAX_SAMPLING_PERIOD_MS}, not {ms!r}"
        )
    return period


def finite_number(value, what: str) -> float:
    """``value`` as a float; DeviceError naming ``what`` unless it is a finite real number (a bool
    or a string is not one, as they are not in C)."""
    try:
        if not isinstance(value, bool) and isinstance(value, numbers.Real) and math.isfinite(value):
            return float(value)
    except OverflowError:  # an int beyond a float's range (10**400)
        pass
    raise DeviceError(f"{what} must be a finite number, not {short_repr(value)}")


class Device:
    """A named device with Webots' enable/sample/disable cycle."""

    kind = "device"
    enable_call = ""  # the API function that enables it, when not ``<kind>_enable``
    sampled = ""  # what it samples, where a device samples more than one thing: keys ``enabled_devices``

    def __init__(self, robot: Robot, locator: str, name: str):
        self.robot, self.locator, self.name = robot, locator, name
        self.key = f"{locator} {self.sampled}" if self.sampled else locator
        self.period: int | None = None
        self._next_sample_ms = 0
        self._value = None

    def enable(self, ms: int) -> None:
        """Sample every ``ms`` milliseconds, the first sample ``ms`` after now; drops any earlier value.

        :raises DeviceError: ``ms`` is not a positive whole number.
        """
        ms = sampling_period(ms, self.locator)
        self.period, self._value = ms, None
        self._next_sample_ms = self.robot.time_ms + ms
        self.robot.enabled_devices[self.key] = self

    def disable(self) -> None:
        """Stop sampling and forget the last value."""
        self.period, self._value = None, None
        self.robot.enabled_devices.pop(self.key, None)

    def _after_frame(self, time_ms: int) -> None:
        if self.period is not None and time_ms >= self._next_sample_ms:
            self._value = self._sample()
            while self._next_sample_ms <= time_ms:
                self._next_sample_ms += self.period

    def _sample(self):
        raise NotImplementedError

    def value(self):
        """The last sample.

        :raises DeviceError: the device is not enabled, or its first sample is not due yet.
        """
        if self.period is None:
            call = self.enable_call or f"{self.kind}_enable"
            raise DeviceError(f"{self.locator}: {self.sampled or self.kind} is not enabled (call {call} first)")
        if self._value is None:
            raise DeviceError(
                f"{self.locator}: no sample yet: enabled with a {self.period} ms period, first value at "
                f"t = {self._next_sample_ms} ms (now {self.robot.time_ms} ms)"
            )
        return self._value


class Servo(Device):
    """A joint's position servo (``ers7.JOINTS``); its position is sampled as a sensor's value."""

    kind = "servo"
    enable_call = "servo_enable_position"

    def __init__(self, robot, locator, name):
        super().__init__(robot, locator, name)
        self.index = ers7.JOINT_INDEX[name]
        self._actuator = robot.sim.servos.ctrl.start + self.index  # in the world's model: after the robots before
        self.force_feedback = MotorForceFeedback(self)

    def _number(self, value, what: str) -> float:
        return finite_number(value, f"{self.locator}: {what}")

    def set_position(self, radians: float) -> None:
        """Target angle in radians, clipped to the joint's range."""
        self.robot.sim.servos.set_target(self.index, self._number(radians, "position"))

    def set_velocity(self, rad_per_s: float) -> None:
        """Speed limit; never above Sony's maximum for the joint."""
        self.robot.sim.servos.velocity[self.index] = abs(self._number(rad_per_s, "velocity"))

    def set_acceleration(self, rad_per_s2: float) -> None:
        """Acceleration limit above 0; -1 means unlimited (Webots' range: -1 or (0, inf))."""
        value = self._number(rad_per_s2, "acceleration")
        if value != -1 and value <= 0:
            raise DeviceError(f"{self.locator}: acceleration must be -1 (unlimited) or above 0, not {value:g}")
        self.robot.sim.servos.acceleration[self.index] = math.inf if value == -1 else value

    def set_motor_force(self, newton_metres: float) -> None:
        """Torque limit in N m (the absolute value of ``newton_metres``) of the joint's actuator,
        never above Webots' ``maxForce`` (``ers7.MAX_TORQUE``), its default."""
        force = min(abs(self._number(newton_metres, "motor force")), ers7.MAX_TORQUE)
        self.robot.sim.model.actuator_forcerange[self._actuator] = (-force, force)

    def set_control_p(self, p: float) -> None:
        """Proportional gain (above 0) of the joint's position actuator."""
        p = self._number(p, "control P")
        if p <= 0:
            raise DeviceError(f"{self.locator}: control P must be above 0, not {p:g}")
        model = self.robot.sim.model
        model.actuator_gainprm[self._actuator, 0] = p
        model.actuator_biasprm[self._actuator, 1] = -p

    def _sample(self) -> float:
        return float(self.robot.sim.joint_positions()[self.index])

    def get_position(self) -> float:
        """The joint angle in radians at the last sample (``value``)."""
        return self.value()


class MotorForceFeedback(Device):
    """A servo's motor force feedback (Webots 5's ``servo_enable_motor_force_feedback``): the
    torque in N m its actuator applies along the joint, sampled on a period of its own."""

    kind = "servo"
    enable_call = "servo_enable_motor_force_feedback"
    sampled = "motor force feedback"

    def __init__(self, servo: Servo):
        super().__init__(servo.robot, servo.locator, servo.name)
        self._actuator = servo._actuator

    def enable(self, ms: int) -> None:
        """As ``Device.enable``; DeviceError for an ear (Joint4): the robot reports no PWM duty for it."""
        if ers7.JOINTS[ers7.JOINT_INDEX[self.name]].is_ear:
            raise DeviceError(f"{self.locator}: an ear (Joint4) has no motor force feedback: the robot reports no duty")
        super().enable(ms)

    def _sample(self) -> float:
        return float(self.robot.sim.data.actuator_force[self._actuator])


class DistanceSensor(Device):
    """An IR distance sensor: range in millimetres (``Simulation.distance_mm``)."""

    kind = "distance_sensor"

    def _sample(self) -> float:
        return self.robot.sim.distance_mm(self.name)


class TouchSensor(Device):
    """A touch sensor: 1.0 when pressed beyond its threshold, else 0.0."""

    kind = "touch_sensor"

    def _sample(self) -> float:
        sensor = ers7.SENSOR_BY_NAME[self.name]
        return 1.0 if self.robot.sim.touched(self.name, sensor.threshold) else 0.0


class Accelerometer(Device):
    """The body's accelerometer: (x, y, z) in m/s^2 (``Simulation.acceleration``)."""

    kind = "accelerometer"

    def _sample(self) -> tuple[float, float, float]:
        return tuple(float(v) for v in self.robot.sim.acceleration())


class Camera(Device):
    """The head camera: each sample is the newest 30 fps frame, row-major RGB from the backend."""

    kind = "camera"

    def _after_frame(self, time_ms: int) -> None:
        # A sample takes a new picture only when the 30 fps camera has a newer one.
        if self._value is not None and self.robot.sim.camera_frame_index() == self._frame_index:
            while self.period is not None and self._next_sample_ms <= time_ms:
                self._next_sample_ms += self.period
            return
        super()._after_frame(time_ms)

    def _sample(self) -> np.ndarray:
        self._frame_index = self.robot.sim.camera_frame_index()
        return self.robot.camera_source.capture()

    def get_image(self) -> np.ndarray:
        """Row-major RGB, 3 bytes a pixel (what the OPEN-R wrapper's camera_get_image fills)."""
        return self.value()

    def save_image(self, filename, quality, folder: str | None = None) -> int:
        """Webots' camera_save_image: the last picture into ``filename`` (relative to ``folder``,
        default the working folder), a PNG, or a JPEG of ``quality`` 1-100 when it ends in .jpg or .jpeg (any case;
        ``quality`` is ignored for a PNG), written whole or not at all (a link at ``filename`` is
        replaced, not followed; a relative name whose folders hold a link is refused). 0 when
        written; -1, the reason on stderr, when it cannot be (another ending, a JPEG quality out of
        range, the file system's refusal), as Webots answers.

        :raises DeviceError: a file name that is not a string; not enabled, or no picture yet.
        """
        call = f"{self.locator}: camera_save_image({filename!r}, {quality!r})"
        name = os.fspath(filename) if isinstance(filename, (str, os.PathLike)) else None
        if not isinstance(name, str):
            raise DeviceError(f"{call}: the file name must be a string")
        bgr = self.get_image().reshape(self.height, self.width, 3)[:, :, ::-1]
        ending = name.rsplit("/", 1)[-1].lower()
        whole = not isinstance(quality, bool) and isinstance(quality, numbers.Integral)
        problem = data = None
        if not name or "\0" in name or not _encodable(name):
            problem = "not a file name"
        elif ending.endswith(".png"):
            data = png(bgr)
        elif not ending.endswith((".jpg", ".jpeg")):
            problem = "the file name must end in .png, .jpg or .jpeg"
        elif not (whole and 1 <= quality <= 100):
            problem = "a JPEG's quality must be a whole number 1-100"
        else:
            whole_colour = [cv2.IMWRITE_JPEG_SAMPLING_FACTOR, cv2.IMWRITE_JPEG_SAMPLING_FACTOR_444]  # as a stick's
            data = cv2.imencode(".jpg", bgr, [cv2.IMWRITE_JPEG_QUALITY, int(quality), *whole_colour])[1].tobytes()
        if data is not None:
            try:
                # a relative name's folders are reached from the working folder without following a
                # link (one planted under --out); an absolute name's are the controller's choice
                path = named_file(name) if os.path.isabs(name) else Path(folder or os.getcwd()) / name
                # a temporary name of this thread's own: a match's controllers may save one name at once
                write_file_atomic(
                    path, data, temporary_path(path.with_name(f"{path.name}.{threading.get_native_id()}"))
                )
                return 0
            except OSError as error:  # write_file_atomic's say "cannot write PATH: why"; a loop of links not
                problem = str(error) if error.strerror is None else f"cannot write {name}: {error.strerror}"
        sys.stderr.write(f"aibo-sim: {call}: {problem}\n")  # one write: the lines of two robots stay whole
        return -1

    @property
    def width(self) -> int:
        """Image width in pixels."""
        return self.robot.camera_source.width

    @property
    def height(self) -> int:
        """Image height in pixels."""
        return self.robot.camera_source.height

    @property
    def fov(self) -> float:
        """Horizontal field of view in radians."""
        return self.robot.camera_source.fov

    # Settings (an extension of the Webots API): Sony's values 1..3, from the next camera frame.

    def set_white_balance(self, value: int) -> None:
        """1 indoor, 2 outdoor, 3 fluorescent (the default): ``camera.sensor.WHITE_BALANCE_K``'s presets."""
        self._set_setting("camera_set_white_balance", "white_balance", value)

    def set_gain(self, value: int) -> None:
        """1 low, 2 mid (the default), 3 high: ``camera.sensor.GAIN_STEPS``."""
        self._set_setting("camera_set_gain", "gain", value)

    def set_shutter_speed(self, value: int) -> None:
        """1 slow, 2 mid (the default), 3 fast: ``camera.sensor.SHUTTER_S``."""
        self._set_setting("camera_set_shutter_speed", "shutter", value)

    @property
    def settings(self):
        """The settings the next frame is exposed with (``aibo_sim.camera.CameraSettings``)."""
        return self.robot.sim.camera.settings

    def _set_setting(self, function: str, setting: str, value) -> None:
        # sim: straight to sim.camera; openr: the wrapper's OPENR::ControlPrimitive.
        try:
            self.robot.camera_source.set_setting(setting, value)
        except ValueError as error:
            raise DeviceError(f"{self.locator}: {function}({value!r}): {error}") from error


def _encodable(name: str) -> bool:
    """Whether ``name`` is bytes the file system can take (not a lone surrogate such as '\\ud800')."""
    try:
        os.fsencode(name)
        return True
    except UnicodeEncodeError:
        return False


class Led(Device):
    """LED: 0 switches it off, 1 on at full intensity, 2..255 Sony intensities (value/255)."""

    kind = "led"

    def set(self, value: int) -> None:
        """0 (or less) off, 1 full intensity, 2..255 that intensity out of 255 (above 255: 255)."""
        value = int(finite_number(value, f"{self.locator}: led value"))
        level = 0.0 if value <= 0 else 1.0 if value == 1 else min(value, 255) / 255
        self.robot.sim.set_led(self.name, level)


_DEVICE_CLASSES = {"distance": DistanceSensor, "touch": TouchSensor, "accelerometer": Accelerometer, "camera": Camera}


def short_repr(value, limit: int = 60) -> str:
    """``repr(value)``, cut after ``limit`` characters (saying how long it was)."""
    text = repr(value)
    return text if len(text) <= limit else f"{text[:limit]}... ({len(text)} characters)"


def _is_file(path: Path) -> bool:
    try:
        return path.is_file()
    except OSError:  # a name too long for the file system, ...: not a file here
        return False


def find_file(path: str | Path, search_dirs) -> Path:
    """``path`` itself if it is absolute; else the name (of a memory stick's ``/MS/OPEN-R/...``, the
    last part) in the first of ``search_dirs`` (a relative one: the working folder at the call)
    that has it, ignoring case as OPEN-R's memory stick does when the folder lacks the exact name;
    ``path`` unchanged when none has it."""
    path = Path(path)
    on_stick = str(path)[:4].upper() == "/MS/" and not _is_file(path)
    if path.is_absolute() and not on_stick:
        return path
    name = Path(path.name) if on_stick else path
    for folder in map(Path, search_dirs):
        if _is_file(folder / name):
            return folder / name
        try:
            files = sorted((folder / name.parent).iterdir())
        except OSError:  # no such folder, a name too long, ...
            continue
        match = next((f for f in files if f.name.lower() == name.name.lower() and _is_file(f)), None)
        if match is not None:
            return match
    return path


def check_memory_stick(backend: str, memory_stick) -> None:
    """ValueError for a memory stick given to a backend that reads none."""
    if memory_stick is not None and backend != "openr":
        raise ValueError(
            f"--memory-stick applies to the openr backend (--backend openr): the {backend} backend "
            "reads no OPEN-R configuration"
        )


def deleted_motion_error(function: str) -> MtnError:
    """The error of a call on a motion that ``mtn_delete`` deleted (Python's or C's)."""
    return MtnError(None, None, f"{function}: this MTN was deleted by mtn_delete (mtn_new makes a new one)")


class Robot:
    """A simulated ERS-7 seen through the controller API, on one backend."""

    def __init__(
        self,
        sim: Simulation | None = None,
        *,
        backend: str = "sim",
        mtn_mode: str = "openr",
        memory_stick: str | Path | None = None,
        search_dirs: tuple[Path, ...] = (),
    ):
        if backend not in BACKENDS:
            raise ValueError(f"backend must be one of {BACKENDS}, not {backend!r}")
        if mtn_mode not in MTN_MODES:
            raise ValueError(f"mtn_mode must be one of {MTN_MODES}, not {mtn_mode!r}")
        check_memory_stick(backend, memory_stick)
        self.sim = sim or Simulation()
        self.backend, self.mtn_mode = backend, mtn_mode
        self.search_dirs = tuple(search_dirs)
        from .camera.backends import OpenRCamera, SimCamera

        self.camera_source = OpenRCamera(self.sim, memory_stick) if backend == "openr" else SimCamera(self.sim)
        self.devices: dict[str, Device] = {}
        for j in ers7.JOINTS:
            self.devices[j.locator] = Servo(self, j.locator, j.name)
        for s in ers7.SENSORS:
            self.devices[s.locator] = _DEVICE_CLASSES[s.kind](self, s.locator, s.name)
        for alias in ers7.ACCELEROMETER_ALIASES:
            self.devices[alias] = self.devices[ers7.SENSOR_BY_NAME["accelerometer"].locator]
        for led in ers7.LEDS:
            self.devices[led.locator] = Led(self, led.locator, led.name)
        self.playing: list[_Playing] = []
        self.deleted_motions: weakref.WeakValueDictionary[int, Motion] = weakref.WeakValueDictionary()  # by id()
        self.mtn_error = ""  # the last mtn_new error, mtn_get_error's: each robot's own, as each Webots controller's
        self.enabled_devices: dict[str, Device] = {}  # sampled after every frame, in enabling order
        self.end_ms: int | None = None
        self.frame_listeners = []  # called with (robot) after every 8 ms frame

    @property
    def time_ms(self) -> int:
        """Simulated time in ms since reset."""
        return self.sim.time_ms

    def get_device(self, name: str) -> Device:
        """The device with OPEN-R locator ``name`` (the accelerometer also by its aliases).

        :raises DeviceError: no such device; the message names the nearest locators.
        """
        try:
            return self.devices[name]
        except (KeyError, TypeError):
            near = difflib.get_close_matches(str(name), list(self.devices), n=3, cutoff=0.5)
            example = next(iter(self.devices))
            hint = f"; nearest: {', '.join(near)}" if near else f"; devices are OPEN-R locators, such as {example}"
            raise DeviceError(f"no device named {name!r} on the ERS-7{hint}") from None

    def step(self, ms: int) -> None:
        """Advance ``ms`` of simulated time in 8 ms frames; raises SimulationEnd at the end.

        Webots-mode motions advance once per call, as Webots' ``mtn_step(ms)`` does once
        per control step; OPEN-R-mode motions write every 8 ms joint frame.
        """
        whole = whole_ms(ms)
        if whole is None or whole <= 0 or whole % FRAME_MS:
            raise ValueError(f"step of {ms!r} ms: must be a positive whole multiple of the {FRAME_MS} ms joint frame")
        ms = whole
        if self.mtn_mode == "webots":
            self._step_webots_motions(ms)
        for _ in range(ms // FRAME_MS):
            if self.end_ms is not None and self.time_ms >= self.end_ms:
                raise SimulationEnd()
            if self.mtn_mode == "openr":
                self._play_openr_frame()
            self.sim.step_frame()
            now = self.sim.time_ms
            for device in list(self.enabled_devices.values()):
                device._after_frame(now)
            for listener in self.frame_listeners:
                listener(self)

    # ---------------------------------------------------------------- MTN

    def mtn_new(self, path: str | Path):
        """Load a motion, resolving relative names in the search folders; MtnError if not found
        (also for a name that is not a str or path, naming it), kept as ``mtn_error``."""
        try:
            if not isinstance(path, (str, os.PathLike)) or not os.fspath(path):
                return mtn_new(path)  # raises the MtnError naming the argument
            return mtn_new(find_file(path, self.search_dirs), ers7.all_locators(), self.mtn_mode)
        except MtnError as error:
            self.mtn_error = str(error)
            raise

    def mtn_play(self, motion) -> None:
        """Start ``motion``; one that is already playing restarts from its start (a motion has one
        playback, as in OPEN-R's MTN object and Webots' MTN struct: never two at once)."""
        motion = self._motion("mtn_play", motion)
        for locator in motion.locators:  # a Motion made in code: mtn_new refuses such files
            check_joint(locator, motion.source)
        player = MotionPlayer(motion, mode=self.mtn_mode)
        self.playing = [p for p in self.playing if p.motion is not motion]
        self.playing.append(_Playing(motion, player, ers7.joint_indices(motion.locators), self.time_ms))

    def mtn_delete(self, motion) -> None:
        """Stop ``motion``; it is no MTN any more: using it again raises (Webots' C API would
        read freed memory)."""
        motion = self._motion("mtn_delete", motion)
        self.playing = [p for p in self.playing if p.motion is not motion]
        self.deleted_motions[id(motion)] = motion

    def _motion(self, function: str, motion) -> Motion:
        if not isinstance(motion, Motion):
            raise MtnError(None, None, f"{function}({short_repr(motion)}): not an MTN (use the value mtn_new returned)")
        if self.deleted_motions.get(id(motion)) is motion:
            raise deleted_motion_error(function)
        return motion

    def _playing(self, motion) -> _Playing | None:
        return next((p for p in self.playing if p.motion is motion), None)

    def mtn_is_over(self, motion) -> bool:
        """Whether ``motion`` is not playing (never started, or ended)."""
        return self._playing(self._motion("mtn_is_over", motion)) is None

    def mtn_get_time(self, motion) -> int:
        """Milliseconds played (0 when not playing); Webots mode counts as Webots does."""
        playing = self._playing(self._motion("mtn_get_time", motion))
        if playing is None:
            return 0
        return playing.player.time_ms if self.mtn_mode == "webots" else self.time_ms - playing.start_ms

    def _play_openr_frame(self) -> None:
        servos = self.sim.servos
        for playing in list(self.playing):
            frame = (self.time_ms - playing.start_ms) // FRAME_MS
            if frame >= playing.player.num_frames:
                self.playing.remove(playing)
                continue
            servos.set_target(playing.indices, playing.player.frame(frame) / 1e6)
            servos.command[playing.indices] = servos.target[playing.indices]

    def _step_webots_motions(self, ms: int) -> None:
        for playing in list(self.playing):
            commands = playing.player.step(ms)
            if commands:
                self.sim.servos.set_target(playing.indices, [commands[loc] for loc in playing.motion.locators])
            if playing.player.is_over:
                self.playing.remove(playing)


@dataclass
class _Playing:
    motion: object
    player: MotionPlayer
    indices: list[int]
    start_ms: int
