"""Bad input gets exit status 2 and one line naming it, never a traceback; a controller's own
end (an exception, sys.exit, Ctrl-C, a robot_die function that raises) is reported as such;
CONNECT.CFG is parsed in linear time, quoted briefly and read only from a regular file (issue 15)."""

import json
import math
import os
import re
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from aibo_sim.cli import main
from aibo_sim.robot import Robot
from aibo_sim.runner import ControllerFailed, run_controller
from aibo_sim.sim import ModelError, Simulation
from openr_bridge import ConfigError, OpenRSystem, parse_connect_cfg, parse_stub_cfg
from openr_bridge.config import QUOTE_LIMIT, load_connect_cfg
from openr_bridge.wrapper import CAMERA_CONNECTION

ROOT = Path(__file__).resolve().parents[1]
SCRIPTED = Path(__file__).parent / "controllers" / "scripted_head.py"
DUMMY_LINE = "Controller.DummySubject.DontConnect.S OVirtualRobotComm.DummyObserver.DontConnect.O"


def one_error_line(capsys, *words) -> str:
    """The command's stderr: one line, no traceback, holding every one of ``words``."""
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err[:2000]
    for word in words:
        assert word in err, err
    return err


def controller(tmp_path, body: str, name: str = "ctl.py") -> Path:
    path = tmp_path / name
    path.write_text("from aibo_sim.controller import *\n" + body)
    return path


# ----------------------------------------------------------------------------- duration


@pytest.mark.parametrize("value", ["inf", "nan", "-inf", "1e300"])
def test_duration_that_is_not_a_finite_number_exits_2(value, capsys):
    with pytest.raises(SystemExit) as caught:
        main(["run", str(SCRIPTED), f"--duration={value}"])
    assert caught.value.code == 2
    one_error_line(capsys, "--duration", value)


@pytest.mark.parametrize("value", [math.inf, math.nan, 0, -1.0, "10", None, True])
def test_run_controller_refuses_a_bad_duration(value):
    with pytest.raises(ValueError, match="^duration "):  # the parameter's name: the CLI's option is --duration
        run_controller(SCRIPTED, duration=value)


def test_a_run_shorter_than_one_joint_frame_is_refused(tmp_path, capsys):
    assert main(["run", str(SCRIPTED), "--duration", "0.004", "--out", str(tmp_path / "out")]) == 2
    assert one_error_line(capsys) == (
        "aibo-sim: error: --duration 0.004 s: shorter than one 8 ms joint frame: nothing would run"
    )
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    "command, argument",
    [
        (["run", ""], "controller"),
        (["run", str(SCRIPTED), "--out", ""], "--out"),
        (["run", str(SCRIPTED), "--backend", "openr", "--memory-stick", ""], "--memory-stick"),
        (["render", "--scene", ""], "--scene"),
        (["render", "--out", ""], "--out"),
        (["mtn", "info", ""], "file"),
        (["mtn", "play", ""], "file"),
        (["dump", "", "--out", "d"], "controller"),
        (["dump", str(SCRIPTED), "--out", ""], "--out"),
        (["dump", str(SCRIPTED), "--out", "d", "--backend", "openr", "--memory-stick", ""], "--memory-stick"),
    ],
)
def test_an_empty_path_is_refused_not_read_as_the_current_folder(tmp_path, monkeypatch, capsys, command, argument):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as caught:
        main(command)
    assert caught.value.code == 2
    one_error_line(capsys, f"argument {argument}: an empty string names no file or folder")
    assert not list(tmp_path.iterdir())


def test_an_empty_out_is_refused_by_the_python_api_too_before_anything_is_written(tmp_path, monkeypatch):
    """run_controller(out="") wrote a failed run into the working folder, then a bare FileNotFoundError."""
    from aibo_sim.config import ParameterError
    from aibo_sim.dump import dump
    from aibo_sim.match import run_match
    from aibo_sim.team import RobotSpec

    monkeypatch.chdir(tmp_path)
    for run in (
        lambda: run_controller(SCRIPTED, duration=0.05, out="", progress=False),
        lambda: run_match([RobotSpec("red", 1, None, str(SCRIPTED))], duration=0.05, out="", progress=False),
        lambda: dump("", controller=SCRIPTED, frames=1),
    ):
        with pytest.raises(ParameterError, match="^out '': an empty string names no file or folder$"):
            run()
        assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(
    "command",
    [
        ["run", str(ROOT / "controllers" / "ball_tracker.py"), "--duration", "0.1"],
        ["render", "--settle", "0"],
        ["dump", str(SCRIPTED), "--steps", "2"],
        ["run", str(ROOT / "controllers" / "ball_tracker.py"), "--duration", "0.1", "--robot", "red:1"],
    ],
)
def test_glfw_without_a_display_is_rendering_unavailable_not_the_controllers_fault(
    tmp_path, monkeypatch, capsys, command
):
    """GLFW makes no window without a display and only warns: one line naming MUJOCO_GL, exit 2
    (a run was reported as its controller raising MuJoCo's FatalError), checked before the
    output folder is made (a run wrote a run.json that said failed); a match too."""
    monkeypatch.setenv("MUJOCO_GL", "glfw")
    for variable in ("DISPLAY", "WAYLAND_DISPLAY"):
        monkeypatch.delenv(variable, raising=False)
    assert main(command + ["--out", str(tmp_path / "out")]) == 2
    one_error_line(capsys, "MUJOCO_GL=glfw: cannot create an OpenGL context", "DISPLAY")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    "variables, error",
    [
        pytest.param(
            {"PYOPENGL_PLATFORM": "osmesa"},
            None,
            marks=pytest.mark.skipif(
                not __import__("ctypes.util").util.find_library("OSMesa"), reason="needs libOSMesa (CI installs it)"
            ),
        ),
        (
            {"MUJOCO_GL": "egl", "PYOPENGL_PLATFORM": "glx"},
            "aibo-sim: error: MUJOCO_GL=egl and PYOPENGL_PLATFORM=glx disagree: unset PYOPENGL_PLATFORM, "
            "or set both to egl or to osmesa",
        ),
    ],
    ids=["pyopengl osmesa", "disagree"],
)
def test_pyopengl_platform_alone_chooses_the_backend_and_against_mujoco_gl_is_one_line(tmp_path, variables, error):
    """PYOPENGL_PLATFORM=osmesa alone had EGL chosen beside it, and every render failed asking to
    install what was installed, in MuJoCo's words with a literal '{!r}'."""
    environment = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}
    command = [sys.executable, "-m", "aibo_sim.cli", "render", "--settle", "0", "--out", str(tmp_path / "out")]
    result = subprocess.run(command, env={**environment, **variables}, capture_output=True, text=True, timeout=300)
    if error is None:
        assert result.returncode == 0 and (tmp_path / "out" / "head_camera.png").exists(), result.stderr
    else:
        assert result.returncode == 2 and result.stderr.strip() == error, result.stderr
        assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("match", [[], ["--robot", "red:1:0,0,0:{stick}"]], ids=["alone", "match"])
