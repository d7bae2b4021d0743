"""One option family for ``run``, ``render``, ``dump`` and ``mtn play``: the world (--scene,
--pose, --ball, --seed) and the head camera (--camera-profile, --camera-wb, --camera-gain,
--camera-shutter, --camera-full), with the same defaults, meanings and errors."""

import ast
import json
import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from aibo_sim import motions
from aibo_sim.camera import CameraSettings
from aibo_sim.cli import build_parser, main
from aibo_sim.config import CameraConfig, ParameterError, WorldConfig
from aibo_sim.dump.shards import _in_shard
from aibo_sim.field import BALL_RADIUS
from aibo_sim.options import CAMERA_DESTS, WORLD_DESTS, error_line
from aibo_sim.placement import make_out_folder, place
from aibo_sim.runner import run_controller
from aibo_sim.sim import Simulation

ROOT = Path(__file__).resolve().parents[1]
SCRIPTED = Path(__file__).parent / "controllers" / "scripted_head.py"
ROBOT_ONLY = ROOT / "models" / "ers7.xml"  # a scene without a ball
SHARED = (
    "--scene",
    "--pose",
    "--ball",
    "--ball-type",
    "--seed",
    "--camera-profile",
    "--camera-wb",
    "--camera-gain",
    "--camera-shutter",
    "--camera-full",
)
# Each command with the arguments it needs besides the shared options (argparse stops first).
COMMANDS = {
    "run": ["run", str(SCRIPTED)],
    "render": ["render"],
    "dump": ["dump", str(SCRIPTED), "--out", "unused"],
    "mtn play": ["mtn", "play", "SIT.MTN"],
}


def _subparsers(parser):
    return next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction").choices


def _command_parsers():
    commands = _subparsers(build_parser())
    return {
        "run": commands["run"],
        "render": commands["render"],
        "dump": commands["dump"],
        "mtn play": _subparsers(commands["mtn"])["play"],
    }


def _shared_actions(parser):
    """option string -> what defines its meaning: destination, default, type, choices, nargs, action."""
    actions = {}
    for action in parser._actions:
        for option in action.option_strings:
            if option in SHARED:
                actions[option] = (
                    action.dest,
                    action.default,
                    action.type,
                    action.choices and tuple(action.choices),
                    action.nargs,
                    type(action).__name__,
                    action.metavar,
                )
    return actions


def test_a_negative_number_in_any_form_is_a_value_and_minus_inf_is_refused_as_inf(capsys):
    """argparse read -1e-3, -1. and -inf as options' names: "--pose: expected 3 arguments"."""
    for name, argv in COMMANDS.items():
        args = build_parser().parse_args([*argv, "--pose", "-1e-3", "-1.", "-9_0", "--ball", "-.5", "-2E-1"])
        assert (args.pose, args.ball) == ([-0.001, -1.0, -90.0], [-0.5, -0.2]), name
        for value in ("-inf", "inf", "-nan"):
            with pytest.raises(SystemExit):
                build_parser().parse_args([*argv, "--ball", value, "0"])
            assert f"argument --ball: '{value}' is not a finite number" in capsys.readouterr().err, (name, value)


def test_every_command_takes_the_same_world_and_camera_options():
    parsers = _command_parsers()
    options = {name: _shared_actions(parser) for name, parser in parsers.items()}
    for name, actions in options.items():
        assert sorted(actions) == sorted(SHARED), name
        assert actions == options["run"], f"{name} differs from run"
    defaults = {
        name: vars(parser.parse_args(COMMANDS[name][2 if name == "mtn play" else 1 :]))
        for name, parser in parsers.items()
    }
    expected = {
        "scene": None,
        "pose": None,
        "ball": None,
        "ball_type": "robocup",
        "seed": 0,
        "camera_profile": "ers7",
        "camera_wb": "fl",
        "camera_gain": "mid",
        "camera_shutter": "mid",
        "camera_full": False,
    }
    assert set(expected) == set(WORLD_DESTS + CAMERA_DESTS)
    for name, values in defaults.items():
        assert {k: values[k] for k in expected} == expected, name


