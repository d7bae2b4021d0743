"""A dump runs its controller as ``aibo-sim run`` does: ``--mtn-mode`` and ``--memory-stick``
(recorded, checked on ``--resume``), the controller's files in the dump's ``controller_files/``
(a shard's own); an mp4-only dump counts its bytes."""

import json
import shutil
import textwrap
from pathlib import Path

import pytest

import openr_bridge
from aibo_sim.cli import main
from aibo_sim.config import CameraConfig
from aibo_sim.dump import DumpError, dump
from aibo_sim.dump.writing import CONTROLLER_FILES

ROOT = Path(__file__).resolve().parents[1]
TRACKER = ROOT / "controllers" / "ball_tracker.py"
ENV = "aibo_sim/HeadTrackBall-v0"

# Writes, in its working folder, the robot's MTN mode and camera backend, then idles.
WRITER = textwrap.dedent("""\
    from aibo_sim import controller
    from aibo_sim.controller import robot_run

    robot = controller.current_robot()
    with open("where.txt", "w") as file:
        file.write(f"{robot.mtn_mode} {robot.backend}")
    robot_run(lambda ms: 32)
    """)


@pytest.fixture
def writer(tmp_path, monkeypatch):
    """The controller file; the current folder is an empty one of its own (a file there is a bug)."""
    path = tmp_path / "writer.py"
    path.write_text(WRITER)
    cwd = tmp_path / "cwd"
    cwd.mkdir()
    monkeypatch.chdir(cwd)
    return path


def test_mtn_mode_is_passed_recorded_and_checked_on_resume(writer, tmp_path, capsys):
    out, cwd = tmp_path / "dump", Path.cwd()
    argv = ["dump", str(writer), "--out", str(out), "--steps", "3", "--formats", "rgb"]
    assert main(argv + ["--mtn-mode", "webots"]) == 0
    assert json.loads((out / "meta.json").read_text())["parameters"]["mtn_mode"] == "webots"
    assert (out / CONTROLLER_FILES / "where.txt").read_text() == "webots sim"
    assert list(cwd.iterdir()) == []
    capsys.readouterr()
    for other in (["--mtn-mode", "openr"], []):  # the default is openr
        assert main(argv + ["--resume"] + other) == 2
        assert r"cannot resume, the dump was made with other parameters (mtn_mode)" in capsys.readouterr().err
    assert main(argv + ["--resume", "--mtn-mode", "webots"]) == 0
    assert "(0 written now)" in capsys.readouterr().out


def test_memory_stick_is_checked_first_recorded_and_checked_on_resume(writer, tmp_path):
    first, second = tmp_path / "ms1", tmp_path / "ms2"
    for stick in (first, second):
        shutil.copytree(openr_bridge.DEFAULT_MEMORY_STICK, stick)
    out = tmp_path / "dump"
    with pytest.raises(openr_bridge.ConfigError, match=f"{tmp_path / 'nothing'}: no OPEN-R"):
        dump(out, controller=writer, frames=2, formats=("rgb",), backend="openr", memory_stick=tmp_path / "nothing")
    assert not out.exists()
    dump(out, controller=writer, frames=2, formats=("rgb",), backend="openr", memory_stick=first)
    assert json.loads((out / "meta.json").read_text())["parameters"]["memory_stick"] == str(first)
    assert (out / CONTROLLER_FILES / "where.txt").read_text() == "openr openr"
    with pytest.raises(DumpError, match=r"other parameters \(memory_stick\)"):
        dump(out, controller=writer, frames=2, formats=("rgb",), backend="openr", memory_stick=second, resume=True)
    assert (
        dump(
            out, controller=writer, frames=2, formats=("rgb",), backend="openr", memory_stick=first, resume=True
        ).new_frames
        == 0
    )


