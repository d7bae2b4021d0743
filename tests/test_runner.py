"""The headless runner, the CLI, both backends on one controller, the Annex I port (issue 4)."""

import json
import re
from pathlib import Path

import cv2
import numpy as np
import pytest

import openr_bridge
from aibo_sim import ers7
from aibo_sim.cli import main
from aibo_sim.config import CameraConfig, WorldConfig
from aibo_sim.dump import annex_yuv
from aibo_sim.runner import ControllerFailed, run_controller

ROOT = Path(__file__).resolve().parents[1]
SCRIPTED = Path(__file__).parent / "controllers" / "scripted_head.py"
ROUND_TRIP_BOUND = 2  # max |RGB -> YCrCb -> RGB| per channel, over all 2^24 colours (see below)
TAG_PIXELS = 12  # the tag Sony writes over the start of layer H's last Y row


def test_colour_round_trip_bound_holds_for_every_rgb_colour():
    levels = np.arange(256, dtype=np.uint8)
    green, blue = np.meshgrid(levels, levels, indexing="ij")
    worst = 0
    for red in range(0, 256):
        rgb = np.stack([np.full_like(green, red), green, blue], axis=-1)
        back = openr_bridge.ycrcb_to_rgb(*openr_bridge.rgb_to_ycrcb(rgb))
        worst = max(worst, int(np.abs(back.astype(int) - rgb).max()))
    assert worst == ROUND_TRIP_BOUND


@pytest.mark.parametrize("profile, bound", [("ers7", 0), ("ideal", ROUND_TRIP_BOUND)])
def test_one_controller_on_both_backends(tmp_path, profile, bound):
    """ers7: both backends serve Sony's YCrCb2RGB of the sensor's bytes, identical but for the
    tag; ideal: the sim backend serves the render, openr its colour round trip."""
    runs = {}
    for backend in ("sim", "openr"):
        out = tmp_path / backend
        summary = run_controller(
            SCRIPTED, backend=backend, duration=1.0, out=out, world=WorldConfig(seed=3), camera=CameraConfig(profile)
        )
        assert summary.camera_frames == 30 and summary.simulated_s == pytest.approx(1.0)
        runs[backend] = out
    logs = {
        b: [line for line in (out / "joints.txt").read_text().splitlines() if not line.startswith("pixel")]
        for b, out in runs.items()
    }
    assert len(logs["sim"]) > 50 and logs["sim"] == logs["openr"]  # identical joint trajectories
    frames = sorted(p.name for p in (runs["sim"] / "frames").iterdir())
    assert frames == sorted(p.name for p in (runs["openr"] / "frames").iterdir())
    worst = 0
    for name in frames:
        sim = cv2.imread(str(runs["sim"] / "frames" / name)).astype(int)
        openr = cv2.imread(str(runs["openr"] / "frames" / name)).astype(int)
        assert sim.shape == openr.shape == (160, 208, 3)
        difference = np.abs(sim - openr)
        assert difference[-1, :TAG_PIXELS].max() > 0 or name == frames[0]  # the tag is really there
        difference[-1, :TAG_PIXELS] = 0
        worst = max(worst, int(difference.max()))
    assert worst == bound if bound == 0 else 0 < worst <= bound


def test_controller_exception_reports_simulated_time(tmp_path):
    bad = tmp_path / "bad.py"
    bad.write_text(
        "from aibo_sim.controller import *\n"
        "def run(ms):\n"
        "    if robot_get_time() >= 0.2:\n"
        "        raise RuntimeError('boom')\n"
        "    return 32\n"
        "robot_live(None)\nrobot_run(run)\n"
    )
    with pytest.raises(ControllerFailed, match=r"t = 0\.224 s(.|\n)*RuntimeError: boom"):
        run_controller(bad, duration=1.0)
    assert main(["run", str(bad), "--duration", "1"]) == 1


