"""Tests for aibo_sim.mtn: the OMTN v1.2 reader/writer and the two playback modes."""

from __future__ import annotations

import json
import os
import random
import re
import signal
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from aibo_sim import ers7
from aibo_sim.cli import main
from aibo_sim.motions import play_motion
from aibo_sim.mtn import (
    MAX_JOINT_URAD,
    MAX_LENGTH_MS,
    Motion,
    MotionPlayer,
    MtnError,
    format_motion_info,
    motion_info,
    mtn_new,
    oda_motions,
    parse_mtn,
    read_mtn,
    read_oda_motion,
    serialize_mtn,
    write_mtn,
)

MTN_DIR = Path(__file__).resolve().parents[2] / "shared" / "data" / "mtn"
SONY_MOTIONS = (  # MoNet's archive of Sony's ERS-7 motions (test data)
    Path(__file__).resolve().parents[2] / "shared/data/openr-samples/common/MoNet/MS/OPEN-R/MW/DATA/P/ERS-7/MOTION7.ODA"
)
JOINT_LOCATORS = tuple(j.locator for j in ers7.JOINTS)

# file -> (name, creator, keyframes, length in ms). Lengths: (N-1) segments x 16 ms (all n = 0).
REAL = {
    "SWSDK.MTN": ("a_stand#walk_sox_sdk", "Sony Corporatio", 81, 1280),
    "WSSDK.MTN": ("a_walk#stand_sox_sdk", "Sony Corporatio", 81, 1280),
    "SITDANCE.MTN": ("a_sit#sit_SIT_DANCE1", "AiboPet Editor23", 1771, 28320),
}


def real_path(name: str) -> Path:
    path = MTN_DIR / name
    if not path.is_file():
        pytest.skip(f"real MTN file not available: {path}")
    return path


# ----------------------------------------------------------------------------- real files


@pytest.mark.parametrize("fname", sorted(REAL))
def test_real_file_header(fname):
    name, creator, nkey, length = REAL[fname]
    m = read_mtn(real_path(fname))
    assert (m.name, m.creator, m.design) == (name, creator, "DRX-1000")
    assert m.num_keyframes == nkey and m.keyframes.shape == (nkey, 20)
    assert m.attitudes.shape == (nkey, 3) and m.interpolate.shape == (nkey - 1,)
    assert m.frame_time_ms == 16 and m.option == 0
    assert m.length_ms == length
    assert m.locators == JOINT_LOCATORS


@pytest.mark.parametrize("fname", sorted(REAL))
def test_real_file_round_trip_is_byte_exact(fname, tmp_path):
    raw = real_path(fname).read_bytes()
    m = parse_mtn(raw, fname)
    assert serialize_mtn(m) == raw
    write_mtn(m, tmp_path / fname)
    assert (tmp_path / fname).read_bytes() == raw
    assert read_mtn(tmp_path / fname) == m


# (offset, raw bytes as shown by xxd, keyframe index, joint index, value in µrad).
# Section 3 starts at 0x24c (28 + 56 + 504); keyframe 0 at 0x258: roll, pitch, yaw, then
# 20 joints at 0x264 + 4*j; each later keyframe is 96 bytes on (4-byte count + 92).
HAND_DECODED = {
    "SWSDK.MTN": [
        (0x27C, "3c56fdff", 0, 6, -174532),  # LF J1, -10 deg
        (0x284, "4efd0700", 0, 8, 523598),  # LF J3, 30 deg
        (0x290, "6ca80600", 0, 11, 436332),  # LH J3, 25 deg
    ],
    "SITDANCE.MTN": [
        (0x264, "ed58f5ff", 0, 0, -698131),  # neck tilt, -40 deg
        (0x26C, "e2540100", 0, 2, 87266),  # head tilt, 5 deg
        (0x270, "1eabfeff", 0, 3, -87266),  # mouth, -5 deg
        (0x29A68, "764b1d00", 1770, 17, 1919862),  # last keyframe (0x29a18), RH J3, 110 deg
        (0x29A6C, "e2540100", 1770, 18, 87266),  # last keyframe, tail tilt
    ],
}


