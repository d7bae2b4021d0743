"""The messages between a simulator and the host OPEN-R runtime (``sdk/src``), one table for both.

The runtime is a child process. Messages go over a socket: a little-endian ``uint32`` length,
then that many bytes: a ``uint32`` message kind, then its fields (``uint32``/``int32`` numbers,
strings as ``uint32`` length and bytes). Images go through a shared memory block of
``SHM_SIZE`` bytes: its first ``SHM_HEADER`` bytes hold what the runtime is doing (the object
running a handler, ``uint32`` index + 1, 0 when none, and the selector, ``LOADING`` while its
file loads), then come
``IMAGE_SLOTS`` + 1 areas of ``MAX_IMAGE_BYTES``. An image's message goes into the area the
runtime last named (``IMAGE_SLOT`` records; 0 at the start): a slot whose last image's region
the objects have all given back, which then becomes the new image's region (nothing is
copied), or, when the objects hold every slot's image, the last area, which the runtime
copies into a region of its own. Either the simulator writes the message there (``IMAGE``:
any frame, encoded by ``openr_bridge.encoder``), or it writes the camera's Y, Cr, Cb frame
(``RAW_IMAGE_SIZE``, interleaved rows) into the last area and the runtime makes the message
in the named area (``RAW_IMAGE``: the ers7 sensor's frames of layer H's size with no colour
table or tables ``encode_ycrcb`` takes, the default; its message is ``encode_ycrcb``'s, byte
for byte, with the last ``CDT`` record's tables: tests/test_openr_runtime.py compares them).

Simulator to runtime:

- ``SETUP``: robot design; memory stick folder; working folder; the primitives (locator
  strings; the primitive's index is its ``OPrimitiveID``); the sensor vector's entries
  (primitive index, ``SENSOR_KINDS`` value each); camera, speaker and microphone indices
  (-1: none); the sensor values at boot (as in ``FRAME``: what ``OPENR::GetJointValue``
  reads before the first frame); design data (keyword, ``/MS`` path each); the objects to
  load (library path, the name OBJECT.CFG gives). The runtime loads and initialises the objects and answers
  ``SERVICES`` (per object: its name and registered service names; then the records the loading
  made, as ``FRAME_DONE``'s: an ``OPENR::Fatal`` there ends the run before ``CONNECT``) or
  ``FAILED`` (text).
- ``CONNECT``: (subject, observer) service name pairs; the runtime connects them, starts the
  objects and answers ``FRAME_DONE`` with what they did.
- ``FRAME``: frame tick (``uint64`` as two ``uint32``, low first), OPEN-R frame number,
  ``FRAME_FLAGS``, how many of the following frames the answer may foretell (at most
  ``LOOKAHEAD_FRAMES``; 0: none), the foretold frames stepped since the last message (see
  Lookahead: their count, then each one's OPEN-R frame number and sensor values),
  ``VALUES_PER_SENSOR`` int32 per sensor entry (the state at this tick: value, signal, PWM
  duty, commanded value), then the image's area and size (flag ``IMAGE``; the bytes in the
  shared memory) or the area for its message, its OPEN-R frame number and its field counter
  modulo 2^16 (flag ``RAW_IMAGE``; the frame in the last area), and the power status (flag
  ``POWER``: ``POWER_FIELDS`` int32). The runtime first plays the foretold frames, then
  delivers sensors (every ``SENSOR_FRAMES`` frames), the image and power events, plays the
  effector's and speaker's frame and answers ``FRAME_DONE``.
- ``STOP``: the run is over (at the OPEN-R frame number given; then the foretold frames
  stepped since the last message, as in ``FRAME``): Stop entries, then the runtime exits.

Runtime to simulator: ``SERVICES``, ``FRAME_DONE`` (records: ``uint32`` kind of ``RECORDS``,
``uint32`` size, payload), ``FAILED`` (text), ``CRASHED`` (sent by the runtime's signal
handler before it dies: the object and entry that were running).

Lookahead: most 8 ms frames run no object code (objects run when a sensor vector, an image, a
power event or an effector's ready event reaches them, every fourth frame or so), and there the
runtime only plays the effector's queued command vectors, whose values are already written. A
``FRAME`` message's ``FRAME_DONE`` foretells such frames: after the frame's records, for each
of up to ``LOOKAHEAD_FRAMES`` following frames in which no object code would run (no sensor
vector due for an observer, no microphone data, no subject's last queued vector ending, no
message waiting, no Shutdown), a ``NEXT_FRAME`` record and the records that frame makes (the
effector's set-points and LEDs). The simulator may step a prefix of them without a message,
applying each one's records: it stops at the first frame that has an image or a power event
for the runtime (which it knows, and the runtime does not) and at the run's end; its next
message (``FRAME`` or ``STOP``) carries the frames it stepped, whose sensor values the runtime
needs (``OSensorFrameVectorData`` holds four frames; ``GetJointValue`` reads the newest), and
the runtime then plays them as foretold (it fails, ``FAILED``, if one plays otherwise: a bug).
Nothing is played ahead, so the runtime's state at every message, and what the objects see,
is that of a message every frame; only the messages are fewer (benchmarks/openr.py).

Record payloads (int32 unless said): ``JOINT`` primitive, value (micro-radians; Joint4:
state 0/1); ``LED`` primitive, intensity 0..255, mode (0 A, 1 B); ``MOTOR_POWER`` on;
``GAIN`` primitive, enabled, P, I, D, P shift, I shift, D shift; ``CAMERA`` request,
value; ``CDT`` an ``OCdtVectorData`` (1344 bytes); ``SOUND`` start sample (at 16 kHz), then
16-bit samples; ``SHUTDOWN`` none; ``NEXT_FRAME`` none (the records after it are the next
frame's, foretold: see Lookahead); ``IMAGE_SLOT`` the shared memory's area for the next image;
``CONTROLLER_FAILED`` the wrapper's error message (UTF-8): its controller failed (an aibo-sim
extension, ``aibo_sim_controller_failed``, which the wrapper calls where the runtime has it);
``CAMERA_CAPTURED`` uint32 frame number of the image the wrapper's controller's camera took (the
extension ``aibo_sim_camera_captured``: what the run writes to ``--out``).
``LOG_FAILED`` int32 errno: the console's log could not be written (a full disk); the runtime
writes it no more, and the run ends naming the file. ``FATAL`` uint32 the ``OFatal`` code, then
the name of the object that called ``OPENR::Fatal`` (UTF-8): the robot's power went off there
(no entry of any object runs after it, DoStop and DoDestroy neither), and the run fails.
"""