@pytest.mark.parametrize("command", ["run", "dump"])
def test_a_stick_whose_object_is_not_built_is_refused_before_any_folder(tmp_path, capsys, command, match):
    """Its OBJECT.CFG line named, exit 2, no folder (a run made its folder and run.json first)."""
    stick = tmp_path / "MS"
    (stick / "OPEN-R" / "MW" / "CONF").mkdir(parents=True)
    (stick / "OPEN-R" / "MW" / "CONF" / "OBJECT.CFG").write_text("/MS/OPEN-R/MW/OBJS/NOPE.BIN\n")
    length = ["--duration", "0.1"] if command == "run" else ["--steps", "2"]
    robots = [argument.format(stick=stick) for argument in match]
    assert main([command, str(stick), *robots, *length, "--out", str(tmp_path / "out")]) == 2
    one_error_line(capsys, "OBJECT.CFG:1: cannot read /MS/OPEN-R/MW/OBJS/NOPE.BIN", "not built?")
    assert not (tmp_path / "out").exists()


# ----------------------------------------------------------------------------- scenes


@pytest.fixture
def scenes(tmp_path):
    """A scene without the robot, and the robot without its keyframes."""
    no_robot = tmp_path / "no_robot.xml"
    no_robot.write_text('<mujoco><worldbody><body name="box"><freejoint/><geom size=".1"/></body></worldbody></mujoco>')
    no_stand = tmp_path / "no_stand.xml"
    no_stand.write_text(re.sub(r"<keyframe>.*?</keyframe>", "", (ROOT / "models" / "ers7.xml").read_text(), flags=re.S))
    return no_robot, no_stand


def test_a_scene_without_the_robot_or_its_stand_keyframe_is_a_model_error(scenes):
    no_robot, no_stand = scenes
    with pytest.raises(ModelError, match=rf"{re.escape(str(no_robot))}: no ERS-7 robot in this scene \(missing body"):
        Simulation(no_robot)
    with pytest.raises(ModelError, match=rf"{re.escape(str(no_stand))}: no keyframe 'stand'.*keyframes: none"):
        Simulation(no_stand)
    Simulation(ROOT / "models" / "ers7.xml").close()  # the robot alone is a scene


@pytest.mark.parametrize(
    "command",
    [["run", str(SCRIPTED), "--duration", "0.1"], ["render", "--settle", "0"], ["mtn", "play", "WALKFWD.MTN"]],
)
def test_cli_with_a_scene_without_the_robot_exits_2(scenes, command, tmp_path, capsys):
    no_robot, no_stand = scenes
    out = ["--out", str(tmp_path / "out")] if command[0] == "render" else []
    assert main(command + out + ["--scene", str(no_robot)]) == 2
    one_error_line(capsys, str(no_robot), "no ERS-7 robot")
    assert main(command + out + ["--scene", str(no_stand)]) == 2
    one_error_line(capsys, str(no_stand), "no keyframe 'stand'")


@pytest.mark.parametrize(
    "command",
    [
        ["run", str(SCRIPTED), "--duration", "0.1"],
        ["render", "--settle", "0"],
        ["dump", str(SCRIPTED), "--steps", "3"],
        ["dump", str(SCRIPTED), "--steps", "4", "--workers", "2"],
        ["mtn", "play", "STAND.MTN"],
    ],
)
def test_ball_placed_in_a_scene_whose_ball_has_no_free_joint_exits_2(tmp_path, command, capsys):
    """A scene's 'ball' body fixed to the world (no joint) cannot take ``--ball``: one line, exit 2,
    and no output folder made."""
    models = tmp_path / "models"
    shutil.copytree(ROOT / "models", models)
    scene = models / "scene.xml"
    scene.write_text(scene.read_text().replace('<freejoint name="ball"/>', ""))
    out = ["--out", str(tmp_path / "out")] if command[0] in ("render", "dump") else []
    assert main(command + out + ["--scene", str(scene), "--ball", "0.3", "0"]) == 2
    one_error_line(capsys, "--ball 0.3 0: this scene's body 'ball' cannot be placed: it needs one free joint")
    assert not (tmp_path / "out").exists()


def broken_models(tmp_path: Path, fault: str) -> Path:
    """A copy of the models with one fault; its scene."""
    models = tmp_path / "models"
    shutil.copytree(ROOT / "models", models)
    scene, robot = models / "scene.xml", models / "ers7.xml"
    if fault == "ball geom":
        scene.write_text(scene.read_text().replace('<geom name="ball"', '<geom name="myball"'))
    elif fault == "tracking camera":
        robot.write_text(re.sub(r'<camera name="tracking"[^>]*/>', "", robot.read_text()))
    elif fault == "fifo":
        os.mkfifo(models / "extra.xml")
        scene.write_text(scene.read_text().replace("<worldbody>", '<include file="extra.xml"/><worldbody>', 1))
    else:  # a FIFO that a file in a subfolder includes, found beside it as MuJoCo finds it
        (models / "sub" / "parts").mkdir(parents=True)
        (models / "sub" / "a.xml").write_text('<mujoco><include file="parts/b.xml"/></mujoco>')
        os.mkfifo(models / "sub" / "parts" / "b.xml")
        scene.write_text(scene.read_text().replace("<worldbody>", '<include file="sub/a.xml"/><worldbody>', 1))
    return scene