@pytest.mark.parametrize("fname", sorted(HAND_DECODED))
def test_real_file_values_match_hand_decoded_bytes(fname):
    raw = real_path(fname).read_bytes()
    m = parse_mtn(raw, fname)
    for offset, hexbytes, k, j, value in HAND_DECODED[fname]:
        assert raw[offset : offset + 4] == bytes.fromhex(hexbytes)
        assert m.keyframes[k, j] == value
    # SWSDK: the first interpolation count sits at 0x2b4 (0x258 + 92) and is 0.
    if fname == "SWSDK.MTN":
        assert raw[0x2B4:0x2B8] == bytes(4) and m.interpolate[0] == 0
        assert np.allclose(m.positions_rad()[0, 8], 0.523598)


def test_motion_info_and_format():
    info = motion_info(read_mtn(real_path("SITDANCE.MTN")))
    assert info == json.loads(json.dumps(info))
    assert info["name"] == "a_sit#sit_SIT_DANCE1" and info["num_keyframes"] == 1771
    assert info["length_ms"] == 28320 and info["frame_time_ms"] == 16
    assert info["locators"] == list(JOINT_LOCATORS)
    text = format_motion_info(info)
    assert "a_sit#sit_SIT_DANCE1" in text and "28320 ms" in text and JOINT_LOCATORS[-1] in text


# ----------------------------------------------------------------------------- tiny hand-built file


def tiny_motion() -> Motion:
    return Motion(
        name="walk",
        creator="me",
        design="DRX-1000",
        frame_time_ms=16,
        locators=("a", "bc"),
        keyframes=[[1, -2], [3, 4]],
        attitudes=[[5, 6, 7], [0, 0, -1]],
        interpolate=[2],
    )


TINY = bytes.fromhex(
    "4f4d544e"  # 0   "OMTN"
    # 4   sec0: num 0, size 24, 4 sections, v1.2, 2 keyframes, 16 ms, option
    "00000000 18000000 04000000 0100 0200 0200 1000 00000000"
    "01000000 1c000000"  # 28  sec1: num 1, size 28 = 8 + 17 + 3 padding
    "04 77616c6b 02 6d65 08 4452582d31303030 000000"  # 36  "walk", "me", "DRX-1000", pad
    "02000000 10000000 0200"  # 56  sec2: num 2, size 16 = 8 + 7 + 1 padding; 2 joints
    "01 61 02 6263 00"  # 66  "a", "bc", pad
    "03000000 38000000 00000000"  # 72  sec3: num 3, size 56 = 12 + 2*20 + 4, dataType 0
    "05000000 06000000 07000000 01000000 feffffff"  # 84  keyframe 0: roll 5 pitch 6 yaw 7, joints 1, -2
    "02000000"  # 104 numInterpolate 2
    "00000000 00000000 ffffffff 03000000 04000000"  # 108 keyframe 1: yaw -1, joints 3, 4
)  # 128 bytes


def test_serialize_tiny_matches_hand_written_bytes():
    assert len(TINY) == 128
    assert serialize_mtn(tiny_motion()) == TINY
    m = parse_mtn(TINY, "tiny")
    assert m == tiny_motion()
    assert m.length_ms == 48  # (2 + 1) * 16


def _patch(data: bytes, offset: int, fmt: str, value) -> bytes:
    out = bytearray(data)
    struct.pack_into(fmt, out, offset, value)
    return bytes(out)


BAD_TINY = {
    "wrong magic": (b"OMTX" + TINY[4:], 0),
    "truncated magic": (TINY[:3], 0),
    "section 0 cut short": (TINY[:20], 4),
    "zero keyframes": (_patch(TINY, 20, "<H", 0), 20),
    "frame rate 0": (_patch(TINY, 22, "<H", 0), 22),
    "section 1 overruns file": (_patch(TINY, 32, "<I", 0x1000), 32),
    "strings overrun section 1": (_patch(TINY, 32, "<I", 16), 44),
    "zero joints": (_patch(TINY, 64, "<H", 0), 64),
    "duplicate locator": (TINY[:66] + bytes.fromhex("0161 0161 00") + TINY[71:], 68),
    "keyframe count vs section 3": (_patch(TINY, 20, "<H", 3), 72),
    "negative interpolation": (_patch(TINY, 104, "<i", -1), 104),
    "truncated section 3": (TINY[:127], 72),
    "section 1 size below its header": (_patch(TINY, 32, "<I", 0), 32),
    "more joints than section 2 holds": (_patch(TINY, 64, "<H", 9), 64),
    "a segment of days": (_patch(TINY, 104, "<i", 2**31 - 1), 104),
    "a frame time that makes it last 11 minutes": (_patch(_patch(TINY, 22, "<H", 0xFFFF), 104, "<i", 9), 104),
    "a joint beyond a full turn": (_patch(TINY, 124, "<i", -(2**31)), 124),
}