def test_a_controller_error_shows_the_controller_s_frames_only(tmp_path):
    """An API call's error: the controller's lines and the message, not the simulator's frames
    (runpy, runner, controller.py, robot.py) nor the exception the simulator raised it from."""
    bad = tmp_path / "bad.py"
    bad.write_text(
        "from aibo_sim.controller import *\n"
        "cam = robot_get_device('PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1')\n"
        "def run(ms):\n"
        "    camera_set_gain(cam, 7)\n"
        "robot_live(None)\nrobot_run(run)\n"
    )
    with pytest.raises(ControllerFailed) as failure:
        run_controller(bad, duration=0.1)
    report = str(failure.value)
    frames = re.findall(r'File "([^"]+)", line (\d+)', report)
    assert frames == [(str(bad), "6"), (str(bad), "4")], report
    assert (
        report.rstrip().endswith(
            "the value must be 1 (ocamparamGAIN_LOW), 2 (ocamparamGAIN_MID) or 3 (ocamparamGAIN_HIGH)"
        )
        and "above exception" not in report
    ), report


def test_a_syntax_error_is_bad_input_found_before_anything_runs(tmp_path, capsys):
    bad = tmp_path / "syntax.py"
    bad.write_text("from aibo_sim.controller import *\ndef init(:\n    pass\n")
    for command in (
        ["run", str(bad), "--out", str(tmp_path / "run")],
        ["dump", str(bad), "--out", str(tmp_path / "dump"), "--steps", "2"],
    ):
        assert main(command) == 2
        assert (
            capsys.readouterr().err.strip()
            == f"aibo-sim: error: {bad}, line 2: SyntaxError: invalid syntax ('def init(:')"
        )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["syntax.py"]  # no folder made
    assert main(["run", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert f"{tmp_path}: a folder with no {tmp_path.name}.c or {tmp_path.name}.cc or" in err
    assert err.rstrip().endswith("and no memory stick (MS/OPEN-R/MW/CONF/OBJECT.CFG)")
    (tmp_path / "half" / "OPEN-R" / "MW" / "CONF").mkdir(parents=True)  # a stick without its OBJECT.CFG
    assert main(["run", str(tmp_path / "half")]) == 2  # was told of C controller folders and an MS it has not
    assert capsys.readouterr().err == (
        f"aibo-sim: error: {tmp_path}/half: a memory stick without its OBJECT.CFG ({tmp_path}/half/OPEN-R/MW/CONF: "
        "no OBJECT.CFG (any case) here; expected OPEN-R/MW/CONF/OBJECT.CFG)\n"
    )
    conf = tmp_path / "program" / "MS" / "OPEN-R" / "MW" / "CONF"
    conf.mkdir(parents=True)
    (conf / "OBJECT.CFG").write_text("/MS/OPEN-R/MW/OBJS/X.BIN\n")
    assert main(["run", str(conf.parents[1])]) == 2  # a folder of the stick, not the program's or the stick's
    assert capsys.readouterr().err == (
        f"aibo-sim: error: {conf.parents[1]}: a folder inside the memory stick {conf.parents[2]}: "
        "run the stick's folder\n"
    )


def test_cli_bad_input_exits_2_with_a_clear_message(tmp_path, capsys):
    assert main(["run", str(tmp_path / "missing.py")]) == 2
    assert "missing.py: no such controller file" in capsys.readouterr().err
    assert main(["run", str(SCRIPTED), "--duration", "-1"]) == 2
    assert "--duration -1.0: must be positive" in capsys.readouterr().err
    assert main(["run", str(SCRIPTED), "--scene", str(tmp_path / "nope.xml")]) == 2
    assert "nope.xml: no such model file" in capsys.readouterr().err
    robot_only = str(ROOT / "models" / "ers7.xml")
    assert main(["run", str(SCRIPTED), "--scene", robot_only, "--duration", "0.1", "--ball", "1", "0"]) == 2
    assert "no body named 'ball'" in capsys.readouterr().err
    assert (
        run_controller(SCRIPTED, duration=0.1, out=tmp_path / "robot_only", world=WorldConfig(scene=robot_only)).ball_xy
        is None
    )


def test_physics_divergence_is_a_clear_error(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(ers7, "MAX_TORQUE", 1e12)  # a servo's force is capped at Webots' maxForce: lift the cap
    wild = tmp_path / "wild.py"
    wild.write_text(
        "from aibo_sim.controller import *\n"
        "j = robot_get_device('PRM:/r2/c1-Joint2:21')\n"
        "servo_set_control_p(j, 1e12)\nservo_set_motor_force(j, 1e12)\n"
        "servo_set_position(j, 2.0)\n"
        "while True:\n    robot_step(8)\n"
    )
    assert main(["run", str(wild), "--duration", "2"]) == 3
    assert "physics diverged at t =" in capsys.readouterr().err


def test_annex_yuv_bytes_for_known_pixels():
    # Hand-computed with the Annex's C expressions: y = (uchar)(0.299 r + 0.587 g + 0.114 b),
    # u = (uchar)(0.492 (b - y) + 128), v = (uchar)(0.5 (r - y) + 128).
    image = np.array([255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255, 0, 0, 0, 10, 200, 30], np.uint8)
    expected = [76, 90, 217, 149, 54, 53, 29, 239, 113, 255, 128, 128, 0, 128, 128, 123, 82, 71]  # checked with gcc
    assert list(annex_yuv(image.reshape(1, 6, 3)).reshape(-1)) == expected


@pytest.mark.slow
def test_annex_port_writes_image_raw_of_the_last_frame(tmp_path):
    summary = run_controller(ROOT / "controllers" / "annex_capture.py", duration=30.0, out=tmp_path)
    raw = (tmp_path / "image.raw").read_bytes()
    assert len(raw) == 208 * 160 * 3
    last = sorted((tmp_path / "frames").iterdir())[-1]
    rgb = cv2.imread(str(last))[:, :, ::-1].reshape(-1)
    assert raw == annex_yuv(rgb.reshape(160, 208, 3)).tobytes()
    assert summary.camera_frames > 800
    assert json.loads((tmp_path / "run.json").read_text())["backend"] == "sim"


@pytest.mark.slow
def test_walk_to_ball_reaches_the_ball(capsys):
    summary = run_controller(
        ROOT / "controllers" / "walk_to_ball.py", duration=20.0, world=WorldConfig(ball=(1.2, 0.5))
    )
    assert "reached the ball at t =" in capsys.readouterr().out
    x, y, _ = summary.robot_pose
    assert np.hypot(summary.ball_xy[0] - x, summary.ball_xy[1] - y) < 0.5  # body centre to ball
    assert np.hypot(x, y) > 0.8  # it walked there


def test_ball_tracker_centres_the_ball_on_the_openr_backend(tmp_path):
    summary = run_controller(
        ROOT / "controllers" / "ball_tracker.py",
        backend="openr",
        duration=2.0,
        out=tmp_path,
        world=WorldConfig(ball=(0.6, 0.25)),
    )
    assert np.hypot(*summary.robot_pose[:2]) < 0.02  # it stood still
    frames = sorted((tmp_path / "frames").iterdir())
    first, last = (cv2.imread(str(p)).astype(np.int16)[:, :, ::-1] for p in (frames[0], frames[-1]))
    start, end = _ball_centre(first), _ball_centre(last)
    assert np.hypot(start[0] - 104, start[1] - 80) > 40  # off-centre at first
    assert np.hypot(end[0] - 104, end[1] - 80) < 6  # centred after 2 s


def _ball_centre(rgb):
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    ys, xs = np.nonzero((r > 110) & (r > 3 * g // 2 + 10) & (g > 3 * b // 2))
    return xs.mean(), ys.mean()


def test_cli_mtn_info_and_play(capsys, tmp_path):
    walk = ROOT / "models" / "motions" / "WALKFWD.MTN"
    assert main(["mtn", "info", str(walk), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert (info["name"], info["num_keyframes"], info["length_ms"], len(info["locators"])) == (
        "a_walk#walk_fwd",
        21,
        320,
        12,
    )
    assert main(["mtn", "play", str(walk), "--repeat", "15", "--json"]) == 0
    played = json.loads(capsys.readouterr().out)
    assert played["displacement_m"][0] > 0.25 and not played["fell"] and abs(played["heading_change_deg"]) < 10
    broken = tmp_path / "BROKEN.MTN"
    broken.write_bytes(walk.read_bytes()[:100])
    assert main(["mtn", "info", str(broken)]) == 2
    assert "BROKEN.MTN" in capsys.readouterr().err


def test_run_json_describes_the_pictures_the_backend_serves(tmp_path):
    """On openr, --camera-full renders 416x320 but the wrapper serves layer H: run.json's lens is
    that of the 208x160 frames written."""
    full = run_controller(SCRIPTED, duration=0.1, out=tmp_path / "sim", camera=CameraConfig(full=True)).camera
    served = run_controller(
        SCRIPTED, backend="openr", duration=0.1, out=tmp_path / "openr", camera=CameraConfig(full=True)
    ).camera
    frame = cv2.imread(str(next((tmp_path / "openr" / "frames").glob("*.png"))))
    assert (full["width"], full["height"], served["width"], served["height"]) == (416, 320, 208, 160)
    assert frame.shape == (160, 208, 3) and served["fx"] == pytest.approx(full["fx"] / 2, abs=1e-3)
    assert json.loads((tmp_path / "openr" / "run.json").read_text())["camera"] == served


def test_a_run_into_an_earlier_runs_folder_leaves_no_console_or_sound_of_it(tmp_path):
    """A memory stick's run writes console.log and speaker.wav in --out: a later run there that
    writes neither (a controller's) removes them with the earlier frames; in a folder holding no
    aibo-sim run they are the user's, left alone."""
    out = tmp_path / "out"
    run_controller(SCRIPTED, duration=0.1, out=out)
    for name in ("console.log", "speaker.wav"):
        (out / name).write_text("a memory stick's, earlier")
    run_controller(SCRIPTED, duration=0.1, out=out)
    assert not (out / "console.log").exists() and not (out / "speaker.wav").exists()
    theirs = tmp_path / "theirs"
    theirs.mkdir()
    (theirs / "console.log").write_text("the user's")
    run_controller(SCRIPTED, duration=0.1, out=theirs)
    assert (theirs / "console.log").read_text() == "the user's"


def test_a_controller_that_ends_before_the_duration_is_said_to_have_ended(tmp_path, capsys):
    forgot = tmp_path / "forgot.py"  # robot_run(run) left out: nothing steps
    forgot.write_text("from aibo_sim.controller import *\ndef run(ms):\n    return 32\n")
    assert main(["run", str(forgot), "--duration", "1", "--camera-profile", "ideal"]) == 0
    assert capsys.readouterr().err == (
        "aibo-sim: note: the controller ended at t = 0.000 s, before --duration 1 s "
        "(a controller steps with robot_step, or with robot_run's function)\n"
    )
    out = ["--out", str(tmp_path / "dump"), "--steps", "5", "--formats", "rgb", "--camera-profile", "ideal"]
    assert main(["dump", str(forgot), *out]) == 0
    assert capsys.readouterr().err == (
        "aibo-sim: note: the dump holds 0 of the 5 frames asked: its controller ended first "
        "(a controller steps with robot_step, or with robot_run's function)\n"
    )
    forgot.write_text(forgot.read_text() + "robot_run(run)\n")
    assert main(["run", str(forgot), "--duration", "1", "--camera-profile", "ideal"]) == 0
    assert capsys.readouterr().err == ""