@pytest.mark.parametrize(
    "fault, error",
    [
        ("ball geom", "the body 'ball' needs its geom named 'ball'"),
        ("tracking camera", "no ERS-7 robot in this scene (missing camera 'tracking')"),
        ("fifo", "includes extra.xml: not a regular file"),
        ("nested fifo", "a.xml: includes parts/b.xml: not a regular file"),
    ],
)
@pytest.mark.parametrize(
    "command",
    [
        ["run", str(SCRIPTED), "--duration", "0.1"],
        ["render", "--settle", "0"],
        ["dump", str(SCRIPTED), "--steps", "2"],
        ["mtn", "play", "STAND.MTN", "--ball", "0.5", "0.1"],  # without --ball it plays without the ball
    ],
)
def test_a_scene_every_command_cannot_use_is_refused_alike_before_any_folder(tmp_path, command, fault, error, capsys):
    """A ball whose geom has another name (a KeyError deep in render, dump, --ball), a robot
    without its tracking camera (render's KeyError; run took it) and an included FIFO (a hang)."""
    scene = broken_models(tmp_path, fault)
    out = ["--out", str(tmp_path / "out")] if command[0] in ("render", "dump") else []
    assert main(command + out + ["--scene", str(scene)]) == 2
    one_error_line(capsys, str(scene.parent), error)  # the scene, or the file of its that includes
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("timestep", ["0", "-0.002", "0.003", "0.016"])
@pytest.mark.parametrize(
    "command",
    [
        ["run", str(SCRIPTED), "--duration", "0.1"],
        ["render", "--settle", "0"],
        ["dump", str(SCRIPTED), "--steps", "3"],
        ["mtn", "play", "STAND.MTN"],
    ],
)
def test_a_timestep_that_is_not_a_positive_divisor_of_8_ms_exits_2(tmp_path, command, timestep, capsys):
    """Zero (a division by zero), negative (physics that never ran: time stood still) or not
    dividing the 8 ms joint frame: one line naming the scene, and no output folder."""
    models = tmp_path / "models"
    shutil.copytree(ROOT / "models", models)
    robot = models / "ers7.xml"
    robot.write_text(robot.read_text().replace('timestep="0.002"', f'timestep="{timestep}"'))
    out = ["--out", str(tmp_path / "out")] if command[0] in ("render", "dump") else []
    assert main(command + out + ["--scene", str(models / "scene.xml")]) == 2
    one_error_line(capsys, str(models / "scene.xml"), f"the timestep ({float(timestep)} s) must be positive and divide")
    assert not (tmp_path / "out").exists()


def test_dump_refuses_a_policy_for_a_controller(tmp_path, capsys):
    assert main(["dump", str(SCRIPTED), "--steps", "3", "--policy", "zero", "--out", str(tmp_path / "out")]) == 2
    one_error_line(capsys, "--policy applies to --env dumps: a controller chooses its own actions")
    assert not (tmp_path / "out").exists()


def test_a_fifo_as_the_scene_is_refused(tmp_path, capsys):
    fifo = tmp_path / "scene.xml"
    os.mkfifo(fifo)
    assert main(["run", str(SCRIPTED), "--scene", str(fifo)]) == 2
    one_error_line(capsys, str(fifo), "not a regular file")


@pytest.mark.parametrize("options", [[], ["--ball-type", "pink"], ["--robot", "red:1", "--robot", "blue:1"]])
def test_a_scene_not_named_xml_is_refused_alike_in_every_mode(tmp_path, capsys, options):
    """MuJoCo's MjSpec (a pink ball, a match) finds a file's reader by its extension: such a scene
    loaded for a plain run, then failed there with "could not find decoder" after a warning line."""
    models = tmp_path / "models"
    shutil.copytree(ROOT / "models", models)
    scene = models / "scene.field"
    (models / "scene.xml").rename(scene)
    out = tmp_path / "out"
    assert main(["run", str(SCRIPTED), "--duration", "0.1", "--scene", str(scene), "--out", str(out), *options]) == 2
    one_error_line(capsys, f"{scene}: not an MJCF file's name: a scene is read by its extension, .xml")
    assert not out.exists()


@pytest.mark.skipif(os.geteuid() == 0, reason="root reads a file without read permission")
def test_a_scene_without_read_permission_is_named_so(tmp_path, capsys):
    scene = tmp_path / "scene.xml"
    scene.write_text((ROOT / "models" / "scene.xml").read_text())
    scene.chmod(0)
    assert main(["run", str(SCRIPTED), "--scene", str(scene)]) == 2
    one_error_line(capsys, f"{scene}: cannot read: Permission denied")


def test_a_fifo_as_a_c_controller_or_its_header_is_refused_without_waiting(tmp_path, capsys):
    """A FIFO controller was "no such controller file"; a FIFO header, which gcc opens and waits
    on, held the command for ever."""
    fifo = tmp_path / "ctl.c"
    os.mkfifo(fifo)
    assert main(["run", str(fifo)]) == 2
    one_error_line(capsys, f"{fifo}: not a regular file")
    folder = tmp_path / "ctl"
    folder.mkdir()
    (folder / "ctl.c").write_text('#include "params.h"\nint main(void) { return 0; }\n')
    os.mkfifo(folder / "params.h")
    assert main(["run", str(folder)]) == 2
    one_error_line(capsys, f"{folder / 'params.h'}: included by {folder / 'ctl.c'}: not a regular file")


# ----------------------------------------------------------------------------- dump of another env


def test_dump_of_a_non_aibo_environment_exits_2(tmp_path, capsys):
    out = tmp_path / "dump"
    assert main(["dump", "--env", "CartPole-v1", "--out", str(out)]) == 2
    one_error_line(capsys, "CartPole-v1", "not an aibo_sim environment")
    assert not out.exists()


# ----------------------------------------------------------------------------- placements


