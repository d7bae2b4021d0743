"""OPEN-R motion files (``.MTN``, "OMTN" v1.2): reader, writer and playback.

Format, timing and the Webots playback quirk: ``shared/specs/ers7-reference.md`` §C.3, §D.
No MuJoCo here: playback is a pure function of time that yields joint targets.

Decisions where the spec leaves room (also listed in the report that came with this file):

* The header fields Sony's ``MTNFile.cc`` never reads are not checked either, so a file another
  tool wrote plays as it would on the robot: the version (AIBO MIND's ERS-7 motions,
  ``DRX-1000``, are 1.1 and 1.2 in the same layout; the writer writes 1.2), section 0's size
  and the section count (section 1 starts at byte 28, after section 0's fixed 24 bytes, as in
  OPEN-R's struct and Webots' reader), the sections' numbers and section 3's data type. Only
  the magic ``OMTN`` is checked, so that another file is named as such. Sections 1 and 2 are
  jumped by ``sectionSize``: slack after the
  parsed strings is skipped (its bytes, normally zero padding, are not kept; the writer emits
  zeros). Section 3 holds ``12 + N*4*(3+J) + 4*(N-1)`` bytes for N keyframes of J joints, and
  they must all be in the file; its size field is not checked (OPEN-R's ``MTNFile`` and Webots
  compute the offsets from N and J and never read it, and one of Sony's SDK samples,
  MoNet's ERS-210 ``sit_lose01``, gives the size of 20 joints for its 15); an error in the
  keyframes names the joint count the field fits where it differs from section 2's. Bytes after it are
  ignored (OPEN-R and Webots stop reading there), so they do not survive a round trip. A
  motion needs at least one keyframe, one joint, distinct locators, a frame time > 0 and
  non-negative interpolation counts.
* Limits no real motion reaches, so that a corrupt word is an error rather than a motion
  that plays for days or a joint sent to -2147 rad: a motion lasts at most
  ``MAX_LENGTH_MS`` (10 minutes; Sony's motions last seconds, SITDANCE 28 s), and a joint
  value lies within a full turn, +-2 pi rad (the ERS-7's widest joint spans 4.1 rad). Values
  just past a joint's hardware range are kept (Sony's own SWSDK.MTN has one: the servo
  stops at its limit).
* Strings are latin-1 (a pstring is a u8 length, so at most 255 bytes).
* A missing file is an ``OSError`` from :func:`read_mtn` (it is not a malformed file);
  :func:`mtn_new` turns it into Webots' "File not found: <path>" :class:`MtnError`. A FIFO,
  device or folder in its place is an :class:`MtnError` naming it ("not a regular file").
* OPEN-R playback (``MTN.cc``) hard-codes 16 ms frames: ``2n+2`` sub-frames of 8 ms per
  segment. Here a segment has ``(n+1)*frame_time_ms/8`` sub-frames, which is the same for
  16 ms and scales otherwise; a frame time that is not a multiple of 8 ms cannot be played in
  this mode, and :func:`mtn_new` refuses it there (an :class:`MtnError` naming the file; Webots'
  ``mtn_play`` has no way to fail). ``MTN.cc`` never sends the final keyframe
  itself (it stops once the last segment is done); this player appends it as one last
  sub-frame, so a motion ends exactly on its final pose at ``t = length_ms``.
* Joint values are held in int64; OPEN-R's 32-bit ``value1 - value0`` could overflow for
  values more than 2^31 apart, which no real file has; this code does not reproduce that.
"""

from __future__ import annotations

import math
import numbers
import operator
import os
import struct
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from openr_bridge import FRAME_TICK_MS
from openr_bridge.config import read_regular_file
from openr_bridge.errors import NotRegularFile

from . import ers7
from .files import named_file, write_file_atomic

MAGIC = b"OMTN"
ODA_MAGIC, ODA_HEADER_SIZE, ODA_ENTRY_SIZE = b"ODAR", 64, 144  # Sony's archives of motions and sounds (ODA.h)
VERSION = (1, 2)  # what the writer writes; the reader takes any, as Sony's MTNFile does
NUM_SECTIONS = 4
SECTION0_SIZE = 24  # section 1 starts after it, at byte 28, whatever its size field says (MTNFile)
DEFAULT_FRAME_TIME_MS = 16
SUBFRAME_MS = FRAME_TICK_MS  # OPEN-R command vectors carry one joint value per 8 ms frame
MODES = ("openr", "webots")  # MotionPlayer's playback modes
ERS7_DESIGN = "DRX-1000"  # the robot design an ERS-7 motion names (Sony's MoNet: MoNetAgentManager.h)
OTHER_DESIGNS = {"DRX-900": "ERS-210/220"}  # the other design Sony's MoNet names
_S32_MIN, _S32_MAX = -(2**31), 2**31 - 1
MAX_LENGTH_MS = 10 * 60 * 1000
MAX_JOINT_URAD = round(2 * np.pi * 1e6)


