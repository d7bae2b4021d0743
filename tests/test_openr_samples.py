"""Sony's OPEN-R sample programs, unchanged, built by the host SDK with their own Makefiles and run
on the simulated ERS-7. They are test data (../shared/data/openr-samples, never in the
repository): these tests skip without them."""

import math
import re
import shutil
import wave

import cv2
import numpy as np
import pytest
from openr_support import SAMPLES, make, run_stick

import openr_bridge
from aibo_sim import ers7
from aibo_sim.openr import host

pytestmark = [
    pytest.mark.skipif(not SAMPLES.is_dir(), reason="Sony's OPEN-R samples not present (../shared/data)"),
    pytest.mark.slow,  # heavy: run by CI and by python -m pytest -m slow
]
PROGRAMS = (
    "common/HelloWorld",
    "common/ObjectComm",
    "common/ImageObserver",
    "ers7/BlinkingLED7",
    "ers7/MovingHead7",
    "ers7/SensorObserver7",
    "ers7/BallTrackingHead7",
)


@pytest.fixture(scope="module")
def samples(tmp_path_factory):
    """A copy of the samples, each program built and installed into its MS folder."""
    root = tmp_path_factory.mktemp("samples") / "openr-samples"
    shutil.copytree(SAMPLES, root)
    for program in PROGRAMS:
        (root / program / "MS" / "OPEN-R" / "MW" / "OBJS").mkdir(parents=True, exist_ok=True)
        make(root / program, "install")
    return root


def head_joints(run):
    return run.sim.servos.command[[ers7.JOINT_INDEX[n] for n in ("neck_tilt", "head_pan", "head_tilt")]].copy()


def test_hello_world_prints_at_start_and_logs_at_stop(samples, tmp_path):
    result = run_stick(samples / "common/HelloWorld/MS", 0.2, tmp_path)
    assert result.console.splitlines() == [
        "[    0.000 s] HELLO: !!! Hello World !!!",
        "[    0.200 s] HELLO: [ERROR] Bye Bye ...",
    ]


def test_object_comm_observer_receives_what_its_subject_sent(samples, tmp_path):
    result = run_stick(samples / "common/ObjectComm/MS", 0.1, tmp_path)
    assert result.lines("SampleObserver") == [
        "SampleObserver::Notify() !!! Hello world !!!",
        "SampleObserver::Notify() !!! Hello world again !!!",
    ]
    assert result.lines("SampleSubject") == ["SampleSubject::Ready() : ASSERT READY"] * 3 + [
        "SampleSubject::Ready() : DEASSERT READY"
    ]  # its observer's DoStop