import struct

from .ers7_camera import LAYER_SIZE
from .image import TAG_LENGTH, ofbkimageLAYER_H

MESSAGES = {"SETUP": 1, "CONNECT": 2, "FRAME": 3, "STOP": 4}
REPLIES = {"SERVICES": 101, "FRAME_DONE": 102, "FAILED": 103, "CRASHED": 104}
RECORDS = {
    "JOINT": 1,
    "LED": 2,
    "MOTOR_POWER": 3,
    "GAIN": 4,
    "CAMERA": 5,
    "CDT": 6,
    "SOUND": 7,
    "SHUTDOWN": 8,
    "NEXT_FRAME": 9,
    "IMAGE_SLOT": 10,
    "CONTROLLER_FAILED": 11,
    "CAMERA_CAPTURED": 12,
    "LOG_FAILED": 13,
    "FATAL": 14,
}
FRAME_FLAGS = {"IMAGE": 1, "POWER": 2, "RAW_IMAGE": 4}
# What each sensor vector entry holds (the runtime gives each its ODataType).
SENSOR_KINDS = {"JOINT": 1, "DISTANCE": 2, "ACCELERATION": 3, "SWITCH": 4, "TOUCH": 5}
VALUES_PER_SENSOR = 4
SENSOR_FRAMES = 4  # 8 ms frames per sensor vector (every 32 ms)
LOOKAHEAD_FRAMES = 16  # at most this many frames foretold by a FRAME_DONE
POWER_FIELDS = (
    "robotStatus",
    "batteryStatus",
    "remainingCapacity",
    "temperature",
    "fullyChargedCapacity",
    "voltage",
    "current",
    "timeDif",
    "volume",
)
SPEAKER_RATE = 16000  # SOUND records' samples per second
SHM_HEADER = 64
LOADING = 0xFFFFFFFF  # the shared status's selector while an object's file loads (its constructors run)
MAX_IMAGE_BYTES = 1 << 20  # the room for an image message in each area of the shared block
IMAGE_SLOTS = 4  # areas an image's region may stay in (and one more, copied by the runtime)
SHM_SIZE = SHM_HEADER + (IMAGE_SLOTS + 1) * MAX_IMAGE_BYTES
RAW_IMAGE_SIZE = LAYER_SIZE[ofbkimageLAYER_H]  # (width, height) of the Y, Cr, Cb frames the runtime encodes
WAIT_NOTICE_S = 10.0