# Header fields Sony's MTNFile.cc never reads: a file with other values there plays as it would on the robot.
UNREAD_BY_SONY = {
    "section 0 size": _patch(TINY, 8, "<I", 25),
    "section count": _patch(TINY, 12, "<I", 5),
    "version 1.3": _patch(TINY, 18, "<H", 3),
    "version 2.2": _patch(TINY, 16, "<H", 2),
    "section 0 number": _patch(TINY, 4, "<I", 9),
    "section 1 number": _patch(TINY, 28, "<I", 7),
    "section 3 number": _patch(TINY, 72, "<I", 2),
    "data type": _patch(TINY, 80, "<I", 1),
}


@pytest.mark.parametrize("name", UNREAD_BY_SONY)
def test_header_fields_sony_does_not_read_are_not_checked(name):
    assert parse_mtn(UNREAD_BY_SONY[name], "tiny") == tiny_motion()


def test_a_wrong_joint_count_is_named_from_section_3s_size_field():
    """Section 2 listing one joint fewer than the keyframes hold: keyframe 0's second joint
    value (-2) is read as an interpolation count; the error names the joint count that section
    3's size field fits. A right count adds nothing."""
    with pytest.raises(MtnError) as info:
        parse_mtn(_patch(TINY, 64, "<H", 1), "tiny")
    assert str(info.value) == (
        "tiny: byte 100 (0x64): negative interpolation count -2 before keyframe 1; "
        "section 3's size field fits 2 joints, section 2 lists 1"
    )
    with pytest.raises(MtnError, match=r"before keyframe 1$"):
        parse_mtn(_patch(TINY, 104, "<i", -1), "tiny")


def test_limits_hold_at_their_edges_and_for_motions_built_in_code():
    longest = MAX_LENGTH_MS // 16 - 1  # tiny's one segment lasts n + 1 frames of 16 ms
    assert parse_mtn(_patch(TINY, 104, "<i", longest), "tiny").length_ms == MAX_LENGTH_MS
    with pytest.raises(MtnError, match="longer than the 600 s"):
        parse_mtn(_patch(TINY, 104, "<i", longest + 1), "tiny")
    assert parse_mtn(_patch(TINY, 124, "<i", MAX_JOINT_URAD), "tiny").keyframes[1, 1] == MAX_JOINT_URAD
    with pytest.raises(MtnError, match=r"^walk: keyframe 0, a: -7 rad is beyond a full turn$"):
        Motion("walk", "me", "DRX-1000", 16, ("a",), [[-7_000_000], [0]], np.zeros((2, 3)), [0])


def test_a_motion_too_long_names_the_segment_that_passes_the_limit():
    """37,501 segments of one 16 ms frame each: none is long, the motion passes 600 s in its last."""
    segments = MAX_LENGTH_MS // 16 + 1
    with pytest.raises(MtnError) as info:
        Motion(
            "long",
            "me",
            "DRX-1000",
            16,
            ("a",),
            np.zeros((segments + 1, 1)),
            np.zeros((segments + 1, 3)),
            np.zeros(segments),
        )
    assert str(info.value) == (
        "long: the motion lasts 600 s, longer than the 600 s a motion may last "
        f"(it passes them in segment {segments - 1} -> {segments} of {segments}: numInterpolate 0 of 16 ms frames)"
    )


def test_play_errors_name_the_file(tmp_path):
    path = tmp_path / "odd frame.mtn"
    path.write_bytes(_patch(TINY, 22, "<H", 20))
    with pytest.raises(MtnError, match=r"odd frame\.mtn: frame time 20 ms is not a multiple of 8 ms"):
        MotionPlayer(read_mtn(path))


def test_bytes_after_section_3_are_ignored_as_the_robot_reads():
    assert parse_mtn(TINY + b"\0\xff\0\0", "tiny.mtn") == parse_mtn(TINY, "tiny.mtn")


@pytest.mark.parametrize("minor", [0, 1])
def test_versions_1_0_and_1_1_read_as_1_2_and_are_written_as_1_2(minor):
    """AIBO MIND's ERS-7 motions are 1.1 and 1.2 in one layout; OPEN-R ignores the field."""
    older = _patch(TINY, 18, "<H", minor)
    assert parse_mtn(older, "tiny") == tiny_motion()
    assert serialize_mtn(parse_mtn(older, "tiny")) == TINY