@pytest.mark.parametrize(
    "function, args, name",
    [
        ("place_ball", (math.nan, 0.0), "x"),
        ("place_ball", (0.0, math.inf), "y"),
        ("place_ball", (1e300, 0.0), "x"),
        ("place_ball", (0.0, "1"), "y"),
        ("place_robot", (math.nan, 0.0, 0.0), "x"),
        ("place_robot", (0.0, -math.inf, 0.0), "y"),
        ("place_robot", (0.0, 0.0, 1e300), "yaw"),
        ("place_robot", (0.0, 0.0, None), "yaw"),
    ],
)
def test_placements_that_are_not_finite_are_refused_naming_the_argument(function, args, name):
    sim = Simulation()
    try:
        before = sim.data.qpos.copy()
        with pytest.raises(ValueError, match=rf"{function}: {name}\b"):
            getattr(sim, function)(*args)
        np.testing.assert_array_equal(sim.data.qpos, before)  # nothing moved, no MuJoCo reset
        getattr(sim, function)(*[1.0] * len(args))  # finite values still work
    finally:
        sim.close()


PLACED = [
    ["run", str(SCRIPTED), "--duration", "0.1"],
    ["render", "--settle", "0"],
    ["dump", str(SCRIPTED), "--steps", "3"],
]


@pytest.mark.parametrize("command", PLACED + [["mtn", "play", "STAND.MTN"]])
@pytest.mark.parametrize(
    "scene", [[], ["--scene", str(Path(__file__).parents[1] / "models" / "scene.xml")]], ids=["", "field named"]
)
@pytest.mark.parametrize(
    "placement, message",
    [
        (["--pose", "3", "0", "0"], r"--pose 3 0 0: the robot would overlap wall_skyblue by \d+\.\d cm"),
        (["--ball", "-0.12", "0.06"], r"--ball -0.12 0.06: the ball would overlap the robot by \d+\.\d cm"),
        (["--pose", "50", "0", "0"], r"--pose 50 0 0: off the carpet \(\|x\| <= 3 m\) of the default field"),
        (["--ball", "0", "2.5"], r"--ball 0 2.5: off the carpet \(\|y\| <= 2 m\) of the default field"),
    ],
)
def test_a_robot_or_ball_placed_into_something_exits_2_naming_the_option(
    tmp_path, command, scene, placement, message, capsys
):
    """Placed into a wall or into each other, the robot and ball would be flung apart at the
    first step: one line naming the option, exit 2, no output folder. The field named with
    --scene is the default field (off its carpet went unchecked then)."""
    out = ["--out", str(tmp_path / "out")] if command[0] in ("render", "dump") else []
    assert main(command + out + scene + placement) == 2
    assert re.fullmatch(rf"aibo-sim: error: {message}\n", capsys.readouterr().err)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("command", PLACED)
def test_a_robot_placed_onto_the_scenes_ball_exits_2(tmp_path, command, capsys):
    """The ball rests at (0.5, 0) in the scene: a pose that puts a leg through it is refused."""
    out = ["--out", str(tmp_path / "out")] if command[0] in ("render", "dump") else []
    assert main(command + out + ["--pose", "0.62", "-0.06", "0"]) == 2
    one_error_line(capsys, "--pose 0.62 -0.06 0: the robot would overlap the ball by")
    assert not (tmp_path / "out").exists()


def test_placements_clear_of_everything_are_accepted(tmp_path):
    """Beside the wall, beside the robot: no overlap, so no error (the check is not a fence)."""
    assert main(["mtn", "play", "STAND.MTN", "--pose", "2.5", "0", "0", "--ball", "2.5", "0.3"]) == 0
    assert main(["mtn", "play", "STAND.MTN", "--ball", "-0.25", "0"]) == 0


# ----------------------------------------------------------------------------- memory sticks


def memory_stick(tmp_path, text) -> Path:
    conf = tmp_path / "ms" / "OPEN-R" / "MW" / "CONF"
    conf.mkdir(parents=True)
    (conf / "CONNECT.CFG").write_text(text)
    return tmp_path / "ms"


@pytest.mark.parametrize(
    "text, words",
    [
        ("", "has no connection"),
        ("# nothing here\n\n", "has no connection"),
        (DUMMY_LINE + "\n", "does not connect Controller.Image.OFbkImageVectorData.O"),
    ],
)
def test_a_memory_stick_without_the_camera_line_is_refused_when_loaded(tmp_path, capsys, text, words):
    stick = memory_stick(tmp_path, text)
    cfg = str(stick / "OPEN-R" / "MW" / "CONF" / "CONNECT.CFG")
    with pytest.raises(
        ConfigError, match=re.escape(f"{cfg}: {words}: the camera needs the line '{CAMERA_CONNECTION}'")
    ):
        OpenRSystem.from_memory_stick(stick)
    sim = Simulation()
    try:
        with pytest.raises(ConfigError, match=words):
            Robot(sim, backend="openr", memory_stick=stick)  # at the backend's creation, not at camera_get_image
    finally:
        sim.close()
    assert main(["run", str(SCRIPTED), "--backend", "openr", "--memory-stick", str(stick), "--duration", "0.1"]) == 2
    err = one_error_line(capsys, cfg, words)
    assert "raised" not in err  # not reported as the controller's failure


def test_connect_cfg_of_20000_lines_reports_the_first_error_at_once(tmp_path):
    """Was quadratic: 45 s before the error on line 1 (no timing here: a slow suite shows it)."""
    lines = [f"Obj{i}.Sub.Data.S Other.Sub.Data.O" for i in range(20_000)]
    connections = parse_connect_cfg("\n".join(lines))
    assert len(connections) == 20_000
    stick = memory_stick(tmp_path, "\n".join(lines))
    with pytest.raises(ConfigError, match=r"CONNECT.CFG:1: unknown object 'Obj0'"):
        OpenRSystem.from_memory_stick(stick)
    with pytest.raises(ConfigError, match="CONNECT.CFG:20001: connection repeated from line 1"):
        parse_connect_cfg("\n".join(lines + lines[:1]))


