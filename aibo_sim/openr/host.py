"""A memory stick's OPEN-R objects on the simulated ERS-7.

``MemoryStickRun`` starts the runtime (``openr-host`` of the host SDK, a child process: see
``openr_bridge.host_protocol`` for the messages), gives it the ERS-7's primitives and the
stick's objects, checks CONNECT.CFG against the services the objects registered (a line
naming a service no object has is a ``ConfigError`` naming the line), then, every 8 ms frame:

1. sends the state at this tick: for each sensor vector entry its value, signal, PWM duty and
   commanded value (joints in micro-radians, distances in micrometres, accelerations in
   micrometres/s^2 as a1 forward, a2 left, a3 up, switches 0/1, the electrostatic head and back
   sensors an AD value 0..80), and, when the camera made a frame that an object observes, its
   OFbkImageVectorData (with the CDT layer of the table the objects set) in the shared memory
   area the runtime named, which becomes the image's region there: the ers7 sensor's Y, Cr,
   Cb frame, from which the runtime makes ``encode_ycrcb``'s message itself (``RAW_IMAGE``:
   the encoding and its memory traffic cost this process more than the runtime), or the
   message encoded here (other cameras, colour tables ``encode_ycrcb`` refuses);
2. applies what the objects did (joint set-points, LEDs, motor power, joint gains, camera
   settings, colour tables, sound, Shutdown);
3. steps the physics one frame.

A frame in which no object code can run (most of them: the runtime foretells them in its
answer, with the set-points its effector plays in them; see ``host_protocol``'s Lookahead)
and that has no image or power event skips the message: its foretold records are applied
and its sensor values go with the next message. The runtime then plays those frames as
foretold, so every run is the one a message every frame gives (``lookahead = 0``), frame
for frame; only the round trips are fewer (fewer than half of HeadSwing's frames have one).

The robot's servos act only when powered (``OPENR::SetMotorPower``) and, for the Joint2
joints, once their gain is enabled and set (``EnableJointGain``, ``SetJointGain``): a joint's
stiffness is the model's (``mjcf.servo_stiffness`` of Sony's standard P) times the P register's
ratio to the standard P, scaled by 2^(14 - PSHIFT), so that the standard gains give the model's
stiffness bit for bit; I and D are not modelled (the servo's damping is the motor's). A joint
whose gain comes on holds where it is until commanded. The ears (Joint4) follow their state:
0 down, 1 up (their joint's range), when powered.

Choices marked UNCONFIRMED (no source gives them): the order of the sensor vector, the
touch sensors' AD value (100 per newton, at most 80: the simulated touch threshold, 0.1 N,
reads 10, beside Sony's thresholds 9-14), the head distance sensors' alternation (near on even
frames, far on odd), the battery (``BATTERY``, draining 1 % a minute from 100 %).
"""

from __future__ import annotations

import contextlib
import io
import mmap
import os
import signal
import socket
import struct
import sys
import time
import wave
from pathlib import Path

import numpy as np

import openr_bridge
from openr_bridge import host_protocol as protocol
from openr_bridge.config import ConfigError, Connection, cut
from openr_bridge.errors import CdtError
from openr_bridge.ers7_camera import CAMERA_SETTINGS, openr_frame_number
from openr_bridge.memory_stick import MemoryStick, read_object
from openr_bridge.wrapper import message_rgb

from .. import ers7
from ..camera import CameraFrame
from ..cbind.child import Child
from ..exit_status import scratch_folder
from ..files import SymlinkRefused, check_atomic_write, create_file, write_file_atomic
from ..robot import SimulationEnd
from ..sim import ACCEL_RANGE, FRAME_MS, IR_NOISE, Simulation
from .sdk import sdk_root