@pytest.mark.parametrize("size", [0, 60, 392])
def test_section_3_size_field_is_not_read_as_openr_reads(size):
    """OPEN-R's MTNFile and Webots take section 3's layout from the keyframe and joint counts;
    Sony's own MoNet sample sit_lose01 gives a size that fits 20 joints for its 15."""
    assert parse_mtn(_patch(TINY, 76, "<I", size), "tiny") == tiny_motion()


@pytest.mark.parametrize("case", sorted(BAD_TINY))
def test_malformed_tiny_raises_mtn_error_at_offset(case):
    data, offset = BAD_TINY[case]
    with pytest.raises(MtnError) as info:
        parse_mtn(data, "tiny.mtn")
    assert isinstance(info.value, ValueError)
    assert info.value.offset == offset, str(info.value)
    assert str(info.value).startswith(f"tiny.mtn: byte {offset} ")


def test_random_mutations_of_real_file_raise_only_mtn_error():
    path = real_path("SWSDK.MTN")
    raw = path.read_bytes()
    rng = random.Random(20050801)
    # u16/u32 header and size fields, plus the first few interpolation counts.
    fields = [
        (8, "<I"),
        (12, "<I"),
        (16, "<H"),
        (18, "<H"),
        (20, "<H"),
        (22, "<H"),
        (32, "<I"),
        (88, "<I"),
        (92, "<I"),
        (96, "<H"),
        (592, "<I"),
        (596, "<I"),
        (600, "<I"),
        *((0x2B4 + 96 * k, "<I") for k in range(5)),
    ]
    errors = parsed = 0
    for trial in range(360):
        kind = trial % 3
        if kind == 0:
            data = raw[: rng.randrange(len(raw))]
        elif kind == 1:
            data = bytearray(raw)
            for _ in range(rng.randint(1, 4)):
                # bias flips toward the headers, where they matter most
                i = rng.randrange(700) if rng.random() < 0.7 else rng.randrange(len(raw))
                data[i] ^= rng.randrange(1, 256)
            data = bytes(data)
        else:
            offset, fmt = rng.choice(fields)
            limit = 0xFFFF if fmt == "<H" else 0xFFFFFFFF
            old = struct.unpack_from(fmt, raw, offset)[0]
            value = rng.choice([0, 1, limit, old + rng.randint(-8, 8), rng.randrange(limit + 1)]) & limit
            data = _patch(raw, offset, fmt, value)
        try:
            parse_mtn(data, str(path))
            parsed += 1
            assert kind != 0, "a truncated file parsed"
        except MtnError as exc:
            errors += 1
            assert "SWSDK.MTN" in str(exc)
            assert exc.offset is not None and 0 <= exc.offset <= len(data)
    assert errors >= 200 and parsed >= 20  # both paths really exercised


# ----------------------------------------------------------------------------- writing


def test_write_refuses_long_pstring_and_leaves_nothing(tmp_path):
    m = tiny_motion()
    m.name = "x" * 256
    with pytest.raises(MtnError, match="at most 255"):
        write_mtn(m, tmp_path / "long.mtn")
    assert list(tmp_path.iterdir()) == []
    m.name = "x" * 255  # the longest allowed
    write_mtn(m, tmp_path / "ok.mtn")
    assert read_mtn(tmp_path / "ok.mtn").name == m.name


def test_write_failing_midway_leaves_old_file_and_no_temp(tmp_path, monkeypatch):
    target = tmp_path / "motion.mtn"
    target.write_bytes(b"old")

    def broken_fsync(fd):
        raise OSError("disk full")

    monkeypatch.setattr(os, "fsync", broken_fsync)
    with pytest.raises(OSError, match="disk full"):
        write_mtn(tiny_motion(), target)
    assert [p.name for p in tmp_path.iterdir()] == ["motion.mtn"]
    assert target.read_bytes() == b"old"


def test_writing_into_a_missing_folder_is_a_file_not_found_error_naming_the_file(tmp_path):
    target = tmp_path / "missing" / "motion.mtn"
    with pytest.raises(FileNotFoundError, match=rf"^cannot write {re.escape(str(target))}: No such file or directory$"):
        write_mtn(tiny_motion(), target)