def test_stub_cfg_of_20000_services_and_long_blank_runs_parse_in_linear_time():
    services = "".join(f'Service : "Obj.S{i}.Data.O", null, Notify()\n' for i in range(20_000))
    stub = parse_stub_cfg(
        "ObjectName : Obj\nNumOfOSubject : 1\nNumOfOObserver : 20000\n"
        'Service : "Obj.Dummy.Data.S", null, null\n' + services
    )
    assert len(stub.services) == 20_001
    with pytest.raises(ConfigError, match="not a name"):  # a lazy expression backtracked quadratically over blanks
        parse_stub_cfg("ObjectName : A" + " " * 1_000_000 + "B\nNumOfOSubject : 1\nNumOfOObserver : 1\n")


@pytest.mark.slow
def test_a_50_mb_line_is_quoted_briefly(tmp_path):
    huge = "A" * 50_000_000
    for text in (f"{huge} B.y.char.O", f"A.x.char.S B.y.char.O {huge}", f"A.x.{huge}.S B.y.char.O"):
        with pytest.raises(ConfigError) as caught:
            parse_connect_cfg(text)
        message = str(caught.value)
        assert len(message) < 2 * QUOTE_LIMIT + 200 and "characters in all" in message, message[:500]
    with pytest.raises(ConfigError) as caught:  # a valid line whose object no system has
        OpenRSystem(parse_connect_cfg(f"{huge}.x.char.S B.y.char.O"))
    assert len(str(caught.value)) < 2 * QUOTE_LIMIT + 200 and "characters in all" in str(caught.value)


def test_a_fifo_in_place_of_connect_cfg_is_refused_without_waiting(tmp_path):
    conf = tmp_path / "OPEN-R" / "MW" / "CONF"
    conf.mkdir(parents=True)
    fifo = conf / "CONNECT.CFG"
    os.mkfifo(fifo)

    def unblock():  # should the reader wait for a writer after all, release it so that the test fails, not hangs
        try:
            os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
        except OSError:
            pass

    timer = threading.Timer(5, unblock)
    timer.start()
    try:
        with pytest.raises(ConfigError, match="cannot read: a FIFO, not a regular file"):  # waiting read it empty
            OpenRSystem.from_memory_stick(tmp_path)
    finally:
        timer.cancel()
    folder = tmp_path / "other" / "CONNECT.CFG"
    folder.mkdir(parents=True)
    with pytest.raises(ConfigError, match="cannot read: a folder"):
        load_connect_cfg(folder)


# ----------------------------------------------------------------------------- how a controller ends


def test_a_raising_robot_die_function_does_not_hide_the_controllers_exception(tmp_path, capsys):
    bad = controller(
        tmp_path,
        "def cleanup():\n    raise OSError('cleanup failed')\n"
        "robot_die(cleanup)\nrobot_step(16)\nraise RuntimeError('boom')\n",
    )
    with pytest.raises(ControllerFailed) as caught:
        run_controller(bad, duration=1.0)
    message = str(caught.value)
    assert "raised at simulated t = 0.016 s" in message and "RuntimeError: boom" in message
    assert "then its robot_die function cleanup raised" in message and "OSError: cleanup failed" in message
    assert message.index("RuntimeError: boom") < message.index("OSError: cleanup failed")
    assert main(["run", str(bad), "--duration", "1"]) == 1
    err = capsys.readouterr().err
    assert "RuntimeError: boom" in err and "OSError: cleanup failed" in err


def test_every_robot_die_function_runs_and_one_that_raises_fails_the_run(tmp_path):
    ok = controller(
        tmp_path,
        "def first():\n    raise ValueError('first')\n"
        "def second():\n    open('second.txt', 'w').write('ran')\n"
        "robot_die(first)\nrobot_die(second)\nwhile True:\n    robot_step(32)\n",
    )
    with pytest.raises(
        ControllerFailed, match=r"ended at simulated t = 0\.200 s;\nits robot_die function first raised"
    ):
        run_controller(ok, duration=0.2, out=tmp_path / "out")
    assert (tmp_path / "out" / "second.txt").read_text() == "ran"


@pytest.mark.parametrize("code, status", [("3", 1), ("'stopped by the user'", 1), ("0", 0), ("", 0), ("None", 0)])
def test_sys_exit_from_a_controller_is_its_exit_not_a_divergence(tmp_path, capsys, code, status):
    ctl = controller(
        tmp_path,
        f"import sys\nrobot_die(lambda: open('die.txt', 'w').write('ran'))\nrobot_step(64)\nsys.exit({code})\n",
    )
    out = tmp_path / "out"
    assert main(["run", str(ctl), "--duration", "1", "--out", str(out)]) == status
    err = capsys.readouterr().err
    assert "diverged" not in err and (out / "die.txt").read_text() == "ran"
    if status:
        assert f"ctl.py exited with sys.exit({code}) at simulated t = 0.064 s" in err
        with pytest.raises(ControllerFailed) as failed:
            run_controller(ctl, duration=1.0, out=tmp_path / "again")
        assert failed.value.exit_status == eval(code)
    else:
        assert run_controller(ctl, duration=1.0, out=tmp_path / "again").simulated_s == pytest.approx(
            0.064
        )  # ends there


def test_ctrl_c_in_a_controller_exits_130_after_its_robot_die_functions(tmp_path, capsys):
    ctl = controller(
        tmp_path, "robot_die(lambda: open('die.txt', 'w').write('ran'))\nrobot_step(8)\nraise KeyboardInterrupt\n"
    )
    out = tmp_path / "out"
    assert main(["run", str(ctl), "--duration", "1", "--out", str(out)]) == 130
    assert "interrupted" in capsys.readouterr().err
    assert (out / "die.txt").read_text() == "ran"
    run = json.loads((out / "run.json").read_text())
    assert (run["status"], run["simulated_s"], run["camera"]["profile"]) == ("interrupted", 0.008, "ers7")


def test_a_controller_catching_every_exception_around_its_step_still_ends_with_its_run(tmp_path):
    """The run's end (SimulationEnd) is no Exception: ``except Exception`` does not keep it going."""
    ctl = controller(tmp_path, "while True:\n    try:\n        robot_step(8)\n    except Exception:\n        pass\n")
    assert run_controller(ctl, duration=0.1, out=tmp_path / "out").simulated_s == pytest.approx(0.104)