class MtnError(ValueError):
    """A malformed or unusable motion. ``str()`` names the file and, for parse errors, the byte
    offset; ``message`` is the bare text. With neither source nor offset, ``str()`` is the bare
    text (used for Webots' own messages, e.g. "Missing device in model: <locator>"). The source
    is shown as :func:`printable` shows it (a motion's name may hold control characters)."""

    def __init__(self, source: str | None, offset: int | None, message: str):
        self.source, self.offset, self.message = source, offset, message
        where = [] if source is None else [printable(source, NAME_LIMIT)]
        if offset is not None:
            where.append(f"byte {offset} (0x{offset:x})")
        super().__init__(": ".join(where + [message]))


def _beyond_limits(
    frame_time_ms: int, interpolate: np.ndarray, keyframes: np.ndarray, locators: Sequence[str]
) -> tuple[str, int, int | None] | None:
    """The first of ``MAX_LENGTH_MS`` and ``MAX_JOINT_URAD`` a motion breaks, as (message, keyframe,
    joint): for the length, the keyframe that ends the segment in which it passes the limit, and
    joint None."""
    elapsed_ms = np.cumsum((interpolate + 1) * frame_time_ms)
    if elapsed_ms.size and elapsed_ms[-1] > MAX_LENGTH_MS:
        k = int(np.argmax(elapsed_ms > MAX_LENGTH_MS))  # the segment in which the motion passes the limit
        return (
            f"the motion lasts {elapsed_ms[-1] / 1000:.0f} s, longer than the {MAX_LENGTH_MS // 1000} s a motion "
            f"may last (it passes them in segment {k} -> {k + 1} of {len(interpolate)}: numInterpolate "
            f"{int(interpolate[k])} of {frame_time_ms} ms frames)",
            k + 1,
            None,
        )
    beyond = np.argwhere(np.abs(keyframes) > MAX_JOINT_URAD)
    if beyond.size:
        k, j = beyond[0].tolist()
        return f"keyframe {k}, {printable(locators[j])}: {keyframes[k, j] / 1e6:g} rad is beyond a full turn", k, j
    return None


def whole_ms(value) -> int | None:
    """``value`` as an int when it is a whole number (an int, or a float such as 16.0), else
    None: 8.9 ms is not silently 8 ms, nor a bool or a string a duration."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return None
    if isinstance(value, numbers.Integral):
        return int(value)
    value = float(value)
    return int(value) if value.is_integer() else None


def _whole_numbers(values, what: str, source: str) -> np.ndarray:
    """``values`` as an int64 array, or the MtnError naming ``what`` unless each is a whole number
    the file's 32-bit fields hold (0.7 rad given for micro-radians was cut to 0, NaN a ValueError)."""
    try:
        array = np.asarray(values)
    except ValueError:  # rows of different lengths
        raise MtnError(source, None, f"{what}: rows of different lengths") from None
    whole = array.dtype.kind in "iu" or (array.dtype.kind == "f" and bool(np.isfinite(array).all()))
    whole = whole and bool((array == np.round(array)).all()) and bool(((array >= -(2**31)) & (array < 2**31)).all())
    if array.size and not whole:
        raise MtnError(source, None, f"{what} must be whole numbers within 32 bits (micro-radians, frame counts)")
    return array.astype(np.int64)


def _check(source: str, checks) -> None:
    """Raise the MtnError of the first (bad, message) pair whose ``bad`` is true."""
    for bad, message in checks:
        if bad:
            raise MtnError(source, None, message)


