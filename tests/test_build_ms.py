"""aibo_sim.openr.build_ms: a C or C++ controller linked with the Webots OPEN-R wrapper object
(openr_bridge/wrapper), built with the host OPEN-R SDK and run by the host runtime
(MemoryStickRun), against the same controller run by run_controller on the openr backend.

What the memory stick does differently, and what these tests hold it to:
- Latency: sensor values come in vectors of 4 frames every 32 ms, so the wrapper computes the
  controller's frames (samples, run calls, set-points) 4 at a time and its set-points play 4
  frames later than the time the controller saw. The reference runs therefore simulate
  Simulation(command_latency_frames=4); with it, joint trajectories and camera frames are
  identical, bit for bit.
- The end: a run call needs the sensor vector holding its frame, so a stick run of N frames
  (N a multiple of 4) makes the run calls of a reference run of N - 1 frames: their files are
  the same bytes.
- Units: OPEN-R sends joint angles, distances and accelerations in micro-units and takes
  set-points in micro-radians. Motions (whole micro-radians) are exact; a controller computing
  set-points from sensor values (the ball tracker) drifts from the reference by a bounded amount.
"""

import fnmatch
import functools
import gzip
import json
import shutil
import struct
import subprocess
from pathlib import Path

import cv2
import numpy as np
import pytest

from aibo_sim import controller as api
from aibo_sim import ers7, runner
from aibo_sim.cli import main
from aibo_sim.config import WorldConfig
from aibo_sim.mtn import Motion, MtnError, mtn_new, serialize_mtn
from aibo_sim.openr.build_ms import BuildMsError, build_ms, short_name
from aibo_sim.openr.host import MemoryStickRun
from aibo_sim.openr.sdk import sdk_root
from aibo_sim.placement import place
from aibo_sim.robot import DeviceError, Robot
from aibo_sim.sim import Servos, Simulation, load_model, models_dir
from openr_bridge.memory_stick import load_memory_stick
from openr_bridge.wrapper import WRAPPER_SOURCES

pytestmark = pytest.mark.slow  # heavy: run by CI and by python -m pytest -m slow

ROOT = Path(__file__).resolve().parents[1]
ANNEX = ROOT / "controllers" / "annex_capture_c" / "annex_capture_c.cpp"
TRACKER = ROOT / "controllers" / "ball_tracker_c"
WALK = models_dir() / "motions" / "WALKFWD.MTN"
LATENCY_FRAMES = 4
BALL = (0.5, 0.1)  # in view, off-centre: the tracker turns the head

# A C controller that shows what the wrapper gives it; what it does is the line in scenario.txt
# (in its working folder), so that one build serves every case.
PROBE = r"""
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <device/accelerometer.h>
#include <device/camera.h>
#include <device/led.h>
#include <device/mtn.h>
#include <device/robot.h>
#include <device/servo.h>
#include <device/touch_sensor.h>

static char scenario[32];
static DeviceTag camera, accelerometer, paw, joints[128];
static int joint_count, plays, pictures;
static MTN *walk;
static FILE *out;

static void die(void) {
    FILE *file = fopen("died.txt", "w");
    fputs("died\n", file);
    fclose(file);
    if (out) fclose(out);
}

static int is(const char *name) { return strcmp(scenario, name) == 0; }

static void init(void) {
    FILE *file = fopen("scenario.txt", "r");
    if (!file || !fgets(scenario, sizeof scenario, file)) return;
    fclose(file);
    scenario[strcspn(scenario, "\n")] = 0;
    out = fopen("probe.txt", "w");
    if (is("camera")) {
        camera = robot_get_device("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1");
        camera_enable(camera, 32);
        fprintf(out, "%d %d %.9g\n", camera_get_width(camera), camera_get_height(camera), camera_get_fov(camera));
    } else if (is("sensors") || is("torques") || is("devices")) {
        char line[128];
        FILE *list = fopen("locators.txt", "r");
        while (fgets(line, sizeof line, list)) {
            line[strcspn(line, "\n")] = 0;
            joints[joint_count] = robot_get_device(line);
            if (is("devices")) fprintf(out, "%s %d\n", line, joints[joint_count]);
            else if (is("torques")) servo_enable_motor_force_feedback(joints[joint_count], 32);
            else servo_enable_position(joints[joint_count], 32);
            joint_count++;
        }
        fclose(list);
        accelerometer = robot_get_device("PRM:/a1-Sensor:a1");
        paw = robot_get_device("PRM:/r2/c1/c2/c3/c4-Sensor:24");
        accelerometer_enable(accelerometer, 32);
        touch_sensor_enable(paw, 32);
    } else if (is("motion")) {
        walk = mtn_new("walkfwd.mtn");
        mtn_fprint(out, walk);
        fprintf(out, "%d %s\n", mtn_get_length(walk), mtn_get_name(walk));
    } else if (is("bad motions")) {
        static const char *const names[] = {"bad1.mtn", "bad2.mtn", "bad3.mtn", "bad4.mtn", "bad5.mtn", "bad6.mtn",
                                            "bad7.mtn", "bad8.mtn", "bad9.mtn"};
        for (int i = 0; i < 9; i++) fprintf(out, "%s\n", mtn_new(names[i]) ? "loaded" : mtn_get_error());
    } else if (is("leds")) {
        led_set(robot_get_device("PRM:/r1/c1/c2/c3/l2-LED2:l2"), 1);
        led_set(robot_get_device("PRM:/r1/c1/c2/c3/la-LED3:la"), 128);
        led_set(robot_get_device("PRM:/lz-LED3:lz"), 300);
    } else if (is("ear")) {
        servo_set_position(robot_get_device("PRM:/r1/c1/c2/c3/e5-Joint4:15"), 0.26);
    } else if (is("short name")) {
        fprintf(out, "%d\n", mtn_get_length(mtn_new("Walk_Forward.long.mtn")));
    } else if (is("device error")) {
        robot_get_device("no-such-device");
    } else if (is("acceleration")) {
        servo_set_acceleration(robot_get_device("PRM:/r1/c1/c2-Joint2:12"), 0);
    } else if (is("control p")) {
        servo_set_control_p(robot_get_device("PRM:/r1/c1/c2-Joint2:12"), -50);
    } else if (is("ear torque")) {
        servo_enable_motor_force_feedback(robot_get_device("PRM:/r1/c1/c2/c3/e5-Joint4:15"), 32);
    } else if (is("mode")) {
        robot_keyboard_enable(32);
        fprintf(out, "mode %d key %d step %g synchronized %d error [%s]\n", robot_get_mode(), robot_keyboard_get_key(),
                robot_get_basic_time_step(), robot_get_synchronization(), mtn_get_error());
    } else if (is("missing motion")) {
        char name[32];
        sprintf(name, "%s.mtn", "missing");
        MTN *missing = mtn_new(name);
        fprintf(out, "%s\n", mtn_get_error());
        fflush(out);
        mtn_play(missing);
    }
}

static int inner(int ms) {
    fprintf(out, "inner %d %g\n", ms, robot_get_time());
    return 32;
}

static int run(int ms) {
    if (is("zero step")) return 0;
    if (is("exit 0") && ms) exit(0);
    if (is("exit 3") && ms) exit(3);
    if (is("run in run")) {
        fprintf(out, "outer %d %g\n", ms, robot_get_time());
        if (ms) robot_run(inner);
        fprintf(out, "after robot_run\n"); /* never reached after robot_run: it does not return */
        return 64;
    }
    if (is("camera") && ms) {
        fwrite(camera_get_image(camera), 3, camera_get_width(camera) * camera_get_height(camera), out);
        if (++pictures == 10) {  /* the 10th picture as a file; and one where no folder is */
            FILE *saved = fopen("saved.txt", "w");
            int png = camera_save_image(camera, "shot.png", 0), jpeg = camera_save_image(camera, "shot.jpg", 90);
            int gif = camera_save_image(camera, "a.gif", 90), low = camera_save_image(camera, "a.JPEG", 0);
            fprintf(saved, "%d %d %d %d %d\n", png, jpeg, camera_save_image(camera, "no/a.png", 0), gif, low);
            fclose(saved);
        }
    } else if (is("sensors") && ms) {
        for (int j = 0; j < joint_count; j++) fprintf(out, "%.9f ", servo_get_position(joints[j]));
        const float *a = accelerometer_get_values(accelerometer);
        fprintf(out, "%.6f %.6f %.6f %g\n", a[0], a[1], a[2], touch_sensor_get_value(paw));
    } else if (is("torques") && ms) {
        for (int j = 0; j < joint_count; j++) fprintf(out, "%.9f ", servo_get_motor_force_feedback(joints[j]));
        fprintf(out, "\n");
    } else if (is("motion")) {
        if (mtn_is_over(walk) && plays < 2) {
            mtn_play(walk);
            plays++;
        }
        fprintf(out, "%g %d %d\n", robot_get_time(), mtn_is_over(walk), mtn_get_time(walk));
    }
    return 32;
}

int main(void) {
    robot_live(init);
    robot_die(die);
    if (is("step")) robot_step(32);
    robot_run(run);
    if (is("after run")) fclose(fopen("after.txt", "w"));  /* never reached: robot_run does not return */
    return 0;
}
"""