def test_shared_options_parse_to_the_same_values_everywhere():
    given = [
        "--scene",
        "x.xml",
        "--pose",
        "-1",
        "0.5",
        "90",
        "--ball",
        "0.2",
        "-0.3",
        "--ball-type",
        "pink",
        "--seed",
        "7",
        "--camera-profile",
        "ideal",
        "--camera-wb",
        "outdoor",
        "--camera-gain",
        "high",
        "--camera-shutter",
        "fast",
        "--camera-full",
    ]
    parsed = {}
    for name, argv in COMMANDS.items():
        args = build_parser().parse_args(argv + given)
        parsed[name] = {k: getattr(args, k) for k in WORLD_DESTS + CAMERA_DESTS}
    assert parsed["run"]["pose"] == [-1.0, 0.5, 90.0] and parsed["run"]["ball"] == [0.2, -0.3]
    assert all(values == parsed["run"] for values in parsed.values())


BAD = [
    (["--ball", "nan", "nan"], "--ball"),
    (["--ball", "1", "inf"], "--ball"),
    (["--ball", "one", "0"], "--ball"),
    (["--pose", "0", "0", "-inf"], "--pose"),
    (["--pose", "1e9", "0", "0"], "--pose"),
    (["--seed", "-1"], "--seed"),
    (["--seed", "1.5"], "--seed"),
    (["--camera-profile", "fancy"], "--camera-profile"),
    (["--camera-wb", "sunny"], "--camera-wb"),
    (["--camera-gain", "max"], "--camera-gain"),
    (["--camera-shutter", "1"], "--camera-shutter"),
]


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize("bad, option", BAD, ids=[" ".join(b) for b, _ in BAD])
def test_bad_values_exit_2_with_one_line_naming_the_option(command, bad, option, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(COMMANDS[command] + bad)
    assert exit_info.value.code == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.splitlines()
    assert len(lines) == 1, captured.err
    assert f"argument {option}" in lines[0] and "error" in lines[0] and "Traceback" not in captured.err


@pytest.mark.parametrize("command", COMMANDS)
def test_an_unknown_option_is_named_with_its_command(command, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(COMMANDS[command] + ["--no-such-option", "1"])
    assert exit_info.value.code == 2
    assert capsys.readouterr().err == (
        f"aibo-sim {command}: error: unrecognized arguments: --no-such-option 1 (see aibo-sim {command} --help)\n"
    )


def test_each_commands_help_gives_its_own_ball_default():
    """mtn play plays without a ball unless --ball places one; the others keep the scene's."""
    for name, parser in _command_parsers().items():
        (ball,) = [action for action in parser._actions if "--ball" in action.option_strings]
        assert ball.help.endswith("default: no ball" if name == "mtn play" else "default: the scene's"), name


def test_runtime_bad_input_exits_2_with_one_line(tmp_path, capsys):
    assert main(["mtn", "play", "SIT.MTN", "--scene", str(ROBOT_ONLY), "--ball", "0", "0"]) == 2
    assert "no body named 'ball'" in capsys.readouterr().err
    assert main(["render", "--out", str(tmp_path), "--keyframe", "lying"]) == 2
    err = capsys.readouterr().err
    assert "--keyframe 'lying'" in err and len(err.splitlines()) == 1
    assert main(["render", "--out", str(tmp_path), "--settle", "-1"]) == 2
    assert "--settle" in capsys.readouterr().err


def test_the_world_config_refuses_non_finite_pose_and_ball_naming_them():
    with pytest.raises(ParameterError, match="^pose 0.0 nan 0.0: must be 3 finite numbers$"):
        WorldConfig(pose=(0.0, math.nan, 0.0))
    with pytest.raises(ParameterError, match="^ball inf 0.0: must be 2 finite numbers$"):
        WorldConfig(ball=(math.inf, 0.0))
    with pytest.raises(ParameterError, match="^pose 1.0 2.0: must be 3 finite numbers$") as caught:
        WorldConfig(pose=(1.0, 2.0))
    assert error_line(caught.value) == "--pose 1.0 2.0: must be 3 finite numbers"
    with pytest.raises(ParameterError, match="^seed -1: must be a whole number") as caught:
        WorldConfig(seed=-1)
    assert error_line(caught.value).startswith("--seed -1: ")
    with pytest.raises(ParameterError, match="^ball_type blue:") as caught:
        WorldConfig(ball_type="blue")
    assert error_line(caught.value).startswith("--ball-type blue: ")


def test_configs_are_recorded_whole_and_read_back(tmp_path):
    world = WorldConfig(seed=7, pose=(0.1, -0.2, 30.0), ball=(0.6, 0.25), ball_type="pink")
    camera = CameraConfig("ideal", True, CameraSettings("indoor", "high", "slow"))
    assert WorldConfig.from_dict(world.as_dict()) == world and CameraConfig.from_dict(camera.as_dict()) == camera
    run_controller(SCRIPTED, duration=0.1, out=tmp_path / "sim", world=world, camera=camera)
    recorded = json.loads((tmp_path / "sim" / "run.json").read_text())
    assert WorldConfig.from_dict(recorded) == world and CameraConfig.from_dict(recorded["camera"]) == camera
    served = run_controller(SCRIPTED, duration=0.1, backend="openr", out=tmp_path / "openr", world=world, camera=camera)
    served = served.camera
    assert served["width"] == 208 and CameraConfig.from_dict(served) == camera  # layer H served, full asked


def test_the_library_names_parameters_and_the_command_line_its_options(tmp_path):
    sim = Simulation(camera=CameraConfig("ideal"))
    try:
        with pytest.raises(ParameterError, match="^pose 0.62 -0.06 0: the robot would overlap the ball by ") as caught:
            place(sim, pose=(0.62, -0.06, 0.0))
    finally:
        sim.close()
    assert error_line(caught.value).startswith("--pose 0.62 -0.06 0: the robot would overlap the ball by ")
    taken = tmp_path / "taken"
    taken.write_text("")
    with pytest.raises(ParameterError) as caught:
        make_out_folder(taken)
    assert (str(caught.value), error_line(caught.value)) == (
        f"out {taken}: not a folder",
        f"--out {taken}: not a folder",
    )
    error = ParameterError.at("scene", "pose.xml", "the robot starts inside a wall; place it with", fix="pose")
    assert error_line(_in_shard(error, tmp_path / "shard_1")) == (
        "shard_1: --scene pose.xml: the robot starts inside a wall; place it with --pose"
    )
    with pytest.raises(ParameterError, match="^ball nan 0.0: must be 2 finite numbers$"):
        motions.play_motion(motions.motions()["STAND.MTN"], world=WorldConfig(ball=(math.nan, 0.0)))


def _imports(path: Path) -> set[str]:
    """The modules ``path`` imports, and each name a ``from`` import takes, as dotted names."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            module = "." * node.level + (node.module or "")
            names.update({module, *(f"{module}.{alias.name}" for alias in node.names)})
    return names


def test_the_library_does_not_import_the_command_line_and_shards_do_not_import_running():
    package = ROOT / "aibo_sim"
    library = [package / "runner.py", package / "motions.py", package / "placement.py"]
    for path in library + [p for p in (package / "dump").glob("*.py") if p.name not in ("__init__.py", "command.py")]:
        assert not any("options" in name.split(".") for name in _imports(path)), path
    assert not any("running" in name.split(".") for name in _imports(package / "dump" / "shards.py"))


def _run(tmp_path, name, *options):
    out = tmp_path / name
    assert main(["run", str(SCRIPTED), "--duration", "0.2", "--out", str(out), *options]) == 0
    return out, json.loads((out / "run.json").read_text())


def test_run_camera_profile_changes_the_frames_and_run_json_records_it(tmp_path):
    frames, records = {}, {}
    for profile in ("ideal", "ers7"):
        out, record = _run(
            tmp_path,
            profile,
            "--camera-profile",
            profile,
            "--camera-wb",
            "outdoor",
            "--camera-gain",
            "high",
            "--camera-shutter",
            "fast",
        )
        frames[profile] = cv2.imread(str(out / "frames" / "000003.png"))
        records[profile] = record
    assert frames["ideal"].shape == frames["ers7"].shape == (160, 208, 3)
    assert np.abs(frames["ideal"].astype(int) - frames["ers7"].astype(int)).mean() > 2
    for profile, record in records.items():
        camera = record["camera"]
        assert camera["profile"] == profile and (camera["width"], camera["height"]) == (208, 160)
        assert (camera["white_balance"], camera["gain"], camera["shutter"]) == ("outdoor", "high", "fast")
        assert record["seed"] == 0 and record["pose"] is None and record["ball"] is None and record["scene"] is None
        for key in (
            "controller",
            "backend",
            "simulated_s",
            "wall_s",
            "real_time_factor",
            "camera_frames",
            "robot_pose",
            "ball_xy",
        ):  # the summary's fields are all still there
            assert key in record
    assert records["ers7"]["camera"]["lens"] != records["ideal"]["camera"]["lens"]


def test_run_pose_ball_and_seed_are_applied_and_recorded(tmp_path):
    out, default = _run(tmp_path, "default")
    out, placed = _run(
        tmp_path, "placed", "--pose", "1.0", "-0.5", "90", "--ball", "-0.3", "0.4", "--seed", "5", "--camera-full"
    )
    # The controller's leg motion shifts the robot a little; the same shift, turned by the pose,
    # from where --pose put it (the carpet is flat and uniform).
    dx, dy, dyaw = default["robot_pose"]  # yaw in degrees, as --pose takes it
    assert math.hypot(dx, dy) < 0.05 and abs(dyaw) < 17  # the field's start: the centre, heading +x
    x, y, yaw = placed["robot_pose"]
    assert x == pytest.approx(1.0 - dy, abs=0.02) and y == pytest.approx(-0.5 + dx, abs=0.02)
    assert abs(math.remainder(yaw - 90 - dyaw, 360)) < 3
    assert placed["ball_xy"] == pytest.approx([-0.3, 0.4], abs=0.02)
    assert placed["pose"] == [1.0, -0.5, 90.0] and placed["ball"] == [-0.3, 0.4] and placed["seed"] == 5
    assert (placed["camera"]["width"], placed["camera"]["height"]) == (416, 320)
    assert cv2.imread(str(out / "frames" / "000000.png")).shape == (320, 416, 3)


def test_mtn_play_takes_the_world_and_camera_options(capsys):
    argv = ["mtn", "play", "SIT.MTN", "--json", "--camera-profile", "ideal", "--camera-wb", "indoor", "--seed", "3"]
    assert main(argv + ["--pose", "-0.5", "0.75", "-45", "--ball", "0", "0"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert not result["fell"]
    assert result["start_pose"] == pytest.approx([-0.5, 0.75, -45.0], abs=0.01)
    assert result["end_pose"][:2] == pytest.approx([-0.5, 0.75], abs=0.05)
    assert main(argv) == 0
    assert json.loads(capsys.readouterr().out)["start_pose"] == pytest.approx([0.0, 0.0, 0.0], abs=0.01)


@pytest.mark.slow
def test_render_takes_the_camera_and_world_options(tmp_path, capsys):
    pictures = {}
    for profile in ("ideal", "ers7"):
        out = tmp_path / profile
        assert (
            main(
                [
                    "render",
                    "--out",
                    str(out),
                    "--settle",
                    "0.1",
                    "--camera-profile",
                    profile,
                    "--pose",
                    "-0.8",
                    "-1.0",
                    "-5",
                    "--ball",
                    "-0.2",
                    "-0.97",
                ]
            )
            == 0
        )
        pictures[profile] = cv2.imread(str(out / "head_camera.png"))
        assert cv2.imread(str(out / "tracking.png")).shape == (480, 640, 3)
        described = json.loads((out / "head_camera.json").read_text())
        assert described["camera"]["profile"] == profile and described["camera"]["width"] == 208
        # The recorded lens and pose put the ball where the frame's label says, through OpenCV (within
        # 0.3 px: the resting ball sits ~0.5 mm into the carpet's soft contact, below BALL_RADIUS).
        lens, pose = described["camera"], described["frame"]["camera"]
        to_opencv = np.array(pose["xmat"]).reshape(3, 3) @ np.diag([1.0, -1.0, -1.0])
        ball = (np.array([-0.2, -0.97, BALL_RADIUS]) - pose["position"]) @ to_opencv
        matrix = np.array([[lens["fx"], 0, lens["cx"]], [0, lens["fy"], lens["cy"]], [0, 0, 1]])
        pixel = cv2.projectPoints(ball[None], np.zeros(3), np.zeros(3), matrix, np.array(lens["distortion"]))[0]
        assert described["frame"]["ball"]["visible"]
        assert pixel.ravel() == pytest.approx(described["frame"]["ball"]["pixel"], abs=0.3)
        assert sorted(p.name for p in out.iterdir()) == ["head_camera.json", "head_camera.png", "tracking.png"]
    assert pictures["ideal"].shape == pictures["ers7"].shape == (160, 208, 3)
    assert np.abs(pictures["ideal"].astype(int) - pictures["ers7"].astype(int)).mean() > 2
    assert main(["render", "--out", str(tmp_path / "full"), "--settle", "0", "--camera-full"]) == 0
    assert cv2.imread(str(tmp_path / "full" / "head_camera.png")).shape == (320, 416, 3)
    assert "head_camera.png (416x320)" in capsys.readouterr().out


def test_a_dumps_and_a_renders_records_read_back_as_configs(tmp_path):
    from aibo_sim.dump import dump

    world = WorldConfig(seed=5, pose=(0.2, 0.1, 10.0), ball=(0.7, -0.1))
    camera = CameraConfig("ideal", settings=CameraSettings("outdoor", "low", "mid"))
    dump(tmp_path / "dump", controller=SCRIPTED, frames=2, formats=("rgb",), world=world, camera=camera)
    meta = json.loads((tmp_path / "dump" / "meta.json").read_text())
    assert WorldConfig.from_dict(meta["parameters"]) == world and CameraConfig.from_dict(meta["camera"]) == camera
    flags = ["--seed", "5", "--pose", "0.2", "0.1", "10", "--ball", "0.7", "-0.1", "--camera-profile", "ideal"]
    flags += ["--camera-wb", "outdoor", "--camera-gain", "low", "--camera-full"]
    assert main(["render", "--out", str(tmp_path / "render"), "--settle", "0", *flags]) == 0
    recorded = json.loads((tmp_path / "render" / "head_camera.json").read_text())
    assert CameraConfig.from_dict(recorded["camera"]) == CameraConfig("ideal", True, camera.settings)


def test_render_shows_the_camera_frame_at_settle_as_a_dump_lists_it(tmp_path):
    """--settle 0.5 (62.5 joint frames) rounded half to even to 0.496 s, an earlier camera frame,
    and head_camera.json gave it index 0 where a dump of the same start lists it as 15."""
    from aibo_sim.dump import dump, load_dump

    idle = tmp_path / "idle.py"
    idle.write_text("from aibo_sim.controller import *\n\nwhile robot_step(32) != -1:\n    pass\n")
    dump(tmp_path / "dump", controller=idle, frames=16, formats=("rgb",), world=WorldConfig(seed=4))
    assert main(["render", "--out", str(tmp_path / "render"), "--seed", "4"]) == 0
    recorded = json.loads((tmp_path / "render" / "head_camera.json").read_text())["frame"]
    listed = load_dump(tmp_path / "dump")[15]
    assert recorded == listed.meta and recorded["index"] == 15
    picture = cv2.imread(str(tmp_path / "render" / "head_camera.png"))[..., ::-1]
    assert np.array_equal(picture, listed.rgb)


def test_mtn_play_takes_runs_mtn_mode_option(capsys):
    reports = []
    for option in ("--mtn-mode", "--mode"):  # run's and dump's name, and mtn play's earlier one
        assert main(["mtn", "play", "STAND.MTN", option, "webots", "--json"]) == 0
        reports.append(json.loads(capsys.readouterr().out))
    assert main(["mtn", "play", "STAND.MTN", "--json"]) == 0
    openr = json.loads(capsys.readouterr().out)
    assert reports[0] == reports[1] and reports[0]["duration_s"] != openr["duration_s"]