def test_serialize_rejects_out_of_range_values():
    m = tiny_motion()
    m.keyframes[0, 0] = 2**31
    with pytest.raises(MtnError, match="s32"):
        serialize_mtn(m)
    with pytest.raises(MtnError, match="not latin-1"):
        serialize_mtn(Motion("ü€", "me", "DRX-1000", 16, ("a",), [[0]], [[0, 0, 0]], []))
    with pytest.raises(MtnError, match="negative interpolation"):
        Motion("bad", "me", "DRX-1000", 16, ("a",), [[0], [1]], np.zeros((2, 3)), [-1])


def test_from_poses():
    poses = np.array([[0.0, 1.0], [0.1234567891, -0.0000005], [0.0, 0.0]])
    m = Motion.from_poses("auth", JOINT_LOCATORS[:2], poses, [16, 48])
    assert m.keyframes.tolist() == [[0, 1000000], [123457, 0], [0, 0]]  # nearest µrad
    assert m.interpolate.tolist() == [0, 2] and m.length_ms == 64
    assert (m.creator, m.design) == ("aibo-sim", "DRX-1000") and not m.attitudes.any()
    assert parse_mtn(serialize_mtn(m)) == m
    assert Motion.from_poses("all", None, np.zeros((2, 20)), 32).locators == JOINT_LOCATORS
    with pytest.raises(MtnError, match="multiples of 16"):
        Motion.from_poses("bad", JOINT_LOCATORS[:2], poses, 24)
    with pytest.raises(MtnError, match="segment durations"):
        Motion.from_poses("bad", JOINT_LOCATORS[:2], poses, [16])


# ----------------------------------------------------------------------------- OPEN-R playback


def two_key(v0, v1, n, frame_time=16) -> Motion:
    j = len(v0)
    return Motion("m", "me", "DRX-1000", frame_time, JOINT_LOCATORS[:j], [v0, v1], np.zeros((2, 3)), [n])


def test_openr_interpolation_truncates_toward_zero():
    # n = 1: 2n+2 = 4 sub-frames of 8 ms, delta = (v1 - v0) / 4 in C integer division.
    # +1001/4 = 250 and -1001/4 = -250 (Python's floor division would give -251).
    p = MotionPlayer(two_key([0, 0, 500], [1001, -1001, 497], 1))
    assert p.num_frames == 5 and p.length_ms == 32
    expected = [[0, 0, 500], [250, -250, 500], [500, -500, 500], [750, -750, 500], [1001, -1001, 497]]
    assert [f.tolist() for f in p] == expected  # 497-500 = -3: delta 0, final keyframe exact
    assert np.allclose(p.targets_rad_at(8.0), [250e-6, -250e-6, 500e-6])
    assert np.allclose(p.targets_rad_at(31.9), [750e-6, -750e-6, 500e-6])
    assert np.allclose(p.targets_rad_at(32), [1001e-6, -1001e-6, 497e-6])
    assert np.allclose(p.targets_rad_at(1e6), p.targets_rad_at(32))
    assert np.array_equal(p.targets_rad_at(-5), p.frame(0) / 1e6)
    with pytest.raises(IndexError):
        p.frame(5)


def test_openr_segments_chain_and_frame_time_scales():
    m = Motion("m", "me", "DRX-1000", 16, JOINT_LOCATORS[:1], [[0], [-7], [93]], np.zeros((3, 3)), [0, 1])
    # segment 0: 2 sub-frames, delta -7/2 = -3; segment 1 starts exactly on -7, delta 100/4 = 25.
    assert [int(f[0]) for f in MotionPlayer(m)] == [0, -3, -7, 18, 43, 68, 93]
    assert m.length_ms == 16 + 32
    # 32 ms frames: n = 0 gives 4 sub-frames; 12 ms is not a whole number of sub-frames.
    assert [int(f[0]) for f in MotionPlayer(two_key([0], [-10], 0, frame_time=32))] == [0, -2, -4, -6, -10]
    with pytest.raises(ValueError):
        MotionPlayer(two_key([0], [1], 0, frame_time=12))


def test_openr_real_file_frames():
    m = read_mtn(real_path("SWSDK.MTN"))
    p = MotionPlayer(m, mode="openr")
    assert p.num_frames == 1280 // 8 + 1
    d = m.keyframes[1] - m.keyframes[0]
    assert np.array_equal(p.frame(1), m.keyframes[0] + np.trunc(d / 2).astype(np.int64))
    assert np.array_equal(p.frame(2), m.keyframes[1]) and np.array_equal(p.frame(160), m.keyframes[-1])