def build(controller: Path, project: Path) -> list[str]:
    """build_ms, then make install with the host SDK; the compiler's warning lines."""
    build_ms(controller, project)
    result = subprocess.run(
        ["make", f"OPENRSDK_ROOT={sdk_root()}", "install"], cwd=project, capture_output=True, text=True
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert (project / "MS" / "OPEN-R" / "MW" / "OBJS" / "CONTROLL.BIN").is_file()
    return [line for line in (result.stdout + result.stderr).splitlines() if "warning:" in line]


class Recorder:
    """Each frame's qpos, ctrl and LED colours, and each camera frame's picture by index."""

    def __init__(self):
        self.qpos, self.ctrl, self.leds, self.frames = [], [], [], {}
        self.sim = None

    def __call__(self, sim) -> None:
        self.sim = sim
        self.qpos.append(sim.data.qpos.copy())
        self.ctrl.append(sim.data.ctrl.copy())
        self.leds.append(sim.model.geom_rgba[[sim.model.geom(name).id for name in ers7.LEDS_BY_GEOM]].copy())
        index = sim.camera_frame_index()
        if index not in self.frames:
            self.frames[index] = sim.camera.frame().rgb.copy()


def run_stick(project: Path, frames: int, workdir: Path, ball=None) -> tuple[Recorder, Simulation, MemoryStickRun]:
    workdir.mkdir(exist_ok=True)
    sim = Simulation()
    place(sim, None, ball)
    run = MemoryStickRun(sim, load_memory_stick(project / "MS"), workdir, log_path=workdir / "console.log")
    run.end_ms = frames * 8
    record = Recorder()
    run.frame_listeners.append(lambda r: record(r.sim))
    run.run()
    return record, sim, run


def run_reference(monkeypatch, controller: Path, frames: int, out: Path, ball=None, workdir=None) -> Recorder:
    """run_controller on the openr backend, the robot's command latency simulated."""
    monkeypatch.setattr(runner, "Simulation", functools.partial(Simulation, command_latency_frames=LATENCY_FRAMES))
    record = Recorder()
    runner.run_controller(
        controller,
        backend="openr",
        duration=frames * 8 / 1000,
        out=out,
        progress=False,
        workdir=workdir,
        frame_listeners=[lambda robot: record(robot.sim)],
        world=WorldConfig(ball=ball),
    )
    monkeypatch.undo()
    return record


def test_annex_i_as_a_memory_stick_runs_as_on_the_openr_backend_bit_for_bit(tmp_path, monkeypatch):
    """The Annex, given the walk it plays (WALKFWD.MTN as its wwfwd.mtn): 15 plays, then image.raw."""
    controller = tmp_path / "annex_capture_c"
    controller.mkdir()
    shutil.copy(ANNEX, controller)
    shutil.copy(WALK, controller / "WWFWD.MTN")
    warnings = build(controller, tmp_path / "project")
    # -Wall: the wrapper is silent; the Annex's own unused variable is the one warning.
    assert len(warnings) == 1 and "controller/annex_capture_c.cpp" in warnings[0] and "head_pan" in warnings[0]
    stick_walk = tmp_path / "project" / "MS" / "OPEN-R" / "MW" / "DATA" / "P" / "WWFWD.MTN"
    assert stick_walk.read_bytes() == WALK.read_bytes()

    frames = 684  # 15 plays of 320 ms at 16 ms steps, then images: a multiple of 4
    stick, _, _ = run_stick(tmp_path / "project", frames, tmp_path / "stick")
    reference = run_reference(monkeypatch, controller, frames - 1, tmp_path / "reference")
    assert len(stick.qpos) == frames and len(reference.qpos) == frames - 1
    assert np.array_equal(np.array(stick.qpos[:-1]), np.array(reference.qpos))
    assert np.array_equal(np.array(stick.ctrl[:-1]), np.array(reference.ctrl))
    assert np.ptp(np.array(reference.ctrl)[:, 6:18], axis=0).min() > 0.1  # every leg joint walked
    assert len(reference.frames) == 164 and all(
        np.array_equal(stick.frames[i], picture) for i, picture in reference.frames.items()
    )
    image = (tmp_path / "stick" / "image.raw").read_bytes()
    assert len(image) == 208 * 160 * 3 and image == (tmp_path / "reference" / "image.raw").read_bytes()


def test_ball_tracker_c_as_a_memory_stick_follows_the_openr_backend_within_a_micro_radian_drift(tmp_path, monkeypatch):
    assert build(TRACKER, tmp_path / "project") == []
    frames = 500
    stick, _, _ = run_stick(tmp_path / "project", frames, tmp_path / "stick", ball=BALL)
    reference = run_reference(monkeypatch, TRACKER, frames - 1, tmp_path / "reference", ball=BALL)
    head = [ers7.JOINT_INDEX[name] for name in ("neck_tilt", "head_pan", "head_tilt")]
    ctrl_stick, ctrl_reference = np.array(stick.ctrl[:-1])[:, head], np.array(reference.ctrl)[:, head]
    moves = np.flatnonzero(np.diff(ctrl_reference, axis=0).any(axis=1))
    # The head moves in the same frames (each 32 ms step, from frame 8: the first step's
    # set-points, 4 frames late), to the micro-radian at first, then within a bounded drift.
    assert moves[0] == 7 and np.array_equal(moves, np.flatnonzero(np.diff(ctrl_stick, axis=0).any(axis=1)))
    assert np.abs(ctrl_stick[:9] - ctrl_reference[:9]).max() <= 0.5e-6
    assert np.abs(ctrl_stick - ctrl_reference).max() < 1e-4
    assert np.abs(np.array(stick.qpos[:-1]) - np.array(reference.qpos)).max() < 1e-4
    assert np.ptp(ctrl_reference[:, 1]) > 0.1  # the head turned to the ball
    # Pictures: the same before the head moves; then the drift moves edges by a pixel here and
    # there (0.2 % of the pixels at most here).
    assert np.array_equal(stick.frames[0], reference.frames[0])
    for index, picture in reference.frames.items():
        assert (stick.frames[index] != picture).any(axis=2).mean() < 0.01


def test_ball_tracker_c_tracks_as_ball_tracker_py(tmp_path):
    """The C port through aibo-sim's C binding against the Python original, same numbers but the
    field of view, a float in the C API."""
    records = []
    for controller in (TRACKER, ROOT / "controllers" / "ball_tracker.py"):
        record = Recorder()
        runner.run_controller(
            controller,
            duration=2.0,
            progress=False,
            frame_listeners=[lambda robot, record=record: record(robot.sim)],
            world=WorldConfig(ball=BALL),
        )
        records.append(np.array(record.ctrl))
    assert np.abs(records[0] - records[1]).max() < 1e-8 and np.ptp(records[1][:, 1]) > 0.1  # 1.4e-10 here


def too_long() -> bytes:
    """A motion of two segments that passes 600 s in its second, the shorter one (320 + 304 s)."""
    marker = struct.pack("<i", 12345)
    data = serialize_mtn(
        Motion.from_poses("long", ["PRM:/r2/c1-Joint2:21"], [[0], [0], [0]], [20001 * 16, 12346 * 16])
    )  # numInterpolate 20000, 12345
    assert data.count(marker) == 1
    return data.replace(marker, struct.pack("<i", 19000))


def odd_header(motion: bytes) -> bytes:
    """``motion`` with other values in the header fields Sony's MTNFile never reads: version 2.0,
    5 sections, section 0's size 40, section 1 numbered 7, data type 1."""
    out = bytearray(motion)
    struct.pack_into("<I", out, 8, 40)
    struct.pack_into("<IHH", out, 12, 5, 2, 0)
    struct.pack_into("<I", out, 28, 7)
    end2 = 28 + struct.unpack_from("<I", out, 32)[0]
    end2 += struct.unpack_from("<I", out, end2 + 4)[0]
    struct.pack_into("<I", out, end2 + 8, 1)
    return bytes(out)


@pytest.fixture(scope="module")
def probe(tmp_path_factory):
    """The probe controller, with the motion it opens under a long name, and its stick."""
    folder = tmp_path_factory.mktemp("probe")
    controller = folder / "probe"
    controller.mkdir()
    (controller / "probe.c").write_text(PROBE)
    shutil.copy(WALK, controller / "Walk_Forward.long.mtn")
    walk = WALK.read_bytes()
    bad = [
        b"OMTX" + walk[4:],
        walk[:-10],
        walk[:-4] + (7_000_000).to_bytes(4, "little"),
        serialize_mtn(Motion.from_poses("odd", ["PRM:/r2/c1-Joint2:21", "PRM:/p1-Sensor:p1"], [[0, 0]], [])),
        serialize_mtn(Motion.from_poses("sit", ["PRM:/r2/c1-Joint2:j1"], [[0]], [], design="DRX-900")),
        too_long(),
        odd_header(walk),
        walk[:22] + (20).to_bytes(2, "little") + walk[24:],  # 20 ms frames: not whole 8 ms frames
        walk[:20],
    ]
    for number, data in enumerate(bad, start=1):
        (controller / f"bad{number}.mtn").write_bytes(data)
    assert build(controller, folder / "project") == []
    return controller, folder / "project"


def probe_runs(monkeypatch, probe, tmp_path, scenario: str, frames: int = 128):
    """The probe on the stick and on the openr backend, each in its folder: the two folders and
    the two simulations at their ends."""
    controller, project = probe
    folders = tmp_path / "stick", tmp_path / "reference"
    for folder in folders:
        folder.mkdir(parents=True)
        (folder / "scenario.txt").write_text(scenario + "\n")
        locators = (
            [j.locator for j in ers7.JOINTS if "-Joint2:" in j.locator]
            if scenario in ("sensors", "torques")
            else ers7.all_locators()
        )
        (folder / "locators.txt").write_text("".join(locator + "\n" for locator in locators))
    _, sim, _ = run_stick(project, frames, folders[0])
    reference = run_reference(monkeypatch, controller, frames - 1, tmp_path / "out", workdir=folders[1])
    return (*folders, sim, reference.sim)


def test_camera_get_image_is_the_openr_backends_byte_for_byte(probe, tmp_path, monkeypatch, capfd):
    stick, reference, sim, reference_sim = probe_runs(monkeypatch, probe, tmp_path, "camera")
    data = (stick / "probe.txt").read_bytes()
    assert data.startswith(b"208 160 0.993092") and len(data) > 30 * 208 * 160 * 3
    assert data == (reference / "probe.txt").read_bytes()
    assert (stick / "died.txt").read_text() == (reference / "died.txt").read_text() == "died\n"
    # camera_save_image: the 10th picture, as a PNG (the stick's uncompressed: no zlib on the robot)
    # and a JPEG, colour not subsampled (the stick's own encoder; libjpeg's through OpenCV in the simulator)
    tenth = data.index(b"\n") + 1 + 9 * 208 * 160 * 3
    picture = np.frombuffer(data[tenth : tenth + 208 * 160 * 3], np.uint8).reshape(160, 208, 3)
    sampling = [cv2.IMWRITE_JPEG_QUALITY, 90, cv2.IMWRITE_JPEG_SAMPLING_FACTOR, cv2.IMWRITE_JPEG_SAMPLING_FACTOR_444]
    libjpeg = cv2.imdecode(cv2.imencode(".jpg", picture[:, :, ::-1], sampling)[1], cv2.IMREAD_COLOR)[:, :, ::-1]
    libjpeg_error = np.abs(libjpeg.astype(int) - picture).mean()  # ~2.6: the sensor's noise costs
    for folder in (stick, reference):
        assert (folder / "saved.txt").read_text() == "0 0 -1 -1 -1\n" and not (folder / "no").exists()
        assert np.array_equal(cv2.imread(str(folder / "shot.png"), cv2.IMREAD_UNCHANGED)[:, :, ::-1], picture)
        jpeg_error = np.abs(cv2.imread(str(folder / "shot.jpg"))[:, :, ::-1].astype(int) - picture).mean()
        assert jpeg_error < libjpeg_error + 0.05, folder.name  # as good as libjpeg's
    assert np.array_equal(cv2.imread(str(reference / "shot.jpg"))[:, :, ::-1], libjpeg)
    # a name it cannot write is -1, and the reason the Python API's (on the robot's console there)
    reasons = ["the file name must end in .png, .jpg or .jpeg", "a JPEG's quality must be a whole number 1-100"]
    stderr, console = capfd.readouterr().err, (stick / "console.log").read_text()
    for call, reason in zip(("'a.gif', 90", "'a.JPEG', 0"), reasons, strict=True):
        line = f"PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1: camera_save_image({call}): {reason}\n"
        assert f"Controller: {line}" in console and f"aibo-sim: {line}" in stderr
    # The LED the wrapper commands when the controller commands nothing stays as it was.
    assert np.array_equal(sim.model.geom_rgba, reference_sim.model.geom_rgba)


def test_a_stick_runs_out_holds_the_pictures_its_controller_took_as_the_openr_backends(probe, tmp_path, monkeypatch):
    """--out's frames: each picture the controller's camera took, as camera_get_image gave it (layer
    H, its tag pixels kept), as the latency-4 openr run writes them. It wrote every 30 fps frame, as
    rendered (untagged; 416 x 320 with --camera-full), whatever the camera took."""
    controller, project = probe
    folders = {name: tmp_path / name for name in ("stick", "reference")}
    for folder in folders.values():
        folder.mkdir()
        (folder / "scenario.txt").write_text("camera\n")
        (folder / "locators.txt").write_text("".join(locator + "\n" for locator in ers7.all_locators()))
    frames = 64
    stick = runner.run_controller(
        project / "MS", duration=frames * 8 / 1000, out=tmp_path / "o1", progress=False, workdir=folders["stick"]
    )
    run_reference(monkeypatch, controller, frames - 1, tmp_path / "o2", workdir=folders["reference"])
    written = [sorted((tmp_path / out / "frames").glob("*.png")) for out in ("o1", "o2")]
    assert [p.name for p in written[0]] == [p.name for p in written[1]] and stick.camera_frames == len(written[0])
    assert 10 <= len(written[0]) < 16  # a camera at 32 ms takes some 30 fps frames, not all 16
    for ours, theirs in zip(*written):
        assert np.array_equal(cv2.imread(str(ours)), cv2.imread(str(theirs))), ours.name
    assert cv2.imread(str(written[0][0])).shape == (160, 208, 3)
    run_json = json.loads((tmp_path / "o1" / "run.json").read_text())
    assert (run_json["camera"]["width"], run_json["camera"]["height"]) == (208, 160)
    # a wrapper built before it told which pictures it took (here: its hook's name changed): every
    # frame it observed is written, where none was
    old = tmp_path / "old"
    shutil.copytree(project / "MS", old)
    binary = old / "OPEN-R" / "MW" / "OBJS" / "CONTROLL.BIN"
    code = gzip.decompress(binary.read_bytes())
    binary.write_bytes(gzip.compress(code.replace(b"aibo_sim_camera_captured", b"aibo_sim_camera_xaptured")))
    old_run = runner.run_controller(old, duration=frames * 8 / 1000, out=tmp_path / "o3", workdir=folders["stick"])
    assert old_run.camera_frames == len(list((tmp_path / "o3" / "frames").glob("*.png"))) >= len(written[0])


def test_devices_tags_and_motions_are_the_python_apis(probe, tmp_path, monkeypatch):
    for scenario in ("devices", "motion"):
        stick, reference, _, _ = probe_runs(monkeypatch, probe, tmp_path / scenario, scenario)
        assert (stick / "probe.txt").read_text() == (reference / "probe.txt").read_text()
    lines = (tmp_path / "motion" / "stick" / "probe.txt").read_text().splitlines()
    assert lines[0] == "name:        a_walk#walk_fwd" and lines[19] == "320 a_walk#walk_fwd"
    assert lines[20:23] == ["0 0 0", "0.032 0 32", "0.064 0 64"] and "0.352 0 0" in lines  # played twice,
    assert lines[-1] == "0.992 1 0"  # then over
    tags = (tmp_path / "devices" / "stick" / "probe.txt").read_text().splitlines()
    assert len(tags) == len(ers7.all_locators()) and tags[-1].endswith(f" {len(tags) - 2}")  # a2, a3: one device


def test_malformed_motions_are_refused_with_the_python_readers_messages(probe, tmp_path, monkeypatch):
    stick, reference, _, _ = probe_runs(monkeypatch, probe, tmp_path, "bad motions", frames=8)
    errors = [(folder / "probe.txt").read_text().splitlines() for folder in (stick, reference)]
    assert [line.split(": ", 1)[0] for line in errors[0][:3]] == [f"/MS/OPEN-R/MW/DATA/P/BAD{k}.MTN" for k in (1, 2, 3)]
    assert [line.split(": ", 1)[0] for line in errors[1][:3]] == [str(probe[0] / f"bad{k}.mtn") for k in (1, 2, 3)]
    # The same messages but for the file's name: the stick's path, the folder's on the backend.
    assert [line.split(": ", 1)[1] for line in errors[0][:3]] == [line.split(": ", 1)[1] for line in errors[1][:3]]
    assert errors[0][0].endswith("byte 0 (0x0): wrong magic b'OMTX' (should be b'OMTN')")
    assert "truncated: section 3 (21 keyframes of 12 joints) needs" in errors[0][1]
    assert errors[0][2].endswith(": 7 rad is beyond a full turn")
    assert errors[0][3] == errors[1][3] == "Not a joint: PRM:/p1-Sensor:p1 (a motion moves joints only)"
    assert (
        errors[0][4]
        == errors[1][4]
        == (
            "Missing device in model: PRM:/r2/c1-Joint2:j1 "
            "(a motion for DRX-900, the ERS-210/220, not the ERS-7's DRX-1000)"
        )
    )
    assert errors[0][5].split(": ", 1)[1] == errors[1][5].split(": ", 1)[1]
    assert errors[0][5].endswith("(it passes them in segment 1 -> 2 of 2: numInterpolate 19000 of 16 ms frames)")
    assert errors[0][6] == errors[1][6] == "loaded"  # fields Sony's reader ignores are ignored
    assert (
        errors[0][7].split(": ", 1)[1] == errors[1][7].split(": ", 1)[1] == "frame time 20 ms is not a multiple of 8 ms"
    )  # refused by mtn_new, as an error mtn_get_error gives, not at mtn_play
    assert (
        errors[0][8].split(": ", 1)[1]
        == errors[1][8].split(": ", 1)[1]
        == "byte 4 (0x4): truncated: section 0 needs 24 bytes, the file ends at byte 20"
    )


def test_leds_light_as_on_the_openr_backend_frame_for_frame(probe, tmp_path, monkeypatch):
    """LED2 on or off, LED3 at their intensity (more than 255 is 255), as the Python API sets them,
    32 ms after the controller's time on both (the latency did not delay the reference's LEDs)."""
    controller, project = probe
    for folder in (tmp_path / "stick", tmp_path / "reference"):
        folder.mkdir()
        (folder / "scenario.txt").write_text("leds\n")
        (folder / "locators.txt").write_text("".join(locator + "\n" for locator in ers7.all_locators()))
    stick, sim, _ = run_stick(project, 16, tmp_path / "stick")
    reference = run_reference(monkeypatch, controller, 15, tmp_path / "out", workdir=tmp_path / "reference")
    assert np.array_equal(np.array(stick.leds[:-1]), np.array(reference.leds))
    lit = [not np.allclose(leds, ers7.LED_OFF_RGBA) for leds in stick.leds]
    assert lit.index(True) == LATENCY_FRAMES  # lit in the frame that begins 32 ms after t = 0, the 5th
    names = ("led_head_white", "led_face_bottom_outer_l", "led_back_rear_white", "led_head_colour")
    rgba = [np.array([s.model.geom_rgba[s.model.geom(name).id] for name in names]) for s in (sim, reference.sim)]
    assert np.array_equal(rgba[0], rgba[1]) and not np.array_equal(rgba[0][0], rgba[0][3])  # lit, unlit


def test_an_ear_held_up_is_flicked_for_128_ms_then_let_down(probe, tmp_path):
    """The plunger was on for as long as the set-point stayed up; Sony's Model Information warns that
    this may damage the robot, and its MovingEar7 turns it on for 16 frames."""
    controller, project = probe
    (tmp_path / "scenario.txt").write_text("ear\n")
    record, sim, _ = run_stick(project, 96, tmp_path)
    up = [bool(ctrl[sim.model.actuator("ear_l").id] > 0) for ctrl in record.ctrl]
    first = up.index(True)
    assert up[first : first + 16] == [True] * 16 and not any(up[first + 16 :]), up


def test_robot_run_does_not_return_on_the_stick_as_in_the_simulator(probe, tmp_path):
    """robot_run returned on the stick, so main's statements after it ran there, and never in the simulator."""
    (tmp_path / "scenario.txt").write_text("after run\n")
    run_stick(probe[1], 16, tmp_path)
    assert (tmp_path / "console.log").exists() and not (tmp_path / "after.txt").exists()


def test_robot_run_in_the_run_function_replaces_it_at_once_as_in_the_simulator(probe, tmp_path, monkeypatch):
    """That robot_run returned on the stick: the old run function went on and the new one started
    a step later."""
    stick, reference, _, _ = probe_runs(monkeypatch, probe, tmp_path, "run in run", frames=32)
    lines = (stick / "probe.txt").read_text().splitlines()
    assert lines[:4] == ["outer 0 0", "after robot_run", "outer 64 0.064", "inner 0 0.064"]
    assert lines[4:6] == ["inner 32 0.096", "inner 32 0.128"]
    assert (reference / "probe.txt").read_text().splitlines() == lines


def test_sensor_values_are_the_python_apis_to_the_micro_unit(probe, tmp_path, monkeypatch):
    stick, reference, _, _ = probe_runs(monkeypatch, probe, tmp_path, "sensors")
    values = [np.loadtxt(folder / "probe.txt") for folder in (stick, reference)]
    assert values[0].shape == values[1].shape == (31, 18 + 4)  # 32 ms steps; the Joint2 joints, a1-a3, a paw
    joints, accelerations = slice(0, 18), slice(18, 21)
    assert np.abs(values[0][:, joints] - values[1][:, joints]).max() <= 0.5e-6 + 1e-9  # micro-radians
    assert np.abs(values[0][:, accelerations] - values[1][:, accelerations]).max() <= 1.5e-6  # um/s^2, floats
    assert np.array_equal(values[0][:, 21], values[1][:, 21])  # the paw switch


def test_motor_force_feedback_is_the_python_apis_to_the_pwm_dutys_step(probe, tmp_path, monkeypatch):
    """The stick reads each joint's torque off its PWM duty (ers7.PWM_DUTY_FULL_SCALE of
    ers7.MAX_TORQUE), where the Python API reads MuJoCo's actuator force."""
    stick, reference, _, _ = probe_runs(monkeypatch, probe, tmp_path, "torques")
    values = [np.loadtxt(folder / "probe.txt") for folder in (stick, reference)]
    step = ers7.MAX_TORQUE / ers7.PWM_DUTY_FULL_SCALE
    assert values[0].shape == values[1].shape == (31, 18) and np.abs(values[1]).max() > 5 * step
    assert np.abs(values[0] - values[1]).max() <= step / 2 + 1e-9
    assert np.abs(values[0] / step - np.round(values[0] / step)).max() < 1e-6  # whole duties


def test_a_motion_under_a_long_name_is_found_on_the_stick_by_its_short_name(probe, tmp_path, monkeypatch):
    assert short_name("Walk_Forward.long.mtn") == "WALK_FOR.MTN" and short_name("/ms/a/wwfwd.mtn") == "WWFWD.MTN"
    assert (probe[1] / "MS" / "OPEN-R" / "MW" / "DATA" / "P" / "WALK_FOR.MTN").read_bytes() == WALK.read_bytes()
    stick, reference, _, _ = probe_runs(monkeypatch, probe, tmp_path, "short name", frames=8)
    assert (stick / "probe.txt").read_text() == (reference / "probe.txt").read_text() == "320\n"


def test_errors_end_the_controller_with_the_python_apis_message(probe, tmp_path):
    robot = Robot(Simulation(ball=False))
    with pytest.raises(DeviceError) as device:
        robot.get_device("no-such-device")
    pan = robot.get_device("PRM:/r1/c1/c2-Joint2:12")
    with pytest.raises(DeviceError) as acceleration:
        pan.set_acceleration(0)
    with pytest.raises(DeviceError) as control_p:
        pan.set_control_p(-50)
    with pytest.raises(DeviceError) as ear_torque:
        robot.get_device("PRM:/r1/c1/c2/c3/e5-Joint4:15").force_feedback.enable(32)
    with pytest.raises(MtnError) as missing:
        mtn_new("missing.mtn")
    api.install(robot)
    try:
        with pytest.raises(ValueError) as zero_step:
            api.robot_run(lambda ms: 0)
    finally:
        api.install(None)
    cases = {
        "device error": str(device.value),
        "acceleration": str(acceleration.value),
        "control p": str(control_p.value),
        "ear torque": str(ear_torque.value),
        "missing motion": f"mtn_play: MTN is NULL: mtn_new failed ({missing.value})",
        "step": "robot_step(32): not on the robot: an OPEN-R object cannot wait for time to pass inside a call",
        "zero step": str(zero_step.value),  # the stick said 'step of 0 ms: must be a positive whole multiple'
    }
    for scenario, message in cases.items():
        folder = tmp_path / scenario.replace(" ", "_")
        folder.mkdir()
        (folder / "scenario.txt").write_text(scenario + "\n")
        _, sim, run = run_stick(probe[1], 64, folder)
        assert sim.time_ms == (32 if scenario == "zero step" else 0)  # shut down before the first frame or vector
        assert f"controller error at t = 0.000 s: {message}" in (folder / "console.log").read_text()
        assert run.controller_error.startswith(f"controller error at t = 0.000 s: {message}")  # the run failed
        assert (folder / "died.txt").exists() == (scenario in ("step", "zero step"))  # the others fail before robot_die
    assert (tmp_path / "missing_motion" / "probe.txt").read_text() == f"{missing.value}\n"
    out = tmp_path / "cli"  # the command: exit 1 and run.json "failed", as for a Python controller's error
    out.mkdir()
    (out / "scenario.txt").write_text("control p\n")
    assert main(["run", str(probe[1]), "--duration", "0.1", "--out", str(out)]) == 1
    run_json = json.loads((out / "run.json").read_text())
    assert run_json["status"] == "failed"
    assert run_json["error"] == f"memory stick MS: controller error at t = 0.000 s: {control_p.value}"


@pytest.mark.parametrize("status", [0, 3])
def test_exit_ends_the_controller_through_its_robot_die_functions_as_in_the_simulator(probe, tmp_path, status):
    """exit(N) is a Python controller's sys.exit(N) (docs/c-controllers.md). On a stick it ended the
    OPEN-R runtime: no robot_die function ran, and exit(0) failed the run ('exited with status 0')."""
    (tmp_path / "scenario.txt").write_text(f"exit {status}\n")
    _, sim, run = run_stick(probe[1], 64, tmp_path)
    assert (tmp_path / "died.txt").read_text() == "died\n"
    assert run.shutdown and sim.time_ms < 64 * 8
    if status:
        assert run.controller_error.startswith("controller error at t = 0.032 s: exited with exit(3)")
    else:
        assert run.controller_error is None


def test_a_memory_stick_is_cross_compiled_and_has_no_keyboard(probe, tmp_path, monkeypatch):
    stick, reference, _, _ = probe_runs(monkeypatch, probe, tmp_path, "mode", frames=8)
    # Webots 5's robot_get_mode: 1 on the robot, 0 in the simulator; the robot does not wait for its controller
    assert (stick / "probe.txt").read_text() == "mode 1 key 0 step 8 synchronized 0 error []\n"
    assert (reference / "probe.txt").read_text() == "mode 0 key 0 step 8 synchronized 1 error []\n"


def test_the_wrappers_structure_sizes_are_checked_when_it_compiles(probe, tmp_path):
    """Were a structure not the robot's size (here: a check expecting another size), the build stops."""
    project = tmp_path / "project"
    shutil.copytree(probe[1], project, symlinks=True)
    source = project / "Controller" / "Controller.cc"
    source.write_text(source.read_text().replace("sizeof(OCommandInfo) == 32", "sizeof(OCommandInfo) == 64"))
    result = subprocess.run(
        ["make", f"OPENRSDK_ROOT={sdk_root()}", "Controller.o"],
        cwd=project / "Controller",
        capture_output=True,
        text=True,
    )
    assert result.returncode != 0 and "OCommandInfo_is_32_bytes" in result.stderr


def test_make_clean_removes_what_sonys_mkbin_leaves_too(probe, tmp_path):
    project = tmp_path / "project"
    shutil.copytree(probe[1], project)
    leftovers = ["controller.nosnap.elf", "controller.rel.elf", "controller.snap.elf", "controller.snap.cc"]
    for name in leftovers:
        (project / "Controller" / name).write_text("mkbin's\n")
    subprocess.run(["make", "clean"], cwd=project, check=True, capture_output=True)
    assert not [name for name in leftovers if (project / "Controller" / name).exists()]
    assert not (project / "MS" / "OPEN-R" / "MW" / "OBJS" / "CONTROLL.BIN").exists()


def test_the_project_is_sonys_form_and_its_device_table_is_ers7s(probe):
    controller = probe[1] / "Controller"
    makefile = (controller / "Makefile").read_text()
    for line in (
        "OPENRSDK_ROOT?=/usr/local/OPEN_R_SDK",
        "STUBGEN=$(OPENRSDK_ROOT)/OPEN_R/bin/stubgen2",
        "MKBIN=$(OPENRSDK_ROOT)/OPEN_R/bin/mkbin",
        "CXX=$(OPENRSDK_ROOT)/bin/mipsel-linux-g++",
        "\tgzip -c controller.bin > $(INSTALLDIR)/OPEN-R/MW/OBJS/CONTROLL.BIN",
        "\t$(CC) $(CFLAGS) -Dmain=aibo_controller_main_c -o $@ -c $<",
    ):
        assert line in makefile.splitlines()
    assert '"Controller.Image.OFbkImageVectorData.O", null, Notify()' in (controller / "stub.cfg").read_text()
    stick = probe[1] / "MS" / "OPEN-R" / "MW"
    assert (stick / "CONF" / "OBJECT.CFG").read_text() == "/MS/OPEN-R/MW/OBJS/CONTROLL.BIN\n"
    assert (
        "OVirtualRobotComm.FbkImageSensor.OFbkImageVectorData.S Controller.Image.OFbkImageVectorData.O"
        in (stick / "CONF" / "CONNECT.CFG").read_text().splitlines()
    )
    table = (controller / "Ers7Table.h").read_text()
    servos = Servos(load_model(ball=False))
    for i, joint in enumerate(ers7.JOINTS):
        row = (
            f'{{"{joint.locator}", {float(servos.low[i])!r}, {float(servos.high[i])!r}, {joint.max_speed!r}, '
            + ", ".join(f"{gain:#04x}" for gain in joint.gains)
            + "},"
        )
        assert f"    {row}" in table.splitlines()
    for locator in [s.locator for s in ers7.SENSORS] + [led.locator for led in ers7.LEDS]:
        assert f'"{locator}"' in table


def test_the_wrapper_ships_as_package_data():
    tomllib = pytest.importorskip("tomllib")  # Python 3.11+
    setuptools = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    patterns = setuptools["package-data"]["openr_bridge"]
    for path in WRAPPER_SOURCES.iterdir():
        assert any(fnmatch.fnmatch(f"wrapper/{path.name}", pattern) for pattern in patterns), path.name


def test_bad_input_is_refused_naming_the_argument(tmp_path):
    (tmp_path / "notes.txt").write_text("")
    (tmp_path / "empty").mkdir()
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "x").write_text("")
    walker = tmp_path / "walker.c"
    walker.write_text('int main(void) { mtn_new("nowhere.mtn"); mtn_new("/MS/OPEN-R/LONGFOLDER/X.MTN"); return 0; }')
    shutil.copy(WALK, tmp_path / "x.mtn")
    cases = [
        ("", tmp_path / "o1", r"^controller is empty"),
        (tmp_path / "none.c", tmp_path / "o2", r"^controller .*none\.c: no such file or folder$"),
        (tmp_path / "notes.txt", tmp_path / "o3", r"^controller .*notes\.txt: not a C or C\+\+ file"),
        (tmp_path / "empty", tmp_path / "o4", r"^controller .*empty: a folder with no empty\.c or empty\.cc or"),
        (TRACKER, tmp_path / "full", r"^--out .*full: the folder exists and is not empty"),
        (TRACKER, tmp_path / "notes.txt", r"^--out .*notes\.txt: exists and is not a folder$"),
        (TRACKER, "", r"^--out is empty"),
        (walker, tmp_path / "o5", r"^controller .*walker\.c opens 'nowhere\.mtn', which is neither in"),
        (TRACKER, tmp_path / "my stick", r"^--out .*my stick: make cannot build in a folder whose path has ' ' "),
        (TRACKER, tmp_path / "a(b)" / "o7", r"^--out .*o7: make cannot build in a folder whose path has '\(' "),
    ]
    for controller, out, message in cases:
        with pytest.raises(BuildMsError, match=message) as error:
            build_ms(controller, out)
        assert "\n" not in str(error.value)
    assert not any((tmp_path / f"o{k}").exists() for k in range(1, 6)) and not (tmp_path / "my stick").exists()
    assert not (tmp_path / "a(b)").exists() and len(list((tmp_path / "full").iterdir())) == 1
    shutil.copy(WALK, tmp_path / "nowhere.mtn")
    with pytest.raises(BuildMsError, match=r"opens '/MS/OPEN-R/LONGFOLDER/X\.MTN': /MS/\.\.\. names must be 8\.3"):
        build_ms(walker, tmp_path / "o6")
    shutil.copy(WALK, tmp_path / "a+b.mtn")  # a name the robot cannot open (Programmer's Guide A.1)
    walker.write_text('int main(void) { mtn_new("/MS/OPEN-R/MW/DATA/P/a+b.mtn"); return 0; }')
    with pytest.raises(
        BuildMsError, match=r"opens '/MS/OPEN-R/MW/DATA/P/a\+b\.mtn': /MS/\.\.\. names must be 8\.3 names of"
    ):
        build_ms(walker, tmp_path / "o6")
    assert not (tmp_path / "o6").exists()