@dataclass(eq=False)
class Motion:
    """One motion. Angles are integer micro-radians, as stored in the file.

    ``keyframes`` (N, J) joint values; ``attitudes`` (N, 3) body roll/pitch/yaw (editor data,
    ignored by playback); ``interpolate`` (N-1,) numInterpolate of each segment k -> k+1;
    ``source`` the file it was read from, which its errors name (default: its name).
    """

    name: str
    creator: str
    design: str
    frame_time_ms: int
    locators: tuple[str, ...]
    keyframes: np.ndarray
    attitudes: np.ndarray
    interpolate: np.ndarray
    option: int = 0
    source: str | None = None

    def __post_init__(self) -> None:
        texts = (self.name, self.creator, self.design)
        if not all(isinstance(text, str) for text in texts):  # a None name failed only in write_mtn
            raise MtnError(str(self.source or self.name), None, "name, creator and design must be strings")
        self.locators = tuple(self.locators)
        if not all(isinstance(locator, str) for locator in self.locators):
            raise MtnError(self.name, None, f"locators must be strings, not {self.locators!r}")
        self.source = self.name if self.source is None else self.source
        self.keyframes = _whole_numbers(self.keyframes, "keyframes", self.source)
        self.attitudes = _whole_numbers(self.attitudes, "attitudes", self.source)
        self.interpolate = _whole_numbers(self.interpolate, "interpolate", self.source).reshape(-1)
        n, j = len(self.keyframes), len(self.locators)
        whole_time = (whole_ms(self.frame_time_ms) or 0) > 0  # 16.5 was cut to 16
        _check(
            self.source,
            [
                (n < 1, "a motion needs at least one keyframe"),
                (j < 1, "a motion needs at least one joint"),
                (len(set(self.locators)) != j, "duplicate locator"),
                (self.keyframes.shape != (n, j), f"keyframes shape {self.keyframes.shape} is not ({n}, {j})"),
                (self.attitudes.shape != (n, 3), f"attitudes shape {self.attitudes.shape} is not ({n}, 3)"),
                (
                    self.interpolate.shape != (max(n - 1, 0),),
                    f"interpolate has {self.interpolate.size} counts, want {n - 1}",
                ),
                (bool((self.interpolate < 0).any()), "negative interpolation count"),
                (not whole_time, f"frame time {self.frame_time_ms!r} ms is not a positive whole number"),
            ],
        )
        self.frame_time_ms = int(self.frame_time_ms)
        self.option = int(self.option)
        problem = _beyond_limits(self.frame_time_ms, self.interpolate, self.keyframes, self.locators)
        if problem is not None:
            raise MtnError(self.source, None, problem[0])

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Motion):
            return NotImplemented
        return (
            (self.name, self.creator, self.design, self.frame_time_ms, self.locators, self.option)
            == (other.name, other.creator, other.design, other.frame_time_ms, other.locators, other.option)
            and np.array_equal(self.keyframes, other.keyframes)
            and np.array_equal(self.attitudes, other.attitudes)
            and np.array_equal(self.interpolate, other.interpolate)
        )

    @property
    def num_keyframes(self) -> int:
        """Number of keyframes."""
        return len(self.keyframes)

    @property
    def segment_ms(self) -> np.ndarray:
        """Duration of each segment k -> k+1: (numInterpolate + 1) * frame time."""
        return (self.interpolate + 1) * self.frame_time_ms

    @property
    def length_ms(self) -> int:
        """Total length; the last keyframe lasts 0 ms."""
        return int(self.segment_ms.sum())

    def positions_rad(self) -> np.ndarray:
        """Keyframe joint values in radians, (N, J) float64."""
        return self.keyframes / 1e6

    @classmethod
    def from_poses(
        cls,
        name: str,
        locators: Sequence[str] | None,
        poses_rad,
        segment_ms: int | Sequence[int],
        creator: str = "aibo-sim",
        design: str = "DRX-1000",
        frame_time_ms: int = DEFAULT_FRAME_TIME_MS,
    ) -> Motion:
        """Author a motion from poses in radians (N, J). ``locators=None`` means every ERS-7
        joint in ``ers7.JOINTS`` order. ``segment_ms`` (one value, or one per segment) must be
        positive multiples of ``frame_time_ms``. Values are rounded to the nearest µrad (ties to
        even); attitudes are zero."""
        if locators is None:
            locators = [j.locator for j in ers7.JOINTS]
        if isinstance(locators, str):  # its characters would be the locators
            raise MtnError(name, None, f"locators must be a sequence of locators, not the string {locators!r}")
        try:
            poses = np.asarray(poses_rad, dtype=np.float64)
        except (TypeError, ValueError):  # ragged rows, None
            poses = np.empty(0)
        if poses.ndim != 2 or not np.isfinite(poses).all():
            raise MtnError(name, None, "poses must be a finite (N, J) array")
        n = len(poses)
        try:
            seg = np.asarray(segment_ms)
        except (TypeError, ValueError):  # ragged
            seg = np.full(1, np.nan)
        if seg.dtype.kind not in "iuf":  # None, strings, bools
            seg = np.full(seg.shape, np.nan)
        if seg.ndim == 0:
            seg = np.full(max(n - 1, 0), seg)
        if seg.shape != (max(n - 1, 0),):
            raise MtnError(name, None, f"{seg.size} segment durations for {n} poses (want {n - 1})")
        if (whole_ms(frame_time_ms) or 0) <= 0 or not np.isfinite(seg).all() or (seg > _S32_MAX).any():
            raise MtnError(
                name, None, f"segment durations {seg.tolist()} must be positive multiples of {frame_time_ms!r} ms"
            )
        frame_time_ms = int(frame_time_ms)
        if any(int(s) != s or s <= 0 or int(s) % frame_time_ms for s in seg.tolist()):
            raise MtnError(
                name, None, f"segment durations {seg.tolist()} must be positive multiples of {frame_time_ms} ms"
            )
        micro = np.rint(poses * 1e6)
        if (micro < _S32_MIN).any() or (micro > _S32_MAX).any():
            raise MtnError(name, None, "pose out of the s32 micro-radian range")
        return cls(
            name=name,
            creator=creator,
            design=design,
            frame_time_ms=frame_time_ms,
            locators=tuple(locators),
            keyframes=micro.astype(np.int64),
            attitudes=np.zeros((n, 3), dtype=np.int64),
            interpolate=seg.astype(np.int64) // frame_time_ms - 1,
        )