# ----------------------------------------------------------------------------- Webots playback


def test_webots_one_keyframe_per_call_and_time_overshoot():
    poses = np.linspace(0.0, 0.71, 72)[:, None] * np.ones((1, 3))
    m = Motion.from_poses("wwfwd-like", JOINT_LOCATORS[:3], poses, 16)
    assert m.length_ms == 71 * 16 == 1136
    p = MotionPlayer(m, mode="webots")
    calls = 0
    while not p.is_over:
        cmd = p.step(64)
        assert cmd is not None and list(cmd) == list(JOINT_LOCATORS[:3])
        assert cmd[JOINT_LOCATORS[0]] == pytest.approx(m.keyframes[calls, 0] / 1e6)
        calls += 1
        if calls == 71:
            assert p.time_ms == 71 * 64 > m.length_ms  # mtn_get_time overshoots mtn_get_length
    assert calls == 72  # 4.6 s of steps for a 1.136 s motion
    assert p.time_ms == 0 and p.step(64) is None and p.is_over
    p.play()
    assert not p.is_over and p.step(64) is not None


def test_webots_commands_only_at_keyframe_start():
    m = Motion("m", "me", "DRX-1000", 16, JOINT_LOCATORS[:1], [[0], [1000000], [2000000]], np.zeros((3, 3)), [0, 1])
    p = MotionPlayer(m, mode="webots")
    got = [p.step(8) for _ in range(8)]
    # keyframe 0 lasts 16 ms (2 calls), keyframe 1 lasts 32 ms (4 calls), the last 0 ms (1 call).
    assert got == [
        {JOINT_LOCATORS[0]: 0.0},
        None,
        {JOINT_LOCATORS[0]: 1.0},
        None,
        None,
        None,
        {JOINT_LOCATORS[0]: 2.0},
        None,
    ]
    assert p.is_over


def test_mode_specific_api():
    p = MotionPlayer(tiny_motion(), mode="webots")
    with pytest.raises(AttributeError):
        p.frame(0)
    with pytest.raises(ValueError):
        MotionPlayer(tiny_motion(), mode="tekkotsu")


# ----------------------------------------------------------------------------- mtn_new


def test_mtn_new_checks_devices(tmp_path):
    path = real_path("SWSDK.MTN")
    assert mtn_new(path).name == "a_stand#walk_sox_sdk"  # every locator is on the robot
    tail_pan = ers7.JOINT_BY_NAME["tail_pan"].locator
    robot = [loc for loc in ers7.all_locators() if loc != tail_pan]
    with pytest.raises(MtnError) as info:
        mtn_new(path, robot)
    assert str(info.value) == f"Missing device in model: {tail_pan}"

    # default device list: a joint the ERS-7 does not have
    odd = tmp_path / "odd.mtn"
    write_mtn(Motion.from_poses("odd", ["PRM:/r7/c1-Joint2:71"], [[0.0]], []), odd)
    with pytest.raises(MtnError, match=r"^Missing device in model: PRM:/r7/c1-Joint2:71$"):
        mtn_new(odd)
    with pytest.raises(MtnError, match="^File not found: "):
        mtn_new(tmp_path / "nope.mtn")


def test_mtn_new_refuses_frames_openr_cannot_play_where_webots_plays_them(tmp_path):
    """OPEN-R plays 8 ms frames: 20 ms keyframes are refused by mtn_new (mtn_get_error gives it),
    not later by mtn_play, which cannot fail in Webots' API; Webots' own player takes them."""
    path = tmp_path / "odd frame.mtn"
    write_mtn(Motion.from_poses("odd", None, np.zeros((2, len(ers7.JOINTS))), 20, frame_time_ms=20), path)
    with pytest.raises(MtnError) as info:
        mtn_new(path)
    assert str(info.value) == f"{path}: frame time 20 ms is not a multiple of 8 ms"
    assert mtn_new(path, mode="webots").frame_time_ms == 20