SYSTEM_SERVICES = {
    "OVirtualRobotComm": (
        "OVirtualRobotComm.Effector.OCommandVectorData.O",
        "OVirtualRobotComm.Sensor.OSensorFrameVectorData.S",
        "OVirtualRobotComm.FbkImageSensor.OFbkImageVectorData.S",
    ),
    "OVirtualRobotAudioComm": (
        "OVirtualRobotAudioComm.Speaker.OSoundVectorData.O",
        "OVirtualRobotAudioComm.Mic.OSoundVectorData.S",
    ),
}
SPIN_S = 0.005  # how long _reply polls before it blocks
CAPTURE_HOOK = b"\0aibo_sim_camera_captured\0"  # in the dynamic symbols of an object that calls it
PICTURE_SIZE = openr_bridge.LAYER_SIZE[openr_bridge.ofbkimageLAYER_H]  # a stick's pictures (camera_listeners)
SENT_FRAMES_KEPT = 8  # camera frames kept for the wrapper to say it took one (it takes the newest)
CRASH_EXIT_S = 5.0  # how long a runtime that reported a crash has to die of its signal (a core dump may take long)
OLED3_MODE_B = 1  # OPEN-R's oled3_MODE_B: a face light shows its B face
STANDARD_PSHIFT = 0x0E  # Sony's fixed PSHIFT (Model Information 2.2): the P register's scale
TOUCH_AD_PER_NEWTON, TOUCH_AD_MAX = 100, 80  # UNCONFIRMED, see the module docstring
# The battery at the start (UNCONFIRMED): status bits, capacity %, temperature (0.01 C),
# full capacity mAh, voltage mV, current mA, time difference h, volume; 1 % less a minute.
BATTERY = {
    "robotStatus": 0x00008040,
    "batteryStatus": 0x00C0,
    "remainingCapacity": 100,
    "temperature": 3000,
    "fullyChargedCapacity": 2200,
    "voltage": 8000,
    "current": -1200,
    "timeDif": 9,
    "volume": 2,
}
CAPACITY_LOW = 15  # % at which orsbBATTERY_CAPACITY_LOW is set
orsbMOTOR_POWER, orsbBATTERY_CAPACITY_LOW = 0x00000002, 0x00000200
SETTING_BY_REQUEST = {
    request: (setting, {number: name for name, number in values.items()})
    for setting, (request, values) in CAMERA_SETTINGS.items()
}


_U32, _FIELDS2, _FIELDS3, _FRAME = struct.Struct("<I"), struct.Struct("<2I"), struct.Struct("<3I"), struct.Struct("<5I")
_HEADER = _FIELDS2  # a message's size and kind
_JOINT = struct.Struct("<2i")
_JOINT_RECORD = protocol.RECORDS["JOINT"]


def _usable(cdt) -> bool:
    """Whether ``encode_ycrcb`` takes these colour tables (one-bit masks of channels 0-6, one
    table each); it raises CdtError for others, which then happens as before, in this process."""
    try:
        channels = [info.channel_index() for info in cdt.info[: cdt.numData]]
    except CdtError:
        return False
    return len(set(channels)) == len(channels)


# OPENR.h's OFatal values, by number.
FATAL_NAMES = {0: "ofatalMEMORY_STICK", 1: "ofatalPAUSE_SW", 2: "ofatalORB", 0xFFFFFFFF: "ofatalUNDEF"}


class OpenRObjectCrashed(RuntimeError):
    """An object of the memory stick killed the runtime (a signal: segmentation fault, abort)."""


def primitives() -> list[str]:
    """The ERS-7's primitive locators; an OPrimitiveID is the index here."""
    return [
        *(j.locator for j in ers7.JOINTS),
        *(s.locator for s in ers7.SENSORS),
        *ers7.ACCELEROMETER_ALIASES,
        *(led.locator for led in ers7.LEDS),
        ers7.WLAN_SWITCH_LOCATOR,
        ers7.SPEAKER_LOCATOR,
        ers7.MIC_LOCATOR,
    ]


class SensorFrame:
    """The sensor vector's entries and their values at a tick (``VALUES_PER_SENSOR`` int32 each)."""

    def __init__(self, sim: Simulation):
        self.sim = sim
        index = {locator: i for i, locator in enumerate(primitives())}
        kinds = protocol.SENSOR_KINDS
        self.joints = [i for i, j in enumerate(ers7.JOINTS) if not j.is_ear]
        touches = list(ers7.TOUCH_SENSORS)
        self.switch = np.array([s.name.startswith(("touch_paw", "touch_chin")) for s in touches])
        self.entries = (
            [(index[ers7.JOINTS[i].locator], kinds["JOINT"]) for i in self.joints]
            + [(index[s.locator], kinds["DISTANCE"]) for s in ers7.DISTANCE_SENSORS]
            + [
                (index[locator], kinds["ACCELERATION"])
                for locator in (ers7.SENSOR_BY_NAME["accelerometer"].locator, *ers7.ACCELEROMETER_ALIASES)
            ]
            + [
                (index[s.locator], kinds["SWITCH"] if switch else kinds["TOUCH"])
                for s, switch in zip(touches, self.switch)
            ]
            + [(index[ers7.WLAN_SWITCH_LOCATOR], kinds["SWITCH"])]
        )
        distances = len(ers7.DISTANCE_SENSORS)
        model = sim.model
        self._qpos = np.array([model.joint(sim.prefix + ers7.JOINTS[i].name).qposadr[0] for i in self.joints])
        self._touch_adr = np.array([model.sensor(sim.prefix + s.name).adr[0] for s in touches])
        self._threshold = np.array([s.threshold for s in touches])
        self._joints = np.array(self.joints)
        self._force_index = np.arange(model.nu)[sim.servos.ctrl][self._joints]  # this robot's actuators
        self._max_force = model.actuator_forcerange[self._force_index, 1]
        head = [i for i, s in enumerate(ers7.DISTANCE_SENSORS) if s.name in ("ir_near", "ir_far")]
        # The head's two sensors take turns, one a frame: on the other's frame a sensor keeps
        # its last value and gives no signal. _silent[tick % 2] marks the one that rests.
        self._silent = np.zeros((2, distances), bool)
        for turn, sensor in enumerate(head):
            self._silent[1 - turn, sensor] = True
        self._raw = np.zeros((len(self.entries), protocol.VALUES_PER_SENSOR))  # the values before rounding
        self._values = np.zeros(self._raw.shape, np.int32)
        from .sensor_values import fill  # compiled with numba on first use

        self._fill = fill
        self._distances = distances
        self._layout = (
            self._qpos,
            self._force_index,
            self._joints,
            self._max_force,
            np.array([model.sensor(sim.prefix + s.name).adr[0] for s in ers7.DISTANCE_SENSORS]),
            np.array([s.range_mm for s in ers7.DISTANCE_SENSORS], float),
            float(IR_NOISE),
            int(model.sensor(sim.prefix + "accelerometer").adr[0]),
            np.array(ers7.OPENR_ACCELERATION_SIGNS, float),
            float(ACCEL_RANGE),
            self._touch_adr,
            self.switch,
            self._threshold,
            float(TOUCH_AD_PER_NEWTON),
            float(TOUCH_AD_MAX),
            self._raw,
            self._values,
        )

    def at(self, tick: int) -> bytes:
        """The values at ``tick`` (the state now); draws the distance sensors' noise, as
        ``Simulation.distances_mm`` does."""
        sim = self.sim
        data = sim.data
        noise = sim.rng.standard_normal(self._distances)  # Simulation.distances_mm's draws
        self._fill(
            data.qpos,
            data.actuator_force,
            sim.servos.command,
            data.sensordata,
            noise,
            self._silent[tick & 1],
            *self._layout,
        )
        return self._values.tobytes()