def test_blinking_led7_powers_the_motors_blinks_its_leds_and_flaps_the_ears(samples, tmp_path):
    """The head's LED2 lights follow BlinkingHeadLED's table, 64 frames an entry; MovingEar7 raises
    the left ear for the first 16 frames of each 4.096 s cycle, the right one 2.048 s later."""
    header = (samples / "ers7/BlinkingLED7/BlinkingHeadLED/BlinkingHeadLED.h").read_text()
    locators = re.findall(r'"(PRM:/[^"]+LED2[^"]+)"', header)
    table = [re.findall(r"oled(ON|OFF)", row) for row in re.findall(r"\{ (oled[^}]+)\}", header)]
    names = [ers7.LED_BY_LOCATOR[locator].name for locator in locators]
    ears = [ers7.JOINT_INDEX["ear_l"], ers7.JOINT_INDEX["ear_r"]]

    def record(run):
        lit = [run.sim.model.geom_rgba[run.sim.model.geom(name).id, :3].max() > 0.5 for name in names]
        return lit, run.sim.servos.command[ears] > 0, run._powered

    frames = run_stick(samples / "ers7/BlinkingLED7/MS", 4.2, tmp_path, record).frames
    assert len(table) == len(names) == 6 and all(len(row) == 8 for row in table)
    for tick, (lit, ears_up, powered) in enumerate(frames):
        assert powered
        assert lit == [row[tick // 64 % 8] == "ON" for row in table], tick
        assert list(ears_up) == [tick % 512 < 16, 256 <= tick % 512 < 256 + 16], tick


def test_moving_head7_moves_the_head_to_zero_then_swings_it(samples, tmp_path):
    """MovingHead7's set-points: 16 vectors of 16 frames to the zero posture, then the pan at
    80 sin(2 pi k / 2048) degrees (k: frames since the swing began), in OPEN-R's micro-radians."""
    result = run_stick(
        samples / "ers7/MovingHead7/MS", 7.0, tmp_path, lambda r: (head_joints(r), r.sim.joint_positions())
    )
    commands = np.array([c for c, _ in result.frames])
    start = int(np.flatnonzero((commands == 0).all(axis=1))[0])  # the swing's first frame: all three at 0
    assert start == 17 * 16  # after the first vector (the current posture) and 16 to the zero posture
    assert np.abs(np.degrees(commands[start - 1])).max() < 0.5  # the zero posture's last frame, nearly there
    for k, (tilt1, pan, tilt2) in enumerate(commands[start:]):
        micro = int(math.radians(80 * math.sin(2 * math.pi * k / 2048)) * 1e6)
        assert (tilt1, tilt2) == (0, 0) and round(pan * 1e6) == micro, k
    positions = np.degrees(np.array([p for _, p in result.frames]))
    pan = ers7.JOINT_INDEX["head_pan"]
    assert positions[start + 512, pan] > 75  # a quarter period on, the head is near 80 degrees


def test_sensor_observer7_prints_the_simulators_sensors(samples, tmp_path):
    """Its console shows each sensor's value and signal, four frames a vector, as the simulator
    gave them (it also asks "Hit return key> " and reads standard input after each vector)."""
    values = {}  # tick -> (value, signal) of each entry sent for that frame
    original = host.SensorFrame.at

    def at(self, tick):
        data = original(self, tick)
        values[tick] = np.frombuffer(data, np.int32).reshape(-1, 4)[:, :2].copy()
        return data

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(host.SensorFrame, "at", at)
        result = run_stick(samples / "ers7/SensorObserver7/MS", 0.1, tmp_path)
    lines = result.lines("SensorObserver7")
    vectors = [i for i, line in enumerate(lines) if "ERS-7 numData" in line]
    assert len(vectors) == 3 and lines[vectors[0]] == "ERS-7 numData 34 frameNumber 0"
    assert lines[vectors[1]] == "Hit return key> ERS-7 numData 34 frameNumber 4"
    checked = 0
    for start, end in zip(vectors, [*vectors[1:], len(lines)]):
        first = int(lines[start].split()[-1])
        for line, following in zip(lines[start:end], lines[start + 1 : end]):
            match = re.search(r"\| \[\s*(\d+)\] val\s+(-?\d+) (-?\d+) (-?\d+) (-?\d+)", line)
            if not match:
                continue
            entry, printed = int(match[1]), [int(v) for v in match.groups()[1:]]
            assert printed == [values[first + f][entry, 0] for f in range(4)], line
            signal = [int(v) for v in following.split("sig")[1].split()]
            assert signal == [values[first + f][entry, 1] for f in range(4)], following
            checked += 1
    assert checked == 3 * 34  # every entry of each vector


def test_image_observer_saves_layer_h_as_the_frame_has_it(samples, tmp_path):
    stick = samples / "common/ImageObserver/MS"
    (stick / "OPEN-R/MW/DATA/P").mkdir(parents=True, exist_ok=True)
    result = run_stick(stick, 0.2, tmp_path)
    saved = stick / "OPEN-R/MW/DATA/P"
    first = result.images[0].message
    layer_h = first.GetData(openr_bridge.ofbkimageLAYER_H)
    assert (saved / "LAYER_H.RAW").read_bytes() == bytes(layer_h)
    bands = [
        first.band(openr_bridge.ofbkimageLAYER_H, b)
        for b in (openr_bridge.ofbkimageBAND_Y, openr_bridge.ofbkimageBAND_Cr, openr_bridge.ofbkimageBAND_Cb)
    ]
    bmp = cv2.imread(str(saved / "LAYER_H.BMP"), cv2.IMREAD_COLOR)[:, :, ::-1]
    assert np.array_equal(bmp, openr_bridge.ycrcb_to_rgb(*bands))
    for name, frame, layer in (
        ("LAYER_M.BMP", 1, openr_bridge.ofbkimageLAYER_M),
        ("LAYER_L.BMP", 2, openr_bridge.ofbkimageLAYER_L),
    ):
        message = result.images[frame].message
        expected = openr_bridge.ycrcb_to_rgb(
            *(
                message.band(layer, b)
                for b in (openr_bridge.ofbkimageBAND_Y, openr_bridge.ofbkimageBAND_Cr, openr_bridge.ofbkimageBAND_Cb)
            )
        )
        assert np.array_equal(cv2.imread(str(saved / name), cv2.IMREAD_COLOR)[:, :, ::-1], expected), name
    tags = [line for line in result.lines("ImageObserver") if line.startswith("FrameNumber")]
    assert tags[0] == f"FrameNumber {result.images[5].frame_number:x} FieldCounter 5 ColorFreq 0 0 0 0 0 0 0 0 "


def test_ball_tracking_head7_stands_up_and_keeps_the_pink_ball_centred_as_it_rolls(samples, tmp_path):
    """With MoNet, MotionAgents, SoundAgent and PowerMonitor: the limp robot is stood up, the head
    finds Sony's pink ball with Sony's own CDT table on the ers7 camera's frames and keeps it near
    the image centre while it rolls away sideways; the sound it plays on finding it is recorded."""
    push_ms = 15000

    def record(run):
        sim = run.sim
        if run.time_ms == push_ms:
            sim.ball_state()[1][:3] = (0.0, -0.5, 0.0)  # the ball rolls to the robot's right
        offset, visible = sim.camera.image_offset(sim.ball_position())
        return run.time_ms, offset, visible, sim.body_pose()[0][2], sim.ball_position()[1]

    result = run_stick(samples / "ers7/BallTrackingHead7/MS", 17.0, tmp_path, record, ball_type="pink")
    found = next(line for line in result.console.splitlines() if "### BALL FOUND ###" in line)
    found_ms = round(float(found.split("s]")[0].strip("[ ")) * 1000)
    frames = [f for f in result.frames if f[0] >= found_ms + 500]
    assert found_ms < push_ms - 500 and min(f[3] for f in frames) > 0.13  # standing by then
    rolled = frames[0][4] - frames[-1][4]
    assert rolled > 0.1, rolled
    assert all(visible and max(abs(x), abs(y)) < 0.25 for _, (x, y), visible, _, _ in frames)
    with wave.open(str(tmp_path / "speaker.wav")) as sound:
        samples_16k = np.frombuffer(sound.readframes(sound.getnframes()), "<i2")
        assert sound.getframerate() == 16000
    assert np.abs(samples_16k[round(found_ms * 16) :]).max() > 1000  # a sound after the ball was found