PICTURE_DRIVER = r"""
#include <stdio.h>
#include <stdlib.h>
#include "Picture.h"
int main(int argc, char** argv) {  /* width height quality (0: PNG): RGB in, the file out */
    int width = atoi(argv[1]), height = atoi(argv[2]), quality = atoi(argv[3]);
    std::vector<byte> rgb((size_t)width * height * 3);
    if (fread(&rgb[0], 1, rgb.size(), stdin) != rgb.size()) return 1;
    std::vector<byte> file = quality ? wrapper::Jpeg(&rgb[0], width, height, quality)
                                     : wrapper::Png(&rgb[0], width, height);
    fwrite(&file[0], 1, file.size(), stdout);
    return 0;
}
"""


@pytest.fixture(scope="module")
def picture_encoder(tmp_path_factory):
    """The wrapper's PNG and JPEG encoders (Picture.cc) in a program of their own, as the stick builds them."""
    folder = tmp_path_factory.mktemp("picture")
    (folder / "driver.cc").write_text(PICTURE_DRIVER)
    include = Path(sdk_root()) / "OPEN_R" / "include"
    command = ["c++", "-std=gnu++98", "-Wall", "-Werror", f"-I{include}", f"-I{WRAPPER_SOURCES}", "-o", "encode"]
    subprocess.run([*command, "driver.cc", str(WRAPPER_SOURCES / "Picture.cc")], cwd=folder, check=True)

    def encode(rgb: np.ndarray, quality: int) -> np.ndarray:
        height, width, _ = rgb.shape
        result = subprocess.run(
            [folder / "encode", str(width), str(height), str(quality)], input=rgb.tobytes(), capture_output=True
        )
        assert result.returncode == 0
        return cv2.imdecode(np.frombuffer(result.stdout, np.uint8), cv2.IMREAD_COLOR)[:, :, ::-1]

    return encode