# ----------------------------------------------------------------------------- reading


class _Reader:
    """Bounds-checked little-endian reads; every failure is an MtnError at an offset."""

    def __init__(self, data: bytes, source: str):
        self.data, self.source = data, source

    def fail(self, offset: int, message: str) -> MtnError:
        return MtnError(self.source, offset, message)

    def need(self, offset: int, size: int, what: str, end: int | None = None) -> None:
        limit = len(self.data) if end is None else end
        if offset + size > limit:
            where = "file" if limit == len(self.data) else "section"
            raise self.fail(offset, f"truncated: {what} needs {size} bytes, the {where} ends at byte {limit}")

    def unpack(self, fmt: str, offset: int, what: str, end: int | None = None) -> tuple:
        self.need(offset, struct.calcsize(fmt), what, end)
        return struct.unpack_from(fmt, self.data, offset)

    def pstring(self, offset: int, what: str, end: int) -> tuple[str, int]:
        (length,) = self.unpack("<B", offset, f"{what} length", end)
        self.need(offset + 1, length, what, end)
        return self.data[offset + 1 : offset + 1 + length].decode("latin-1"), offset + 1 + length

    def section_header(self, offset: int, number: int) -> int:
        """Check section ``number``'s header at ``offset``; return the section's end. Its number
        field is not read (nor is it by Sony's MTNFile: sections follow from their sizes)."""
        _, size = self.unpack("<II", offset, f"section {number} header")
        if size < 8:
            raise self.fail(offset + 4, f"section {number} size {size} is less than its 8-byte header")
        if offset + size > len(self.data):
            raise self.fail(offset + 4, f"section {number} size {size} overruns the file ({len(self.data)} bytes)")
        return offset + size