def test_a_motion_for_another_robot_says_so(tmp_path):
    """Sony's MTN-FFORM: DRX-900 is the ERS-210/220, DRX-1000 the ERS-7; a DRX-900 motion's
    locators are not the ERS-7's. Both the Webots API and mtn play say whose motion it is."""
    path = tmp_path / "sit.mtn"
    locators = ["PRM:/r2/c1-Joint2:j1", "PRM:/r1/c1-Joint2:j1"]
    write_mtn(Motion.from_poses("sit", locators, [[0.0, 0.0]], [], design="DRX-900"), path)
    other = "a motion for DRX-900, the ERS-210/220, not the ERS-7's DRX-1000"
    with pytest.raises(MtnError) as info:
        mtn_new(path)
    assert str(info.value) == f"Missing device in model: {locators[0]} ({other})"
    with pytest.raises(MtnError) as info:
        play_motion(path)
    assert str(info.value) == f"{path}: {other}: no ERS-7 joint for 2 of its 2 locators, such as {locators[0]}"
    write_mtn(Motion.from_poses("sit", locators, [[0.0, 0.0]], [], design="DRX-1000"), path)
    with pytest.raises(MtnError, match=r"^Missing device in model: PRM:/r2/c1-Joint2:j1$"):  # Webots' own text
        mtn_new(path)


def test_mtn_new_refuses_a_device_that_is_not_a_joint(tmp_path):
    """An LED's locator is a device of the robot but nothing a motion can move: refused by
    mtn_new, not left to fail when the motion plays."""
    led = ers7.LEDS[0].locator
    path = tmp_path / "led.mtn"
    write_mtn(Motion.from_poses("led", [ers7.JOINTS[6].locator, led], [[0.0, 0.0]], []), path)
    with pytest.raises(MtnError) as info:
        mtn_new(path)
    assert str(info.value) == f"Not a joint: {led} (a motion moves joints only)"


# ----------------------------------------------------------------------------- what is not a regular file


@pytest.fixture
def no_hang():
    """Fail a test that blocks (on a FIFO's open) instead of hanging the run."""

    def hung(signum, frame):
        raise TimeoutError("blocked for 10 s")

    previous = signal.signal(signal.SIGALRM, hung)
    signal.alarm(10)
    yield
    signal.alarm(0)
    signal.signal(signal.SIGALRM, previous)


def test_a_fifo_or_a_folder_is_refused_at_once_by_every_reader(tmp_path, no_hang):
    fifo = tmp_path / "fifo.MTN"
    os.mkfifo(fifo)
    for read in (read_mtn, mtn_new, play_motion):
        with pytest.raises(MtnError) as info:
            read(fifo)
        assert str(info.value) == f"{fifo}: a FIFO, not a regular file"
    with pytest.raises(MtnError) as info:
        read_mtn(tmp_path)
    assert str(info.value) == f"{tmp_path}: a folder, not a regular file"


def test_an_empty_name_is_a_missing_file_not_the_current_folder():
    with pytest.raises(FileNotFoundError):
        read_mtn("")
    with pytest.raises(MtnError, match="^File not found: $"):
        mtn_new("")


@pytest.mark.slow
@pytest.mark.parametrize("command", ["info", "play"])
@pytest.mark.parametrize("special", ["fifo", "/dev/zero"])
def test_the_cli_refuses_a_fifo_or_a_device_in_one_line(tmp_path, command, special):
    """Not waited on (a FIFO) nor read without end (a device): exit 2 at once."""
    if special == "fifo":
        special = str(tmp_path / "fifo.MTN")
        os.mkfifo(special)
    done = subprocess.run(
        [sys.executable, "-m", "aibo_sim.cli", "mtn", command, special], capture_output=True, text=True, timeout=60
    )
    kind = "a FIFO" if special.endswith("fifo.MTN") else "a device"
    assert (done.returncode, done.stdout, done.stderr) == (
        2,
        "",
        f"aibo-sim: error: {special}: {kind}, not a regular file\n",
    )


def test_play_escapes_a_locator_that_is_not_a_joint(tmp_path):
    path = tmp_path / "b\x1bd.mtn"
    write_mtn(Motion.from_poses("bogus", [ers7.JOINTS[6].locator, "BOGUS\x1b[31mRED"], [[0.0, 0.0]], []), path)
    with pytest.raises(MtnError) as info:
        play_motion(path)
    assert str(info.value) == f"{tmp_path}/b\\x1bd.mtn: no joint for locator(s) BOGUS\\x1b[31mRED"


def test_info_escapes_what_the_terminals_encoding_lacks(tmp_path):
    """A motion's latin-1 name on an ASCII terminal: shown escaped, not a codec error and exit 2."""
    path = tmp_path / "cafe.mtn"
    write_mtn(Motion.from_poses("caf\xe9", None, [[0.0] * len(ers7.JOINTS)], []), path)
    done = subprocess.run(
        [sys.executable, "-m", "aibo_sim.cli", "mtn", "info", str(path)],
        capture_output=True,
        env={**os.environ, "PYTHONIOENCODING": "ascii"},
        timeout=60,
    )
    assert (done.returncode, done.stderr) == (0, b"")
    assert done.stdout.splitlines()[0] == rb"name:        caf\xe9"