_U32 = struct.Struct("<I")
RECORD_HEADER = struct.Struct("<II")  # a record's kind and payload size
_NEXT_FRAME = RECORDS["NEXT_FRAME"]


def c_header() -> str:
    """``openr_host_protocol.h``: the tables above for the runtime."""
    lines = [
        "/* Generated by openr_bridge.host_protocol: the runtime's messages with its simulator. */",
        "#ifndef OPENR_HOST_PROTOCOL_H",
        "#define OPENR_HOST_PROTOCOL_H",
    ]
    for prefix, table in (
        ("MSG", MESSAGES),
        ("REPLY", REPLIES),
        ("RECORD", RECORDS),
        ("FLAG", FRAME_FLAGS),
        ("SENSOR", SENSOR_KINDS),
    ):
        lines += [f"#define AIBO_OPENR_{prefix}_{name} {value}" for name, value in table.items()]
    lines += [
        f"#define AIBO_OPENR_VALUES_PER_SENSOR {VALUES_PER_SENSOR}",
        f"#define AIBO_OPENR_SENSOR_FRAMES {SENSOR_FRAMES}",
        f"#define AIBO_OPENR_LOOKAHEAD_FRAMES {LOOKAHEAD_FRAMES}",
        f"#define AIBO_OPENR_POWER_FIELDS {len(POWER_FIELDS)}",
        f"#define AIBO_OPENR_SPEAKER_RATE {SPEAKER_RATE}",
        f"#define AIBO_OPENR_SHM_HEADER {SHM_HEADER}",
        f"#define AIBO_OPENR_LOADING {LOADING:#x}u",
        f"#define AIBO_OPENR_MAX_IMAGE_BYTES {MAX_IMAGE_BYTES}",
        f"#define AIBO_OPENR_IMAGE_SLOTS {IMAGE_SLOTS}",
        f"#define AIBO_OPENR_SHM_SIZE {SHM_SIZE}",
        f"#define AIBO_OPENR_IMAGE_WIDTH {RAW_IMAGE_SIZE[0]}",
        f"#define AIBO_OPENR_IMAGE_HEIGHT {RAW_IMAGE_SIZE[1]}",
        f"#define AIBO_OPENR_TAG_LENGTH {TAG_LENGTH}",
        "#endif",
        "",
    ]
    return "\n".join(lines)


def pack_string(text: str) -> bytes:
    data = text.encode()
    return _U32.pack(len(data)) + data


def unpack_string(payload: bytes, offset: int) -> tuple[str, int]:
    """(string, offset after it) at ``offset``."""
    size = _U32.unpack_from(payload, offset)[0]
    start = offset + 4
    return payload[start : start + size].decode("utf-8", "replace"), start + size


def split_frames(payload: bytes) -> list[bytes]:
    """A ``FRAME_DONE`` payload's records per frame: the frame's own, then each foretold frame's
    (the records between ``NEXT_FRAME`` records)."""
    frames, start, offset, end = [], 0, 0, len(payload)
    while offset < end:
        kind, size = RECORD_HEADER.unpack_from(payload, offset)
        if kind == _NEXT_FRAME:
            frames.append(payload[start:offset])
            start = offset + RECORD_HEADER.size
        offset += RECORD_HEADER.size + size
    frames.append(payload[start:])
    return frames