def parse_mtn(data: bytes, source: str = "<bytes>") -> Motion:
    """Parse the bytes of an MTN file. ``source`` names it in error messages."""
    r = _Reader(bytes(data), source)
    r.need(0, 4, "magic")
    if r.data[:4] != MAGIC:
        raise r.fail(0, f"wrong magic {r.data[:4]!r} (should be {MAGIC!r})")

    # Section 0's size, the section count and the version are not read, as Sony's MTNFile does not:
    # a file another Sony tool wrote with other values there plays as on the robot.
    r.need(4, SECTION0_SIZE, "section 0")
    _, _, nkey, frame_time, option = r.unpack("<HHHHI", 16, "section 0")
    end0 = 4 + SECTION0_SIZE
    if nkey == 0:
        raise r.fail(20, "zero keyframes")
    if frame_time == 0:
        raise r.fail(22, "frame rate 0 ms")

    end1 = r.section_header(end0, 1)
    name, p = r.pstring(end0 + 8, "motion name", end1)
    creator, p = r.pstring(p, "creator", end1)
    design, p = r.pstring(p, "robot design", end1)

    end2 = r.section_header(end1, 2)
    (njoint,) = r.unpack("<H", end1 + 8, "joint count", end2)
    if njoint == 0:
        raise r.fail(end1 + 8, "zero joints")
    if end1 + 10 + njoint > end2:  # a locator takes at least its length byte
        raise r.fail(end1 + 8, f"{njoint} joints cannot fit in section 2's {end2 - end1 - 10} bytes of locators")
    locators, p = [], end1 + 10
    for i in range(njoint):
        at = p
        loc, p = r.pstring(p, f"locator {i}", end2)
        if loc in locators:
            raise r.fail(at, f"duplicate locator {loc!r}")
        locators.append(loc)

    _, size_field, _ = r.unpack("<III", end2, "section 3 header")  # number, size, data type: unread, as by MTNFile
    kf_words = 3 + njoint
    size = 12 + nkey * 4 * kf_words + 4 * (nkey - 1)
    # A wrong joint count shows as nonsense in the keyframes: the size field's count, where it
    # differs, is named with the error (a hint only: OPEN-R does not read the field).
    implied, rest = divmod(size_field - 12 - 4 * (nkey - 1), 4 * nkey)
    hint = (
        f"; section 3's size field fits {implied - 3} joints, section 2 lists {njoint}"
        if not rest and implied > 3 and implied - 3 != njoint
        else ""
    )
    r.need(end2, size, f"section 3 ({nkey} keyframes of {njoint} joints{hint})")  # bytes after it are ignored

    # Keyframe 0, then (numInterpolate, keyframe) pairs: view as rows of 1 + kf_words s32,
    # with a dummy interpolation word in front of keyframe 0.
    body = end2 + 12
    words = (
        np.frombuffer(b"\0\0\0\0" + r.data[body : end2 + size], dtype="<i4")
        .astype(np.int64)
        .reshape(nkey, 1 + kf_words)
    )
    interpolate = words[1:, 0]
    if (interpolate < 0).any():
        k = int(np.argmax(interpolate < 0)) + 1
        offset = body + k * 4 * (1 + kf_words) - 4
        raise r.fail(offset, f"negative interpolation count {int(interpolate[k - 1])} before keyframe {k}{hint}")
    keyframes = words[:, 4:]
    problem = _beyond_limits(frame_time, interpolate, keyframes, locators)
    if problem is not None:  # at the word: the segment's numInterpolate, or the joint's value
        message, k, j = problem
        raise r.fail(body + (k * (1 + kf_words) + (0 if j is None else 4 + j)) * 4 - 4, message + hint)
    return Motion(
        name=name,
        creator=creator,
        design=design,
        frame_time_ms=frame_time,
        locators=tuple(locators),
        keyframes=keyframes.copy(),
        attitudes=words[:, 1:4].copy(),
        interpolate=interpolate.copy(),
        option=option,
        source=source,
    )


def oda_motions(data: bytes, source: str = "<bytes>") -> dict[str, bytes]:
    """The motions (``OMTN`` entries) of one of Sony's ODA archives (MoNet's ``MOTION7.ODA``;
    ``ODA.h``: a 64-byte header ``ODAR``, version, file count; then 144-byte entries: magic, a
    128-byte NUL-terminated name, offset from the archive's start, size), by name; of two
    entries with one name, the first (as ``ODA::Find``). An entry whose data lies outside the
    archive is an :class:`MtnError` naming the entry and the data's byte."""
    r = _Reader(bytes(data), source)
    (magic, _, count) = r.unpack("<4sII", 0, "ODA header")
    if magic != ODA_MAGIC:
        raise r.fail(0, f"wrong magic {magic!r} (should be {ODA_MAGIC!r})")
    motions = {}
    for index in range(count):
        at = ODA_HEADER_SIZE + index * ODA_ENTRY_SIZE
        kind, name, offset, size = r.unpack("<4s128sII", at, f"ODA entry {index}")
        r.need(offset, size, f"ODA entry {index}'s data (byte {offset}, {size} bytes)")
        if kind == MAGIC:
            motions.setdefault(name.split(b"\0", 1)[0].decode("latin-1"), r.data[offset : offset + size])
    return motions


def _read_file(source: str) -> bytes:
    if "\0" in source:  # no file has such a name (open() would raise a bare ValueError)
        raise MtnError(source, None, "a file name cannot hold a NUL character")
    try:
        return read_regular_file(source)
    except NotRegularFile as error:
        raise MtnError(source, None, str(error)) from None


def read_mtn(path: str | os.PathLike) -> Motion:
    """Read an MTN file. Malformed content raises :class:`MtnError`, as does a FIFO, device or
    folder in its place (refused at once: opened without blocking, never waited on or read
    without end); I/O errors are ``OSError``."""
    source = os.fspath(path)
    return parse_mtn(_read_file(source), source)