# ----------------------------------------------------------------------------- ODA archives


def oda(entries: list[tuple[bytes, str, bytes]]) -> bytes:
    """An ODA archive as Sony's ODA.h lays it out: the header, 144-byte entries, then the data."""
    table = struct.pack("<4sIII48x", b"ODAR", 0x30000, len(entries), 144)
    data, offset = b"", 64 + 144 * len(entries)
    for kind, name, body in entries:
        table += struct.pack("<4s128sII4x", kind, name.encode(), offset + len(data), len(body))
        data += body
    return table + data


def test_a_motion_is_read_from_an_oda_archive_by_its_name(tmp_path):
    archive = tmp_path / "MOTION7.ODA"
    archive.write_bytes(oda([(b"WAVE", "beep", b"RIFF...."), (b"OMTN", "a_sit#tiny", TINY)]))
    assert oda_motions(archive.read_bytes()) == {"a_sit#tiny": TINY}  # the sound is not a motion
    motion = read_oda_motion(archive, "a_sit#tiny")
    assert motion == tiny_motion() and motion.source == f"{archive}:a_sit#tiny"
    with pytest.raises(
        MtnError, match=r"MOTION7\.ODA: an ODA archive: name one of its motions .*it holds 1: a_sit#tiny$"
    ):
        read_oda_motion(archive, None)
    with pytest.raises(MtnError, match=r"no motion 'beep' .*it holds 1: a_sit#tiny$"):
        read_oda_motion(archive, "beep")
    # Webots' mtn_new and read_mtn read MTN files only, as the memory stick's reader does
    with pytest.raises(MtnError, match=r"byte 0 \(0x0\): wrong magic b'ODAR' \(should be b'OMTN'\)$"):
        read_mtn(archive)
    (tmp_path / "tiny.mtn").write_bytes(TINY)
    with pytest.raises(MtnError, match=r"not an ODA archive \(magic b'OMTN', not b'ODAR'\)"):
        read_oda_motion(tmp_path / "tiny.mtn", "x")
    broken = bytearray(archive.read_bytes())
    struct.pack_into("<I", broken, 64 + 144 + 132, 10_000)  # the motion's offset, beyond the end
    with pytest.raises(MtnError, match=r"ODA entry 1's data \(byte 10000, 128 bytes\) needs 128 bytes"):
        oda_motions(bytes(broken), "broken")


def test_mtn_info_and_play_take_archive_colon_motion(tmp_path, capsys):
    archive = tmp_path / "MOTION7.ODA"
    archive.write_bytes(oda([(b"OMTN", "a_sit#tiny", TINY)]))
    assert main(["mtn", "info", f"{archive}:a_sit#tiny", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["name"] == tiny_motion().name
    assert main(["mtn", "info", str(archive)]) == 2
    assert "an ODA archive: name one of its motions" in capsys.readouterr().err
    other = tmp_path / "SYSMTN.ODA"  # as Sony's system archives, enciphered: no magic of either
    other.write_bytes(b"\x9f\x8c\xda\xc8" + TINY[4:])
    assert main(["mtn", "play", str(other)]) == 2
    assert capsys.readouterr().err.endswith(
        "byte 0 (0x0): wrong magic b'\\x9f\\x8c\\xda\\xc8': "
        "neither an MTN motion (b'OMTN') nor an ODA archive (b'ODAR')\n"
    )


def test_sonys_ers7_motions_in_monets_archive_all_read_and_play():
    if not SONY_MOTIONS.is_file():
        pytest.skip(f"Sony's MoNet archive not available: {SONY_MOTIONS}")
    motions = oda_motions(SONY_MOTIONS.read_bytes(), str(SONY_MOTIONS))
    assert len(motions) == 12 and "a_walk#walk_sox_fwd" in motions
    for name in motions:
        motion = read_oda_motion(SONY_MOTIONS, name)
        assert motion.design == "DRX-1000" and motion.frame_time_ms == 16
        player = MotionPlayer(motion)
        assert np.array_equal(player.frame(player.num_frames - 1), motion.keyframes[-1])