class MemoryStickRun:
    """Runs a memory stick's objects on ``sim`` until ``end_ms`` or their Shutdown.

    ``frame_listeners`` are called with this run after every 8 ms frame (``sim``, ``time_ms``),
    ``camera_listeners`` with (camera frame index, RGB picture) of each picture the objects took:
    with the Webots wrapper (a ``build-ms`` stick), each its controller's camera took, as its
    ``camera_get_image`` served it; else each camera frame the objects observed, layer H as
    Sony's YCrCb2RGB decodes it.
    Console text goes to standard output and, when given, ``log_path``; the speaker's sound to
    ``sound_path`` (a 16 kHz WAV file) when the objects played any.
    """

    def __init__(
        self,
        sim: Simulation,
        stick: MemoryStick,
        workdir: Path,
        *,
        log_path: Path | None = None,
        sound_path: Path | None = None,
    ):
        self.sim, self.stick, self.workdir = sim, stick, Path(workdir)
        self.log_path, self.sound_path = log_path, sound_path
        if log_path is not None and os.path.islink(log_path):  # refused before a run prepares its folder
            raise SymlinkRefused.at(log_path)
        if sound_path is not None:  # a link at its temporary file: refused now, not after the run
            check_atomic_write(sound_path)
        self.frame_listeners, self.camera_listeners = [], []
        self.end_ms: int | None = None
        self.lookahead = protocol.LOOKAHEAD_FRAMES  # frames an answer may foretell (0: a message every frame)
        self.shutdown = False
        self.controller_error: str | None = None  # the wrapper's, when its controller failed
        self.fatal_error: str | None = None  # an object called OPENR::Fatal: the robot's power went off
        self.log_error: OSError | None = None  # console.log could not be written: the run ends
        self.object_names: list[str] = []  # the objects' own names, in OBJECT.CFG's order
        self._sensors = SensorFrame(sim)
        self._locators = primitives()
        self._joint_of = {self._locators.index(j.locator): i for i, j in enumerate(ers7.JOINTS)}
        self._led_of = {self._locators.index(led.locator): led.name for led in ers7.LEDS}
        self._ears = [i for i, j in enumerate(ers7.JOINTS) if j.is_ear]
        self._kp = np.zeros(len(ers7.JOINTS))  # each joint's stiffness when powered (0: gain off)
        self._standard_kp = sim.model.actuator_gainprm[sim.servos.ctrl, 0].copy()
        self._kp[self._ears] = self._standard_kp[self._ears]
        self._powered = False
        self._power = dict(BATTERY)
        self._power_key = None  # (minute, motors powered) of the last _update_power
        self._cdt = None
        self._cdt_usable = True  # no table, or tables the runtime's encoding takes as encode_ycrcb does
        self._sound: dict[int, np.ndarray] = {}
        self._camera_index = -1
        self._sent: dict[int, CameraFrame] = {}  # the newest frames the objects got, by OPEN-R frame number
        self._wrapper = False  # an object says which pictures its camera takes: the Webots wrapper
        self._image_slot = 0  # the shared memory's area for the next image (the runtime names it)
        self._image_observed = any(str(c.subject) == SYSTEM_SERVICES["OVirtualRobotComm"][2] for c in stick.connections)
        self._apply_gains()
        self._host = sdk_root() / "OPEN_R" / "bin" / "openr-host"  # built now, if it must be, not during the run

    @property
    def time_ms(self) -> int:
        return self.sim.time_ms

    def run(self) -> None:
        """Load, connect and start the objects, then run frames until the end; ConfigError for a
        stick that cannot run, OpenRObjectCrashed when an object crashed."""
        with scratch_folder("aibo-sim-openr-") as scratch:
            libraries = []
            for number, stick_object in enumerate(self.stick.objects):
                library = scratch / f"{number}_{stick_object.name}.so"
                code = read_object(stick_object, self.stick.object_cfg)
                self._wrapper |= CAPTURE_HOOK in code  # a wrapper built before it has the name nowhere
                library.write_bytes(code)
                libraries.append((library, stick_object))
            shared = scratch / "shared"
            with open(shared, "wb") as block:
                block.truncate(protocol.SHM_SIZE)  # zeros, written only where used
            with open(shared, "r+b") as block, mmap.mmap(block.fileno(), 0) as memory:
                self._memory = memory
                try:
                    self._serve(libraries, shared)
                except BaseException:  # a signal, a crash, a frame not written: the sound so far is kept
                    with contextlib.suppress(OSError):
                        self._write_sound()
                    raise
        self._write_sound()

    def _serve(self, libraries, shared: Path) -> None:
        ours, theirs = socket.socketpair()
        log = None if self.log_path is None else create_file(self.log_path)
        environment = {
            **os.environ,
            "AIBO_OPENR_FD": str(theirs.fileno()),
            "AIBO_OPENR_SHM": str(shared),
            **({"AIBO_OPENR_LOG_FD": str(log)} if log is not None else {}),
        }
        child = Child(
            [str(self._host)],
            name=f"memory stick {self.stick.root.name}",
            env=environment,
            pass_fds=(theirs.fileno(), *(() if log is None else (log,))),
            grace_note=self._unfinished,
        )
        self._stopping = False  # STOP sent: the objects' Stop entries have begun
        try:
            with child, ours:
                theirs.close()
                self._channel, self._child, self._buffer = ours, child, bytearray()
                self._foretold, self._stepped = [], []  # lookahead: records to come, frames stepped
                self._start(libraries)
                ended = None
                try:
                    while not self.shutdown and (self.end_ms is None or self.time_ms < self.end_ms):
                        if child.pending is not None or self.log_error is not None:
                            break
                        self._frame()
                except SimulationEnd as end:  # a match's stop, a frame its writer could not write
                    ended = end
                # After a signal or SimulationEnd too (the runtime is between messages then): the
                # objects' DoStop and DoDestroy run, as at the end of a run (a runtime silent for
                # the grace period after a signal is stopped by ``child``).
                self._stopping = True
                self._send(
                    protocol.MESSAGES["STOP"],
                    _U32.pack(openr_frame_number(self.sim.frame)) + self._stepped_frames(),
                )
                self._apply(self._reply(protocol.REPLIES["FRAME_DONE"]))
                # The runtime's own exit then flushes the files its objects left open.
                child.wait(None, protocol.WAIT_NOTICE_S, self._waiting)
                if ended is not None:
                    raise ended
                if self.log_error is not None:
                    raise self.log_error
        finally:
            theirs.close()
            if log is not None:
                os.close(log)

    def _start(self, libraries) -> None:
        self.object_names = [o.ms_path for _, o in libraries]  # their files until the runtime tells their names
        locators = self._locators
        setup = b"".join(
            [
                protocol.pack_string(openr_bridge.config.ROBOT_DESIGN),
                protocol.pack_string(str(self.stick.root.resolve())),
                protocol.pack_string(str(self.workdir.resolve())),
                struct.pack("<I", len(locators)),
                *map(protocol.pack_string, locators),
                struct.pack("<I", len(self._sensors.entries)),
                *(struct.pack("<2i", index, kind) for index, kind in self._sensors.entries),
                struct.pack(
                    "<3i",
                    locators.index(openr_bridge.CAMERA_LOCATOR),
                    locators.index(ers7.SPEAKER_LOCATOR),
                    locators.index(ers7.MIC_LOCATOR),
                ),
                self._sensors.at(self.sim.frame),
                struct.pack("<I", len(self.stick.design_data)),
                *(protocol.pack_string(k) + protocol.pack_string(v) for k, v in self.stick.design_data.items()),
                self._power_fields(),
                struct.pack("<I", len(libraries)),
                *(protocol.pack_string(str(path)) + protocol.pack_string(o.ms_path) for path, o in libraries),
            ]
        )
        self._send(protocol.MESSAGES["SETUP"], setup)
        services, records = self._services(self._reply(protocol.REPLIES["SERVICES"]))
        self._apply(records)
        if self.fatal_error is not None:  # the robot's power went off while its objects loaded
            self.shutdown = True
            return
        self._check(self.stick.connections, services)
        self._send(
            protocol.MESSAGES["CONNECT"],
            struct.pack("<I", len(self.stick.connections))
            + b"".join(
                protocol.pack_string(str(c.subject)) + protocol.pack_string(str(c.observer))
                for c in self.stick.connections
            ),
        )
        self._apply(self._reply(protocol.REPLIES["FRAME_DONE"]))

    def _services(self, payload: bytes) -> tuple[dict[str, str], bytes]:
        """Each registered service's object, from the SERVICES reply (plus the system's), and the
        records that follow them."""
        services = {name: system for system, names in SYSTEM_SERVICES.items() for name in names}
        count, offset = struct.unpack_from("<I", payload)[0], 4
        self.object_names = []
        for _ in range(count):
            name, offset = protocol.unpack_string(payload, offset)
            self.object_names.append(name)
            n, offset = struct.unpack_from("<I", payload, offset)[0], offset + 4
            for _ in range(n):
                service, offset = protocol.unpack_string(payload, offset)
                services[service] = name
        for later, name in enumerate(self.object_names):  # their services would share names
            first = self.object_names.index(name)
            if first < later:
                objects = self.stick.objects
                raise ConfigError(
                    f"{objects[later].ms_path} is an object named {name}, as {objects[first].ms_path} on line "
                    f"{objects[first].line} is: each object's name must be its own",
                    self.stick.object_cfg,
                    objects[later].line,
                )
        return services, payload[offset:]

    def _check(self, connections: tuple[Connection, ...], services: dict[str, str]) -> None:
        """ConfigError naming the CONNECT.CFG line of a service no object registered."""
        for connection in connections:
            for name in (connection.subject, connection.observer):
                if str(name) in services:
                    continue
                known = sorted({*services.values(), *self.object_names})  # an object may register none
                registers = [s for s in sorted(services) if services[s] == name.object]
                problem = (
                    f"{name.object} has no service {cut(name)} (it registers {', '.join(registers) or 'none'})"
                    if name.object in known
                    else f"no object named {cut(repr(name.object))} registers {cut(name)} (the objects: "
                    f"{', '.join(known)}; names are case-sensitive)"
                )
                raise ConfigError(problem, connection.path, connection.line)

    def _frame(self) -> None:
        """One 8 ms frame: its events and sensor values to the runtime and its answer back, or,
        on a frame the last answer foretold and that has no event for the runtime, its foretold
        records without a message (its sensor values go with the next one: see
        ``host_protocol``'s Lookahead)."""
        sim = self.sim
        tick = sim.frame
        flags, extra = self._events()
        values = self._sensors.at(tick)
        foretold = self._foretold
        if foretold and not flags:
            records = foretold.pop()
            self._stepped.append(_U32.pack(openr_frame_number(tick)) + values)
        else:
            ahead = self.lookahead
            if self.end_ms is not None:  # the frames after this one before the end
                ahead = min(ahead, -(-(self.end_ms - self.time_ms) // FRAME_MS) - 1)
            self._send(
                protocol.MESSAGES["FRAME"],
                _FRAME.pack(tick & 0xFFFFFFFF, tick >> 32, openr_frame_number(tick), flags, max(ahead, 0))
                + self._stepped_frames()
                + values
                + extra,
            )
            records, *later = protocol.split_frames(self._reply(protocol.REPLIES["FRAME_DONE"]))
            later.reverse()  # popped from the end
            self._foretold = later
        self._apply(records)
        sim.step_frame()
        for listener in self.frame_listeners:
            listener(self)

    def _events(self) -> tuple[int, bytes]:
        """This frame's ``FRAME_FLAGS`` and their fields: a camera frame for the objects (its
        message written to the shared memory; the camera's listeners called), a power change."""
        flags, extra = 0, b""
        index = self.sim.camera_frame_index()
        if index != self._camera_index and (self._image_observed or self.camera_listeners):
            self._camera_index = index
            frame = self.sim.camera.frame()
            if self._image_observed and self._runtime_encodes(frame):  # the runtime makes the message
                start = protocol.SHM_HEADER + protocol.IMAGE_SLOTS * protocol.MAX_IMAGE_BYTES
                ycrcb = frame.ycrcb
                self._memory[start : start + ycrcb.nbytes] = ycrcb
                flags |= protocol.FRAME_FLAGS["RAW_IMAGE"]
                extra += _FIELDS3.pack(self._image_slot, openr_frame_number(frame.frame_number), frame.index % 2**16)
            elif self._image_observed:  # else no object would see the message: it is not made
                message = frame.message if self._cdt is None else self._encode_with_cdt(frame)
                size = self._write_image(message, self._image_slot)
                flags |= protocol.FRAME_FLAGS["IMAGE"]
                extra += _FIELDS2.pack(self._image_slot, size)
            if self._image_observed and self.camera_listeners:
                self._sent[openr_frame_number(frame.frame_number)] = frame
                for number in list(self._sent)[:-SENT_FRAMES_KEPT]:
                    del self._sent[number]
                if not self._wrapper:
                    self._took(frame)
        if self._update_power():
            flags |= protocol.FRAME_FLAGS["POWER"]
            extra += self._power_fields()
        return flags, extra

    def _runtime_encodes(self, frame) -> bool:
        """Whether the runtime makes this camera frame's message itself (``RAW_IMAGE``): a frame
        of Y, Cr, Cb from the ers7 sensor of layer H's size, with no colour table or tables
        ``encode_ycrcb`` takes. The runtime's message is ``encode_ycrcb``'s, byte for byte; it
        spares this process the encoding and its memory traffic. Other frames are encoded here."""
        return (
            self.sim.camera.sensor is not None
            and frame.ycrcb.shape == (protocol.RAW_IMAGE_SIZE[1], protocol.RAW_IMAGE_SIZE[0], 3)
            and frame.ycrcb.flags.c_contiguous
            and self._cdt_usable
        )

    def _write_image(self, message, slot: int) -> int:
        """``message`` (an OFbkImageVectorData) into the shared memory's area ``slot``; its size.
        Its header and infos, then each layer's data, copied once (``bytes(message)`` would
        copy it twice); a message whose data do not follow its infos back to back as bytes."""
        start = protocol.SHM_HEADER + slot * protocol.MAX_IMAGE_BYTES
        infos = [message.GetInfo(layer) for layer in range(message.numData)]
        head = message.vectorInfo.pack() + b"".join(info.pack() for info in infos)
        offsets = [len(head), *(info.dataOffset + info.dataSize for info in infos)]
        size = offsets[-1]
        if message.vectorInfo.totalSize != size or any(i.dataOffset != o for i, o in zip(infos, offsets)):
            data = bytes(message)
            size = len(data)
            self._check_image_size(size)
            self._memory[start : start + size] = data
            return size
        self._check_image_size(size)
        memory = self._memory
        memory[start : start + len(head)] = head
        for layer, (info, offset) in enumerate(zip(infos, offsets)):
            memory[start + offset : start + offset + info.dataSize] = message.GetData(layer)
        return size

    @staticmethod
    def _check_image_size(size: int) -> None:
        if size > protocol.MAX_IMAGE_BYTES:
            raise ValueError(f"an image message of {size} bytes: the runtime takes at most {protocol.MAX_IMAGE_BYTES}")

    def _stepped_frames(self) -> bytes:
        """The foretold frames stepped since the last message, as ``FRAME`` and ``STOP`` carry them."""
        stepped = self._stepped
        fields = _U32.pack(len(stepped)) + b"".join(stepped)
        stepped.clear()
        return fields

    def _encode_with_cdt(self, frame):
        if self.sim.camera.sensor is not None:  # the ers7 sensor delivers Y, Cr, Cb
            return openr_bridge.encode_ycrcb(
                frame.ycrcb, frame_number=frame.frame_number, field_counter=frame.index, cdt=self._cdt
            )
        return openr_bridge.encode_frame(
            frame.rgb, frame_number=frame.frame_number, field_counter=frame.index, cdt=self._cdt
        )

    def _update_power(self) -> bool:
        """The battery at this time; whether anything changed."""
        key = (self.time_ms // 60000, self._powered)  # what it depends on
        if key == self._power_key:
            return False
        self._power_key = key
        power = self._power
        capacity = max(0, BATTERY["remainingCapacity"] - self.time_ms // 60000)
        status = power["robotStatus"] & ~(orsbMOTOR_POWER | orsbBATTERY_CAPACITY_LOW)
        status |= (orsbMOTOR_POWER if self._powered else 0) | (
            orsbBATTERY_CAPACITY_LOW if capacity <= CAPACITY_LOW else 0
        )
        if capacity == power["remainingCapacity"] and status == power["robotStatus"]:
            return False
        power.update(remainingCapacity=capacity, robotStatus=status)
        return True

    def _power_fields(self) -> bytes:
        return struct.pack(f"<{len(protocol.POWER_FIELDS)}i", *(self._power[f] for f in protocol.POWER_FIELDS))

    # ---------------------------------------------------------------- what the objects did

    def _apply(self, payload: bytes) -> None:
        """What the objects did in a frame (its records), in order; set-points, the commonest,
        without a call more."""
        servos, offset, end = self.sim.servos, 0, len(payload)
        while offset < end:
            kind, size = protocol.RECORD_HEADER.unpack_from(payload, offset)
            offset += protocol.RECORD_HEADER.size + size
            if kind == _JOINT_RECORD:
                primitive, value = _JOINT.unpack_from(payload, offset - size)
                joint = self._joint_of[primitive]
                if joint in self._ears:
                    target = servos.high[joint] if value else servos.low[joint]
                else:
                    target = value / 1e6
                servos.set_target(joint, target)
                servos.command[joint] = servos.target[joint]
            else:
                self._apply_record(kind, payload[offset - size : offset])

    def _apply_record(self, kind: int, data: bytes) -> None:
        """A record other than a set-point."""
        if kind == protocol.RECORDS["LED"]:
            primitive, intensity, mode = struct.unpack("<3i", data)
            self.sim.set_led(self._led_of[primitive], min(max(intensity, 0), 255) / 255, face_b=mode == OLED3_MODE_B)
        elif kind == protocol.RECORDS["MOTOR_POWER"]:
            self._powered = bool(struct.unpack("<i", data)[0])
            self._apply_gains()
        elif kind == protocol.RECORDS["GAIN"]:
            primitive, enabled, p, _, _, p_shift, _, _ = struct.unpack("<8i", data)
            joint = self._joint_of[primitive]
            ratio = p / ers7.JOINTS[joint].gains[0] * 2.0 ** (STANDARD_PSHIFT - p_shift)
            self._kp[joint] = self._standard_kp[joint] * ratio if enabled else 0.0
            self._apply_gains()
        elif kind == protocol.RECORDS["CAMERA"]:
            request, value = struct.unpack("<2I", data)
            setting, names = SETTING_BY_REQUEST[request]
            self.sim.camera.set_settings(**{setting: names[value]})
        elif kind == protocol.RECORDS["CDT"]:
            self._cdt = openr_bridge.OCdtVectorData.from_bytes(data)
            self._cdt_usable = _usable(self._cdt)
        elif kind == protocol.RECORDS["SOUND"]:
            start = struct.unpack_from("<I", data)[0]
            self._sound[start] = np.frombuffer(data, "<i2", offset=4).copy()
        elif kind == protocol.RECORDS["SHUTDOWN"]:
            self.shutdown = True
        elif kind == protocol.RECORDS["CONTROLLER_FAILED"]:
            self.controller_error = self.controller_error or bytes(data).decode("utf-8", "replace")
        elif kind == protocol.RECORDS["FATAL"]:
            code = _U32.unpack_from(data)[0]
            name = bytes(data[_U32.size :]).decode("utf-8", "replace")
            self.fatal_error = (
                f"OPEN-R object {name} called OPENR::Fatal({FATAL_NAMES.get(code, code)}) at simulated t = "
                f"{self.time_ms / 1000:.3f} s: the robot's power went off"
            )
        elif kind == protocol.RECORDS["LOG_FAILED"]:
            code = struct.unpack("<i", data)[0]
            self.log_error = OSError(f"cannot write {self.log_path}: {os.strerror(code)}")
            self.log_error.errno = code
        elif kind == protocol.RECORDS["IMAGE_SLOT"]:
            self._image_slot = _U32.unpack(data)[0]
        elif kind == protocol.RECORDS["CAMERA_CAPTURED"]:
            frame = self._sent.get(_U32.unpack(data)[0])
            if frame is not None:  # else written already, or not asked for (no listener)
                self._took(frame)

    def _took(self, frame: CameraFrame) -> None:
        """The camera's listeners told of ``frame``, the picture the objects got."""
        picture = message_rgb(frame.message)
        for listener in self.camera_listeners:
            listener(frame.index, picture)

    def _apply_gains(self) -> None:
        """Each actuator's stiffness: its gain when powered, none otherwise; a joint whose
        stiffness comes on holds its position."""
        model, servos = self.sim.model, self.sim.servos
        kp = self._kp if self._powered else np.zeros_like(self._kp)
        gains, biases = model.actuator_gainprm[servos.ctrl], model.actuator_biasprm[servos.ctrl]  # this robot's
        waking = (kp > 0) & (gains[:, 0] == 0)
        if waking.any():
            positions = self.sim.joint_positions()
            servos.set_target(np.flatnonzero(waking), positions[waking])
            servos.command[waking] = servos.target[waking]
        gains[:, 0] = kp
        biases[:, 1] = -kp

    def _write_sound(self) -> None:
        if not self._sound or self.sound_path is None:
            return
        end = max(start + len(samples) for start, samples in self._sound.items())
        track = np.zeros(end, "<i2")
        for start, samples in self._sound.items():
            track[start : start + len(samples)] = samples
        data = io.BytesIO()
        with wave.open(data, "wb") as out:
            out.setnchannels(1)
            out.setsampwidth(2)
            out.setframerate(protocol.SPEAKER_RATE)
            out.writeframes(track.tobytes())
        write_file_atomic(self.sound_path, data.getvalue())  # whole; a link there replaced, never followed

    # ---------------------------------------------------------------- messages

    def _send(self, kind: int, payload: bytes) -> None:
        try:
            self._channel.sendall(_HEADER.pack(len(payload) + 4, kind) + payload)
        except (BrokenPipeError, ConnectionResetError):  # the runtime died between two messages
            self._gone()

    def _reply(self, expected: int) -> bytes:
        """The next reply's payload if it is ``expected``; raises for FAILED and CRASHED."""
        buffer = self._buffer
        while len(buffer) < 4 or len(buffer) < 4 + struct.unpack_from("<I", buffer)[0]:
            chunk = self._poll()
            if chunk is None:
                try:
                    answered = self._child.wait(self._channel, protocol.WAIT_NOTICE_S, self._waiting)
                    chunk = self._channel.recv(1 << 20) if answered else b""
                except ConnectionResetError:  # the runtime died
                    chunk = b""
            if not chunk:
                self._gone()
            buffer += chunk
        size = struct.unpack_from("<I", buffer)[0]
        kind = struct.unpack_from("<I", buffer, 4)[0]
        payload = bytes(buffer[8 : 4 + size])
        del buffer[: 4 + size]
        if kind == protocol.REPLIES["FAILED"]:
            text, _ = protocol.unpack_string(payload, 0)
            object_cfg = self.stick.object_cfg
            line = next((o.line for o in self.stick.objects if text.startswith(o.ms_path + ":")), None)
            raise ConfigError(text, object_cfg, line)
        if kind == protocol.REPLIES["CRASHED"]:
            self._crashed, _ = protocol.unpack_string(payload, 0)
            self._gone()
        if kind != expected:
            raise RuntimeError(f"openr-host answered {kind} where {expected} was expected")
        return payload

    def _poll(self) -> bytes | None:
        """What the runtime sent within ``SPIN_S`` (b"": it closed the channel), else None,
        yielding the core between looks: a process that blocked resumes slower (see HybridVectorEnv)."""
        deadline = time.perf_counter() + SPIN_S
        while True:
            try:
                return self._channel.recv(1 << 20, socket.MSG_DONTWAIT)
            except ConnectionResetError:  # the runtime died
                return b""
            except BlockingIOError:
                if time.perf_counter() > deadline:
                    return None
                os.sched_yield()

    def _gone(self) -> None:
        """The runtime has exited (or must be stopped): raise what ended it."""
        crashed = getattr(self, "_crashed", None)
        if crashed is not None:  # it said so, then raises the signal again: its death is on its way
            self._child.exits_within(CRASH_EXIT_S)
        status = self._child.stop()
        where = f"at simulated t = {self.time_ms / 1000:.3f} s"
        if status is not None and status < 0:
            name = signal.Signals(-status).name
            # its own word, else the entry the shared status names (a crash its handler could not report)
            what = f"OPEN-R object {crashed}" if crashed else self._running() or "the OPEN-R runtime"
            raise OpenRObjectCrashed(f"{what} crashed ({name}: {signal.strsignal(-status)}) {where}")
        running = self._running()
        by = f" in {running}" if running else ""  # the object that called exit()
        raise OpenRObjectCrashed(f"the OPEN-R runtime exited with status {status}{by} {where}")

    def _unfinished(self) -> str:
        """What did not run of a stick stopped after a signal's grace (``Child``'s ``grace_note``)."""
        if not self._stopping:
            return "its objects' Stop entries did not run"
        running = self._running()
        return (
            f"{running} did not return: what came after it did not run"
            if running
            else "its Destroy entries did not run"
        )

    def _running(self) -> str | None:
        """The object entry the runtime is running ("OPEN-R object HELLO (entry 1)"; "OPEN-R object
        HELLO (while loading)", named by its file as the runtime names it then), or None."""
        number, entry = struct.unpack_from("<2I", self._memory, 0)
        if not number:
            return None
        names = ["OVirtualRobotComm", "OVirtualRobotAudioComm", *self.object_names]
        name = names[number - 1] if number <= len(names) else str(number)
        if entry == protocol.LOADING:
            return f"OPEN-R object {name.rsplit('/', 1)[-1].split('.', 1)[0]} (while loading)"
        return f"OPEN-R object {name} (entry {entry})"

    def _waiting(self, seconds: float) -> None:
        what = self._running() or "the OPEN-R runtime"
        print(
            f"aibo-sim: waiting for {what}: no answer for {seconds:.1f} s of wall time "
            f"(simulated time stays at t = {self.time_ms / 1000:.3f} s)",
            file=sys.stderr,
            flush=True,
        )