def read_oda_motion(path: str | os.PathLike, motion: str | None) -> Motion:
    """The motion named ``motion`` in one of Sony's ODA archives (:func:`oda_motions`), its
    source ``ARCHIVE:MOTION``; an :class:`MtnError` listing the archive's motions when ``motion``
    is None or not among them, and one for a file that is no archive."""
    source = os.fspath(path)
    data = _read_file(source)
    if data[:4] != ODA_MAGIC:
        raise MtnError(source, 0, f"not an ODA archive (magic {data[:4]!r}, not {ODA_MAGIC!r})")
    motions = oda_motions(data, source)
    if motion not in motions:
        held = ", ".join(printable(name) for name in motions) or "none"
        why = "an ODA archive: name one of its motions" if motion is None else f"no motion {printable(motion)!r}"
        raise MtnError(source, None, f"{why} ({source}:NAME); it holds {len(motions)}: {held}")
    return parse_mtn(motions[motion], f"{source}:{motion}")


# ----------------------------------------------------------------------------- writing


def _pstring(text: str, what: str, source: str) -> bytes:
    try:
        raw = text.encode("latin-1")
    except UnicodeEncodeError as exc:
        raise MtnError(source, None, f"{what} {text!r} is not latin-1") from exc
    if len(raw) > 255:
        raise MtnError(source, None, f"{what} is {len(raw)} bytes, a pstring holds at most 255")
    return bytes([len(raw)]) + raw


def _section(number: int, body: bytes) -> bytes:
    body += b"\0" * (-(8 + len(body)) % 4)
    return struct.pack("<II", number, 8 + len(body)) + body


def serialize_mtn(motion: Motion) -> bytes:
    """The bytes of ``motion`` as an MTN v1.2 file (zero padding, minimal section sizes)."""
    m, src = motion, motion.name
    n, j = m.keyframes.shape
    checks = [
        (n > 0xFFFF, f"{n} keyframes, at most 65535"),
        (j > 0xFFFF, f"{j} joints, at most 65535"),
        (not 0 < m.frame_time_ms <= 0xFFFF, f"frame time {m.frame_time_ms} ms not in 1..65535"),
        (not 0 <= m.option <= 0xFFFFFFFF, f"option {m.option} is not a u32"),
        (
            m.interpolate.size > 0 and not 0 <= int(m.interpolate.min()) <= int(m.interpolate.max()) <= _S32_MAX,
            "interpolation count out of 0..2^31-1",
        ),
    ]
    for arr, what in ((m.keyframes, "joint value"), (m.attitudes, "attitude")):
        checks.append((bool(((arr < _S32_MIN) | (arr > _S32_MAX)).any()), f"{what} out of the s32 range"))
    _check(src, checks)

    sec0 = struct.pack("<IIIHHHHI", 0, SECTION0_SIZE, NUM_SECTIONS, *VERSION, n, m.frame_time_ms, m.option)
    strings = ((m.name, "name"), (m.creator, "creator"), (m.design, "design"))
    sec1 = _section(1, b"".join(_pstring(text, what, src) for text, what in strings))
    sec2 = _section(2, struct.pack("<H", j) + b"".join(_pstring(loc, "locator", src) for loc in m.locators))
    rows = np.empty((n, 4 + j), dtype="<i4")
    rows[:, 0] = 0
    rows[1:, 0] = m.interpolate
    rows[:, 1:4] = m.attitudes
    rows[:, 4:] = m.keyframes
    body = rows.tobytes()[4:]  # keyframe 0 has no interpolation word
    sec3 = struct.pack("<III", 3, 12 + len(body), 0) + body
    return MAGIC + sec0 + sec1 + sec2 + sec3


def write_mtn(motion: Motion, path: str | os.PathLike) -> None:
    """Write ``motion`` to ``path`` whole or not at all (``files.write_file_atomic``: the bytes
    built first, then a temporary file, on the disk, renamed over ``path``; never through a link
    at it, while a link to a folder on its way is followed: ``files.named_file``)."""
    if not isinstance(motion, Motion):
        raise TypeError(f"write_mtn: the motion must be a Motion, not {type(motion).__name__}")
    write_file_atomic(named_file(path), serialize_mtn(motion), durable=True)


# ----------------------------------------------------------------------------- playback