def test_the_sticks_jpegs_are_as_close_as_libjpegs_and_its_pngs_exact(picture_encoder):
    """Sizes that are not whole 8x8 blocks, the qualities' ends and middle; white at quality 50
    (DC 63.5 in steps of 16) came back 254 when the half was rounded down."""
    rng = np.random.default_rng(3)
    smooth = cv2.resize(rng.integers(0, 256, (5, 7, 3), dtype=np.uint8), (208, 160), interpolation=cv2.INTER_CUBIC)
    for image in (smooth, rng.integers(0, 256, (9, 17, 3), dtype=np.uint8), np.full((1, 1, 3), 200, np.uint8)):
        assert np.array_equal(picture_encoder(image, 0), image)  # PNG
        for quality in (1, 50, 90, 100):
            options = [cv2.IMWRITE_JPEG_QUALITY, quality]
            options += [cv2.IMWRITE_JPEG_SAMPLING_FACTOR, cv2.IMWRITE_JPEG_SAMPLING_FACTOR_444]
            libjpeg = cv2.imdecode(cv2.imencode(".jpg", image[:, :, ::-1], options)[1], cv2.IMREAD_COLOR)[:, :, ::-1]
            ours = np.abs(picture_encoder(image, quality).astype(int) - image).mean()
            assert ours <= np.abs(libjpeg.astype(int) - image).mean() * 1.05 + 0.05, (image.shape, quality)
    white = np.full((16, 16, 3), 255, np.uint8)
    for quality in (49, 50, 51):
        assert (picture_encoder(white, quality) == 255).all(), quality