def test_a_controller_raising_another_base_exception_fails_as_any_error_does(tmp_path, capsys):
    ctl = controller(tmp_path, "robot_step(8)\nraise GeneratorExit('given up')\n")
    out = tmp_path / "out"
    assert main(["run", str(ctl), "--duration", "1", "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert "ctl.py raised at simulated t = 0.008 s" in err and "GeneratorExit: given up" in err
    assert json.loads((out / "run.json").read_text())["status"] == "failed"


def test_a_signal_during_a_match_says_interrupted_for_every_robot(tmp_path, capsys):
    ctl = controller(
        tmp_path,
        "import os, signal\n"
        "robot_step(16)\n"
        "try:  # the first robot here sends it\n"
        "    os.close(os.open('signalled', os.O_CREAT | os.O_EXCL))\n"
        "    os.kill(os.getpid(), signal.SIGTERM)\n"
        "except FileExistsError:\n"
        "    pass\n"
        "while True:\n    robot_step(8)\n",
    )
    out = tmp_path / "out"
    args = ["run", str(ctl), "--robot", "red:1", "--robot", "blue:1", "--duration", "5", "--out", str(out)]
    assert main(args) == 143
    match = json.loads((out / "run.json").read_text())
    robots = [json.loads((out / f"robot{k}" / "run.json").read_text()) for k in (1, 2)]
    assert [match["status"]] + [r["status"] for r in match["robots"] + robots] == ["interrupted"] * 5


def test_a_sigterm_arriving_inside_a_compiled_function_still_ends_the_run_with_143(tmp_path, capsys):
    """A signal's exception raised while numba's (or a C extension's) function returns reaches
    the controller as the cause of a SystemError: the run ends as SIGTERM, not as a failure."""
    ctl = controller(
        tmp_path,
        "from aibo_sim.cli import Terminated\n"
        "robot_die(lambda: open('die.txt', 'w').write('ran'))\n"
        "robot_step(8)\n"
        "try:\n    raise Terminated()\n"
        "except Terminated as interrupt:\n"
        "    raise SystemError('CPUDispatcher(<function smear_taps>) returned a result with an exception set') "
        "from interrupt\n",
    )
    out = tmp_path / "out"
    assert main(["run", str(ctl), "--duration", "1", "--out", str(out)]) == 143
    assert capsys.readouterr().err.strip() == "aibo-sim: terminated (SIGTERM)"
    assert (out / "die.txt").read_text() == "ran"
    assert json.loads((out / "run.json").read_text())["status"] == "interrupted"


def test_any_command_reads_a_signal_behind_a_compiled_functions_system_error_as_that_signal(monkeypatch, capsys):
    import aibo_sim.cli as cli

    def stopped_inside_numba(args):
        try:
            raise cli.Terminated()
        except cli.Terminated as interrupt:
            raise SystemError(
                "CPUDispatcher(<function develop>) returned a result with an exception set"
            ) from interrupt

    def stopped_two_compiled_functions_deep(args):  # numba's error chain: one SystemError a function
        try:
            stopped_inside_numba(args)
        except SystemError as inner:
            raise SystemError("CPUDispatcher(<function smear_taps>) returned a result with an exception set") from inner

    for render in (stopped_inside_numba, stopped_two_compiled_functions_deep):
        monkeypatch.setattr(cli, "_render", render)
        assert main(["render"]) == 143
        assert capsys.readouterr().err.strip() == "aibo-sim: terminated (SIGTERM)"

    def broken(args):
        raise SystemError("a SystemError of its own")

    monkeypatch.setattr(cli, "_render", broken)
    with pytest.raises(SystemError, match="of its own"):  # not a signal: not hidden
        main(["render"])


@pytest.mark.slow
def test_sigterm_ends_a_run_as_ctrl_c_does_with_143(tmp_path):
    import signal
    import subprocess
    import sys

    ctl = controller(
        tmp_path,
        "camera = robot_get_device('PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1')\n"
        "camera_enable(camera, 32)\n"
        "robot_die(lambda: open('die.txt', 'w').write('ran'))\n"
        "while True:\n    robot_step(32)\n",
    )
    out = tmp_path / "out"
    process = subprocess.Popen(
        [sys.executable, "-m", "aibo_sim.cli", "run", str(ctl), "--duration", "1e5", "--out", str(out)],
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 60
    while not list((out / "frames").glob("*.png")) and time.monotonic() < deadline:
        time.sleep(0.05)
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 143 and err.strip() == "aibo-sim: terminated (SIGTERM)", err
    run = json.loads((out / "run.json").read_text())
    frames = sorted(p.name for p in (out / "frames").iterdir())
    assert run["status"] == "interrupted" and run["camera_frames"] == len(frames) > 0
    assert all(name.endswith(".png") and not name.startswith(".") for name in frames)  # no temporary file left
    assert (out / "die.txt").read_text() == "ran"


def test_ctrl_c_while_the_program_loads_its_modules_is_an_interruption(tmp_path):
    """Ctrl-C once MuJoCo's library is mapped (the package still loading: MuJoCo, gymnasium, the
    command line's modules) printed a traceback of the import it hit, or, inside MuJoCo's
    import, "MuJoCo cannot load the OpenGL backend" with exit status 2."""
    import signal
    import subprocess
    import sys

    program = Path(sys.executable).with_name("aibo-sim")
    process = subprocess.Popen(
        [str(program), "run", str(ROOT / "controllers" / "ball_tracker.py"), "--duration", "20"],
        cwd=tmp_path,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    maps, deadline = Path(f"/proc/{process.pid}/maps"), time.monotonic() + 60
    while "libmujoco" not in maps.read_text() and time.monotonic() < deadline:
        time.sleep(0.001)
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 130 and err == "\naibo-sim: interrupted\n", err


def test_ctrl_c_while_the_arguments_are_read_is_an_interruption(monkeypatch, capsys):
    """Ctrl-C in parse_args (1 start in about 18, a reviewer found) printed a traceback."""
    from aibo_sim import cli

    def interrupted():
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "build_parser", interrupted)
    assert cli.main(["run", "x.py"]) == 130
    assert capsys.readouterr().err == "\naibo-sim: interrupted\n"


def test_ctrl_c_while_a_program_imports_aibo_sim_is_not_taken_for_a_missing_opengl(tmp_path):
    """MuJoCo's module turns the KeyboardInterrupt into "ImportError: initialization failed",
    which read as an OpenGL backend that cannot load."""
    import signal
    import subprocess
    import sys

    process = subprocess.Popen(
        [sys.executable, "-c", "import aibo_sim"], cwd=tmp_path, stderr=subprocess.PIPE, text=True
    )
    maps, deadline = Path(f"/proc/{process.pid}/maps"), time.monotonic() + 60
    while "libmujoco" not in maps.read_text() and time.monotonic() < deadline:
        time.sleep(0.001)
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=60)
    assert err.rstrip().endswith("KeyboardInterrupt") and "OpenGL backend" not in err, err


def test_a_run_ends_though_its_controller_left_a_thread_running(tmp_path):
    """Python waits at exit for every thread that is not a daemon: a thread the controller
    started and never ends held the command for ever after its run was over."""
    import subprocess
    import sys

    ctl = controller(
        tmp_path,
        "import threading, time\n"
        "def spin():\n    while True:\n        time.sleep(0.1)\n"
        "threading.Thread(target=spin, name='vision').start()\n"
        "while robot_step(8) != -1:\n    pass\n",
    )
    result = subprocess.run(
        [sys.executable, "-m", "aibo_sim.cli", "run", str(ctl), "--duration", "0.1"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    assert result.stderr == "aibo-sim: the run is over; not waiting for threads still running: 'vision'\n"
    assert "0.10 s simulated" in result.stdout


@pytest.mark.slow
@pytest.mark.parametrize("signals", [1, 2])
def test_a_controller_that_swallows_the_signal_is_stopped_after_the_grace_or_a_second_signal(tmp_path, signals):
    """One signal ends a run even when the controller catches it and steps on: ``STOP_GRACE_S``
    later the process ends with the signal's status; a second signal ends it at once."""
    import signal
    import subprocess
    import sys

    from aibo_sim.cli import STOP_GRACE_S

    ctl = controller(
        tmp_path,
        "open('started', 'w').close()\n"
        "while True:\n    try:\n        robot_step(8)\n    except BaseException:\n        pass\n",
    )
    process = subprocess.Popen(
        [sys.executable, "-m", "aibo_sim.cli", "run", str(ctl), "--duration", "1e5", "--out", str(tmp_path / "out")],
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 60
    while not (tmp_path / "out" / "started").exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    process.send_signal(signal.SIGTERM)
    signalled = time.monotonic()
    if signals == 2:
        time.sleep(0.5)
        process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=60)
    took = time.monotonic() - signalled
    assert process.returncode == 143, err
    if signals == 1:
        assert STOP_GRACE_S <= took and f"still running {STOP_GRACE_S:g} s later: stopped at once" in err
    else:
        assert took < STOP_GRACE_S and "terminated (SIGTERM) again: stopped at once" in err


def test_a_state_mujoco_resets_silently_counts_as_diverged():
    """MuJoCo replaces NaN positions by the model's defaults with only a warning: that is a divergence."""
    import numpy as np

    from aibo_sim.sim import Simulation, SimulationDiverged

    sim = Simulation()
    sim.data.qpos[0] = np.nan
    with pytest.raises(SimulationDiverged, match="diverged"):
        sim.step_frame()
    sim.reset(0)
    sim.step_frame()  # a reset clears the counters
    sim.close()


@pytest.mark.parametrize("command", [["mtn", "info"], ["mtn", "play"], ["run"]])
def test_a_very_long_file_name_is_cut_in_the_message(command, capsys):
    assert main([*command, "x" * 5000 + ".MTN"]) == 2
    message = capsys.readouterr().err
    assert len(message) < 300 and re.search(r"\.\.\. \(50\d\d characters\)", message), message


def test_output_into_a_closed_pipe_ends_quietly_with_141():
    """``aibo-sim mtn info FILE | head -0``: no error message for the reader having left, no traceback."""
    import subprocess
    import sys

    read_end, write_end = os.pipe()
    os.close(read_end)  # the reader leaves before the first line
    try:
        done = subprocess.run(
            [sys.executable, "-m", "aibo_sim.cli", "mtn", "info", str(ROOT / "models/motions/SIT.MTN")],
            stdout=write_end,
            stderr=subprocess.PIPE,
            text=True,
            timeout=60,
        )
    finally:
        os.close(write_end)
    assert (done.returncode, done.stderr) == (141, "")


def test_seeds_beyond_64_bits_are_refused_rather_than_aliased(capsys):
    with pytest.raises(SystemExit) as exited:  # argparse's own error, before anything runs
        main(["render", "--seed", str(2**64), "--out", "unused"])
    assert exited.value.code == 2
    one_error_line(capsys, "--seed", "from 0 to 2**64 - 1")
    with pytest.raises(ValueError, match="seed must be a whole number from 0 to 2\\*\\*64 - 1"):
        Simulation(seed=2**64)


def test_mujoco_s_scene_errors_come_on_one_line(tmp_path, capsys):
    scene = tmp_path / "odd.xml"
    scene.write_text("<mujoco>\n<statistic bogus='1'/>\n</mujoco>\n")
    assert main(["render", "--scene", str(scene), "--out", str(tmp_path / "out")]) == 2
    one_error_line(capsys, "odd.xml", "unrecognized attribute: 'bogus'", "Element 'statistic', line 2")


def test_an_out_that_is_a_file_and_a_missing_side_by_side_frame_are_named(tmp_path, capsys):
    taken = tmp_path / "taken"
    taken.write_text("keep")
    assert main(["render", "--out", str(taken)]) == 2
    one_error_line(capsys, f"--out {taken}: not a folder")
    assert main(["run", str(SCRIPTED), "--duration", "0.1", "--out", str(taken)]) == 2
    one_error_line(capsys, f"--out {taken}: not a folder")
    assert main(["dump", str(SCRIPTED), "--steps", "2", "--out", str(taken)]) == 2  # "cannot create the dump folder"
    one_error_line(capsys, f"--out {taken}: not a folder")
    assert taken.read_text() == "keep"
    assert main(["render", "--side-by-side", str(tmp_path / "real.png"), "--out", str(tmp_path / "out")]) == 2
    one_error_line(capsys, f"--side-by-side {tmp_path / 'real.png'}: no such file")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("shape", [(160, 208), (100, 200, 3)])
def test_a_side_by_side_frame_of_no_layers_size_or_grey_is_refused_naming_both(tmp_path, capsys, shape):
    """Grey would be read as Y = Cr = Cb, wrong colours without a word; a frame is one of the
    layers or the full picture."""
    import cv2
    import numpy as np

    real = tmp_path / "real.png"
    cv2.imwrite(str(real), np.full(shape, 100, np.uint8))
    assert main(["render", "--side-by-side", str(real), "--out", str(tmp_path / "out")]) == 2
    found = f"{shape[1]}x{shape[0]}, {shape[2] if len(shape) == 3 else 1} channel(s)"
    one_error_line(
        capsys,
        f"--side-by-side {real}: not an EasyTrain frame ({found}): "
        "a colour PNG (R, G, B = Y, Cb, Cr) of 208x160, 104x80, 52x40, 416x320",
    )
    assert not (tmp_path / "out").exists()


def test_a_png_with_bytes_after_its_end_is_still_a_picture():
    """Only a PNG cut short (no IEND chunk) is refused unread: bytes after the end are no cut."""
    import cv2
    import numpy as np

    from aibo_sim.files import decode_image

    picture = np.random.default_rng(0).integers(0, 255, (160, 208, 3), np.uint8)
    encoded = cv2.imencode(".png", picture)[1].tobytes()
    assert np.array_equal(decode_image(encoded + b"\0" * 16, cv2.IMREAD_COLOR), picture)
    assert decode_image(encoded[:-1], cv2.IMREAD_COLOR) is None


def test_a_cut_side_by_side_frame_is_one_line_without_opencvs(tmp_path, capfd):
    """libpng's or OpenCV's own line on the process's stderr came before aibo-sim's."""
    import cv2
    import numpy as np

    real = tmp_path / "real.png"
    ok, encoded = cv2.imencode(".png", np.random.default_rng(0).integers(0, 255, (160, 208, 3), np.uint8))
    real.write_bytes(encoded.tobytes()[: encoded.size // 2])
    assert main(["render", "--side-by-side", str(real), "--out", str(tmp_path / "out")]) == 2
    one_error_line(capfd, f"--side-by-side {real}: not an EasyTrain frame (unreadable)")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("repeat", ["0", "10" * 12])
def test_mtn_play_names_a_repeat_out_of_range(capsys, repeat):
    """One beyond any run's length played until it was killed."""
    assert main(["mtn", "play", "SIT.MTN", "--repeat", repeat]) == 2
    assert one_error_line(capsys) == f"aibo-sim: error: --repeat {repeat}: must be a whole number from 1 to 1000000"


def test_play_motion_refuses_the_repeat_counts_the_cli_refuses():
    """repeat=0 reported a motion that did not play; 2.5 was range()'s bare TypeError."""
    from aibo_sim.config import ParameterError
    from aibo_sim.motions import play_motion

    for repeat in (0, -2, 2.5, True):
        with pytest.raises(ParameterError, match=rf"^repeat {repeat}: must be a whole number from 1 to 1000000$"):
            play_motion(ROOT / "models" / "motions" / "SIT.MTN", repeat=repeat)


@pytest.mark.parametrize(
    "length, message",
    [
        (["--steps", "-5"], "--steps must be a whole number from 1 to 1000000, not -5"),
        (["--steps", "10" * 12], f"--steps must be a whole number from 1 to 1000000, not {'10' * 12}"),
        (["--duration", "-2"], "--duration -2.0: must be positive and finite"),
        (
            ["--duration", "0.01"],
            "--duration 0.01 s holds no camera frame: give at least 0.017 s (frames are 1/30 s apart)",
        ),
    ],
)
def test_dump_names_a_length_that_holds_no_frame(tmp_path, capsys, length, message):
    assert main(["dump", str(SCRIPTED), *length, "--out", str(tmp_path / "out")]) == 2
    assert one_error_line(capsys) == f"aibo-sim: error: {message}"
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    "command", [["run", str(SCRIPTED), "--duration", "0.1"], ["dump", str(SCRIPTED), "--steps", "2"]]
)
def test_a_memory_stick_for_the_sim_backend_is_refused_not_ignored(tmp_path, capsys, command):
    stick = tmp_path / "stick"
    (stick / "OPEN-R" / "MW" / "CONF").mkdir(parents=True)
    out = tmp_path / "out"
    assert main(command + ["--memory-stick", str(stick), "--out", str(out)]) == 2
    one_error_line(capsys, "--memory-stick applies to the openr backend (--backend openr): the sim backend")
    assert not out.exists()


def test_a_signal_right_after_a_frame_is_renamed_in_still_counts_that_frame(tmp_path, monkeypatch):
    """Ctrl-C or SIGTERM lands between bytecodes: after a frame's rename, run.json's
    camera_frames must still equal the frames in the folder (a counter was one short)."""
    import aibo_sim.runner as runner

    writer = runner.FrameWriter(tmp_path / "out")
    image = np.zeros((4, 4, 3), np.uint8)
    writer(0, image)
    write = runner.write_file_atomic

    def write_then_interrupt(path, data):
        write(path, data)
        raise KeyboardInterrupt

    monkeypatch.setattr(runner, "write_file_atomic", write_then_interrupt)
    with pytest.raises(KeyboardInterrupt):
        writer(1, image)
    assert sorted(p.name for p in (tmp_path / "out" / "frames").iterdir()) == ["000000.png", "000001.png"]
    assert writer.count == 2