def _trunc_div(a: np.ndarray, b: int) -> np.ndarray:
    """C integer division (truncates toward zero), unlike Python's floor division."""
    return np.sign(a) * (np.abs(a) // b)


class MotionPlayer:
    """Joint targets of a motion as a function of time, in one of two modes.

    ``mode="openr"`` (Sony ``MTN.cc``): 8 ms sub-frames. Segment k -> k+1 with numInterpolate n
    has s = (n+1)*frame_time/8 sub-frames (2n+2 at 16 ms); sub-frame i (0..s-1) commands
    ``v0 + i*delta`` with ``delta = (v1-v0)/s`` truncated toward zero. One more frame, the last
    keyframe exactly, ends the motion at ``t = length_ms``. Random access: :meth:`frame`,
    :meth:`targets_rad_at`, iteration.

    ``mode="webots"`` (WB-MTN ``mtn_step``): call :meth:`step` once per control step. Playing
    starts at construction (as after ``mtn_play``).
    """

    def __init__(self, motion: Motion, mode: str = "openr"):
        if mode not in MODES:
            raise ValueError(f"mode must be 'openr' or 'webots', not {mode!r}")
        self.motion, self.mode = motion, mode
        check_playable(motion, mode)
        if mode == "openr":
            self._subframes = (motion.interpolate + 1) * (motion.frame_time_ms // SUBFRAME_MS)
            self._start = np.concatenate(([0], np.cumsum(self._subframes)))  # segment k starts at _start[k]
            kf = motion.keyframes
            self._delta = _trunc_div(kf[1:] - kf[:-1], self._subframes[:, None]) if len(kf) > 1 else kf[:0]
        self._key = 0  # webots state
        self._key_time = 0
        self._time = 0
        self._over = False

    # -- OPEN-R mode
    @property
    def num_frames(self) -> int:
        """Number of 8 ms frames, the final keyframe included (= length_ms/8 + 1)."""
        self._need("openr")
        return int(self._start[-1]) + 1

    def frame(self, i: int) -> np.ndarray:
        """Target of 8 ms frame ``i`` (time ``8*i`` ms), (J,) int64 micro-radians."""
        self._need("openr")
        i = operator.index(i)  # a TypeError for 1.5: frames are whole
        if not 0 <= i < self.num_frames:
            raise IndexError(f"frame {i} out of 0..{self.num_frames - 1}")
        k = int(np.searchsorted(self._start, i, side="right")) - 1
        if k >= self.motion.num_keyframes - 1:
            return self.motion.keyframes[-1].copy()
        return self.motion.keyframes[k] + (i - int(self._start[k])) * self._delta[k]

    def __iter__(self) -> Iterator[np.ndarray]:
        self._need("openr")
        return (self.frame(i) for i in range(self.num_frames))

    def targets_rad_at(self, t_ms: float) -> np.ndarray:
        """Target in radians at time ``t_ms``: the 8 ms frame in force then (held before 0 and
        after the end); a ValueError for NaN."""
        if math.isnan(t_ms):
            raise ValueError("t_ms must be a number of ms, not nan")
        t_ms = min(max(t_ms, 0), (self.num_frames - 1) * SUBFRAME_MS)  # before //: inf // 8 is nan
        i = int(t_ms // SUBFRAME_MS)
        return self.frame(i) / 1e6

    # -- Webots mode
    def step(self, ms: int) -> dict[str, float] | None:
        """One ``mtn_step(ms)``: the commands issued (locator -> rad) or None."""
        self._need("webots")
        if not ms >= 0 or not math.isfinite(ms):  # NaN too: the motion would never end
            raise ValueError(f"ms must be a finite number >= 0, not {ms!r}")
        if self._over:
            return None
        m = self.motion
        commands = None
        if self._key_time == 0:
            commands = dict(zip(m.locators, (m.keyframes[self._key] / 1e6).tolist()))
        self._key_time += ms
        self._time += ms
        length = int(m.segment_ms[self._key]) if self._key < m.num_keyframes - 1 else 0
        if self._key_time >= length:
            self._key += 1
            self._key_time = 0
            if self._key >= m.num_keyframes:
                self._key, self._time, self._over = 0, 0, True
        return commands

    def play(self) -> None:
        """Start again after the motion is over (Webots ``mtn_play`` on a finished MTN)."""
        self._need("webots")
        self._over = False

    @property
    def is_over(self) -> bool:
        """Whether the motion has played to its end (Webots mode only)."""
        self._need("webots")
        return self._over

    @property
    def time_ms(self) -> int:
        """``mtn_get_time``: ms passed to :meth:`step` since the start; 0 again once over."""
        self._need("webots")
        return self._time

    @property
    def length_ms(self) -> int:
        """The motion's total length in ms (``Motion.length_ms``)."""
        return self.motion.length_ms

    def _need(self, mode: str) -> None:
        if self.mode != mode:
            raise AttributeError(f"not available in {self.mode!r} mode (needs {mode!r})")


# ----------------------------------------------------------------------------- Webots-style API


def check_playable(motion: Motion, mode: str) -> None:
    """MtnError naming the file where ``mode`` cannot play ``motion``: OPEN-R's 8 ms frames need a
    frame time that is a whole number of them."""
    if mode == "openr" and motion.frame_time_ms % SUBFRAME_MS:
        raise MtnError(
            motion.source, None, f"frame time {motion.frame_time_ms} ms is not a multiple of {SUBFRAME_MS} ms"
        )


def mtn_new(path: str | os.PathLike, available_locators: Iterable[str] | None = None, mode: str = "openr") -> Motion:
    """Webots ``mtn_new``: read ``path`` and check every locator names a device of the robot
    (default: ``ers7.all_locators()``) and is a joint, and that ``mode`` can play it
    (:func:`check_playable`). Failures raise :class:`MtnError` (a controller's robot keeps the
    last for ``mtn_get_error``); Webots' own texts are used ("File not found: <path>",
    "Missing device in model: <locator>", without Webots' trailing newline), with the path or
    locator as :func:`printable` shows it (a path cut to ``NAME_LIMIT`` characters). A
    ``path`` that is not a str or path-like is an MtnError naming it."""
    if not isinstance(path, (str, os.PathLike)):
        text = repr(path)
        raise MtnError(
            None,
            None,
            f"mtn_new({printable(text, 60)}): the file name must be a str or a path, not {type(path).__name__}",
        )
    try:
        motion = read_mtn(path)
    except OSError as exc:
        raise MtnError(None, None, f"File not found: {printable(os.fspath(path), NAME_LIMIT)}") from exc
    if available_locators is None:
        available_locators = ers7.all_locators()
    available = set(available_locators)
    for loc in motion.locators:
        if loc not in available:
            raise MtnError(
                None,
                None,
                f"Missing device in model: {printable(loc)}"
                + (f" ({other})" if (other := another_robot(motion)) else ""),
            )
        check_joint(loc)
    check_playable(motion, mode)
    return motion


def another_robot(motion: Motion) -> str:
    """For a motion whose design is not the ERS-7's, the clause an error about its joints gives
    ("a motion for DRX-900, the ERS-210/220, not the ERS-7's DRX-1000"); "" otherwise."""
    if motion.design == ERS7_DESIGN:
        return ""
    model = OTHER_DESIGNS.get(motion.design)
    design = printable(motion.design) + (f", the {model}" if model else "")
    return f"a motion for {design}, not the ERS-7's {ERS7_DESIGN}"


def check_joint(locator: str, source: str | None = None) -> None:
    """MtnError unless ``locator`` is a joint's (a motion moves joints only)."""
    if locator not in ers7.JOINT_BY_LOCATOR:
        raise MtnError(source, None, f"Not a joint: {printable(locator)} (a motion moves joints only)")


# ----------------------------------------------------------------------------- info


def motion_info(motion: Motion) -> dict:
    """Summary for ``aibo-sim mtn info`` (JSON-serialisable)."""
    return {
        "name": motion.name,
        "creator": motion.creator,
        "design": motion.design,
        "frame_time_ms": motion.frame_time_ms,
        "num_keyframes": motion.num_keyframes,
        "length_ms": motion.length_ms,
        "locators": list(motion.locators),
    }


def printable(text: str, limit: int | None = None) -> str:
    """``text`` safe to print on a terminal: control and other non-printable characters (an
    MTN's latin-1 strings may hold any byte) escaped as Python escapes them (ESC as ``\\x1b``,
    a newline as ``\\n``); cut to ``limit`` characters with a note of the full length."""
    text = str(text)
    cut = limit is not None and len(text) > limit
    shown = text[:limit] if cut else text
    if not shown.isprintable():
        shown = "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in shown)
    return f"{shown}... ({len(text)} characters)" if cut else shown


NAME_LIMIT = 200  # characters of a file name quoted in an mtn_new error


def format_motion_info(info: dict) -> str:
    """Human-readable form of :func:`motion_info`; the strings as :func:`printable` shows them."""
    lines = [
        f"name:        {printable(info['name'])}",
        f"creator:     {printable(info['creator'])}",
        f"design:      {printable(info['design'])}",
        f"frame time:  {info['frame_time_ms']} ms",
        f"keyframes:   {info['num_keyframes']}",
        f"length:      {info['length_ms']} ms ({info['length_ms'] / 1000:.3f} s)",
        f"joints:      {len(info['locators'])}",
    ]
    lines += [f"  {i:2d} {printable(loc)}" for i, loc in enumerate(info["locators"])]
    return "\n".join(lines)