@pytest.mark.parametrize(
    "option",
    [["--memory-stick", str(openr_bridge.DEFAULT_MEMORY_STICK)], ["--mtn-mode", "openr"]],
    ids=["memory-stick", "mtn-mode"],
)
def test_controller_options_with_env_are_refused(tmp_path, capsys, option):
    out = tmp_path / "dump"
    assert main(["dump", "--env", ENV, "--steps", "2", "--out", str(out), *option]) == 2
    assert capsys.readouterr().err == (
        "aibo-sim: error: --mtn-mode and --memory-stick apply to controller dumps, not to --env\n"
    )
    assert not out.exists()


@pytest.mark.parametrize("option", [["--ball", "1", "0"], ["--pose", "0", "0", "0"], ["--ball-type", "pink"]])
def test_placement_options_with_env_are_refused(tmp_path, capsys, option):
    """An environment places its robot and its own ball: a pink ball asked for is refused, not
    recorded in meta.json over frames of the orange one."""
    out = tmp_path / "dump"
    assert main(["dump", "--env", ENV, "--steps", "2", "--out", str(out), *option]) == 2
    assert capsys.readouterr().err.startswith("aibo-sim: error: --ball, --ball-type and --pose apply to controller")
    assert not out.exists()


@pytest.mark.slow
def test_each_shard_runs_its_controller_in_its_own_folder(writer, tmp_path):
    out = tmp_path / "dump"
    dump(out, controller=writer, frames=2, formats=("rgb",), workers=2)
    for k in range(2):
        assert (out / f"shard_{k}" / CONTROLLER_FILES / "where.txt").read_text() == "openr sim"
    assert not (out / CONTROLLER_FILES).exists() and list(Path.cwd().iterdir()) == []
    assert dump(out, controller=writer, frames=2, formats=("rgb",), workers=2, resume=True).new_frames == 0


def test_an_mp4_only_dump_counts_the_video_bytes(tmp_path):
    out = tmp_path / "dump"
    summary = dump(out, controller=TRACKER, frames=3, formats=("mp4",))
    assert summary.bytes_written == (out / "video.mp4").stat().st_size > 0


def test_a_camera_profile_changed_in_code_is_recorded_and_dumped_as_run_shows_it(tmp_path):
    """A preset with options (a rolling shutter, Sony's lens, a robot's colour) is what the dump renders,
    what meta.json and run.json record beside the name, and what a resume must match."""
    import cv2

    from aibo_sim.camera import PROFILES, RobotColour, camera_profile
    from aibo_sim.runner import run_controller

    robot = RobotColour(gain=(1.02, 0.97, 1.0), offset=(1.0, -2.0, 0.5))
    profile = PROFILES["ers7"].with_options(readout_ms=6.0, lens="sony", robot=robot)
    options = {"lens": "sony", "readout_ms": 6.0, "robot": {"gain": [1.02, 0.97, 1.0], "offset": [1.0, -2.0, 0.5]}}
    assert camera_profile("ers7", options) == profile and hash(camera_profile("ers7", options).robot) == hash(robot)
    out = tmp_path / "dump"
    dump(out, controller=TRACKER, frames=3, formats=("rgb",), camera=CameraConfig(profile))
    meta = json.loads((out / "meta.json").read_text())
    assert meta["parameters"]["camera_profile_options"] == options
    assert meta["camera"]["profile_options"] == options and meta["camera"]["lens"] == "sony"
    run = run_controller(TRACKER, duration=0.1, out=tmp_path / "run", camera=CameraConfig(profile))
    preset = run_controller(TRACKER, duration=0.1, out=tmp_path / "preset")
    assert run.camera["profile_options"] == meta["camera"]["profile_options"] and preset.camera["profile_options"] == {}
    for name in ("000000.png", "000002.png"):
        dumped, ran = (cv2.imread(str(folder / name)) for folder in (out / "rgb", tmp_path / "run" / "frames"))
        assert (dumped == ran).all() and not (ran == cv2.imread(str(tmp_path / "preset" / "frames" / name))).all()
    with pytest.raises(DumpError, match=r"other parameters \(camera_profile_options\)"):
        dump(out, controller=TRACKER, frames=3, formats=("rgb",), resume=True)
    dump(out, controller=TRACKER, frames=3, formats=("rgb",), resume=True, camera=CameraConfig(profile))
