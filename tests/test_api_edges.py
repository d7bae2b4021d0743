"""Edges of the controller API and the environments: steps that are not whole frames, a motion
played again while it plays, arguments that are not motions or file names, control characters
in MTN strings, an environment used after close() (issue 15)."""

import json
import math
import sys
from pathlib import Path

import gymnasium
import numpy as np
import pytest

import aibo_sim.envs  # noqa: F401  (registers the environments)
from aibo_sim import controller as api
from aibo_sim import ers7
from aibo_sim.cli import main
from aibo_sim.envs.match import MatchEnv
from aibo_sim.mtn import Motion, MtnError, write_mtn
from aibo_sim.robot import DeviceError, Robot
from aibo_sim.sim import Simulation, models_dir
from aibo_sim.team import RobotSpec, check_robots

SCRIPTED = Path(__file__).parent / "controllers" / "scripted_head.py"

LF_J1 = "PRM:/r2/c1-Joint2:21"
HEAD_PAN = "PRM:/r1/c1/c2-Joint2:12"


@pytest.fixture(params=["openr", "webots"])
def robot(request):
    robot = Robot(Simulation(), mtn_mode=request.param)
    api.install(robot)
    yield robot
    api.install(None)
    robot.sim.close()


def ramp(name="a_test#ramp", frames=(0.0, 10.0, 20.0, 30.0)) -> Motion:
    return Motion.from_poses(name, [LF_J1], np.radians([[f] for f in frames]), 16 * 4)


# ----------------------------------------------------------------------------- robot_step


@pytest.mark.parametrize("ms", [8.9, 7.999, 12, 0, -8, 16.5, math.nan, math.inf, "16", True, None])
def test_robot_step_refuses_what_is_not_a_whole_multiple_of_8_ms(robot, ms):
    with pytest.raises(ValueError, match=r"step of .* ms: must be a positive whole multiple of the 8 ms joint frame"):
        api.robot_step(ms)
    assert robot.time_ms == 0  # not silently 8 ms


def test_robot_step_takes_whole_numbers_of_any_numeric_type(robot):
    for ms in (8, 16.0, np.int64(24), np.float32(32.0)):
        api.robot_step(ms)
    assert robot.time_ms == 80


@pytest.mark.parametrize("ms", [8.9, 0, "32", math.nan, 65536])
def test_sampling_periods_must_be_whole_ms_that_webots_unsigned_short_holds(robot, ms):
    with pytest.raises(DeviceError, match=r"sampling period must be a whole number of ms from 1 to 65535, not "):
        api.servo_enable_position(api.robot_get_device(HEAD_PAN), ms)
    api.servo_enable_position(api.robot_get_device(HEAD_PAN), 65535)


def test_console_printf_formats_as_printf_with_or_without_arguments(robot, capsys):
    api.robot_console_printf("A 100%%\n")
    api.robot_console_printf("B %d%%\n", 5)
    assert capsys.readouterr().out == "A 100%\nB 5%\n"  # as C's printf writes them (tests/test_c_controller.py)
    with pytest.raises(TypeError, match=r"^robot_console_printf\('C %d\\n'\): not enough arguments"):
        api.robot_console_printf("C %d\n")


def test_a_run_function_may_return_a_whole_float_as_robot_step_takes_it(robot):
    steps = []

    def run(ms):
        steps.append(ms)
        return 16.0

    with pytest.raises(api.SimulationEnd):
        robot.end_ms = 48
        api.robot_run(run)
    assert steps[:3] == [0, 16, 16] and robot.time_ms == 48


@pytest.mark.parametrize("value", [None, "0.5", True, math.nan, -math.inf])
@pytest.mark.parametrize("setter", ["servo_set_position", "servo_set_velocity", "servo_set_motor_force", "led_set"])
def test_setters_refuse_what_is_not_a_finite_number_naming_the_device(robot, setter, value):
    tag = api.robot_get_device("PRM:/r1/c1/c2/c3/l1-LED2:l1" if setter == "led_set" else HEAD_PAN)
    with pytest.raises(DeviceError, match=r"^PRM:/r1/c1/\S+: .* must be a finite number, not "):
        getattr(api, setter)(tag, value)


@pytest.mark.parametrize(
    ("setter", "value"),
    [
        ("servo_set_acceleration", 0),
        ("servo_set_acceleration", -2.0),
        ("servo_set_control_p", 0),
        ("servo_set_control_p", -50),
    ],
)
def test_servo_settings_outside_webots_ranges_are_refused(robot, setter, value):
    # Webots' Servo node: acceleration -1 (unlimited) or (0, inf); controlP (0, inf)
    with pytest.raises(DeviceError, match=r"must be .*above 0, not "):
        getattr(api, setter)(api.robot_get_device(HEAD_PAN), value)


def test_motor_force_is_at_most_webots_max_force(robot):
    pan = api.robot_get_device(HEAD_PAN)
    actuator = robot.sim.servos.ctrl.start + ers7.JOINT_INDEX["head_pan"]
    api.servo_set_motor_force(pan, 100)
    assert list(robot.sim.model.actuator_forcerange[actuator]) == [-5.4542, 5.4542]  # maxForce: also the default
    api.servo_set_motor_force(pan, -1.5)
    assert list(robot.sim.model.actuator_forcerange[actuator]) == [-1.5, 1.5]


# ----------------------------------------------------------------------------- mtn_play


def test_mtn_play_on_a_playing_motion_restarts_it_rather_than_stacking(robot):
    motion = ramp()
    api.mtn_play(motion)
    for _ in range(8):
        api.robot_step(8)
    assert api.mtn_get_time(motion) == 64 and len(robot.playing) == 1
    api.mtn_play(motion)  # again, while it plays: from its start
    assert len(robot.playing) == 1 and api.mtn_get_time(motion) == 0
    api.robot_step(8)
    assert api.mtn_get_time(motion) == 8
    # Webots mode commands keyframe 0 on the restart's first step; OPEN-R mode its frame 0.
    assert robot.sim.servos.target[6] == pytest.approx(0.0, abs=1e-9)


def test_a_controller_that_plays_every_step_keeps_one_playback_and_its_speed(robot):
    """Was 1,876 playbacks after 60 s and a real-time factor of 0.9 instead of 100."""
    motion = ramp()
    for _ in range(1250):  # 10 s of simulated time
        api.mtn_play(motion)
        api.robot_step(8)
    assert len(robot.playing) == 1 and not api.mtn_is_over(motion)


def test_mtn_play_refuses_a_motion_made_in_code_that_moves_a_device_not_a_joint(robot):
    led = ers7.LEDS[0].locator
    with pytest.raises(MtnError, match=rf"^blink: Not a joint: {led} \(a motion moves joints only\)$"):
        api.mtn_play(Motion.from_poses("blink", [LF_J1, led], [[0.0, 0.0]], []))
    assert robot.playing == []


def test_other_motions_keep_playing_beside_a_restarted_one(robot):
    first, second = ramp("first"), Motion.from_poses("second", [HEAD_PAN], np.radians([[0.0], [5.0]]), [512])
    api.mtn_play(first)
    api.mtn_play(second)
    api.robot_step(64)
    api.mtn_play(first)
    assert [p.motion for p in robot.playing] == [second, first]
    api.mtn_delete(first)
    assert [p.motion for p in robot.playing] == [second] and not api.mtn_is_over(second)
    api.mtn_delete(None)  # as in Webots: nothing


@pytest.mark.parametrize(
    "function", ["mtn_is_over", "mtn_play", "mtn_get_time", "mtn_get_length", "mtn_get_name", "mtn_delete"]
)
def test_a_deleted_motion_is_no_mtn_any_more(robot, function):
    motion = ramp("deleted")
    api.mtn_play(motion)
    api.mtn_delete(motion)
    assert robot.playing == []
    with pytest.raises(
        MtnError, match=rf"^{function}: this MTN was deleted by mtn_delete \(mtn_new makes a new one\)$"
    ):
        getattr(api, function)(motion)
    api.mtn_play(ramp("another"))  # other motions play on
    assert len(robot.playing) == 1


# ----------------------------------------------------------------------------- arguments


@pytest.mark.parametrize(
    "function", ["mtn_is_over", "mtn_play", "mtn_get_time", "mtn_get_length", "mtn_get_name", "mtn_delete"]
)
@pytest.mark.parametrize("argument, shown", [(42, "42"), ("WALKFWD.MTN", "'WALKFWD.MTN'"), ("x" * 5000, "characters")])
def test_mtn_functions_name_an_argument_that_is_not_a_motion(robot, function, argument, shown):
    with pytest.raises(
        MtnError, match=rf"{function}\(.*{shown}.*\): not an MTN \(use the value mtn_new returned\)"
    ) as caught:
        getattr(api, function)(argument)
    assert len(str(caught.value)) < 200


def test_a_null_mtn_quotes_the_mtn_new_error(robot):
    assert api.mtn_new("NOSUCH.MTN") is None
    with pytest.raises(MtnError, match=r"mtn_is_over: MTN is NULL: mtn_new failed \(File not found: NOSUCH.MTN\)"):
        api.mtn_is_over(None)
    with pytest.raises(ValueError):  # MtnError is a ValueError, as before
        api.mtn_play(None)


@pytest.mark.parametrize(
    "argument, words",
    [
        (None, "mtn_new(None): the file name must be a str or a path, not NoneType"),
        (42, "mtn_new(42): the file name must be a str or a path, not int"),
        ("x" * 5000, "File not found: xxxx"),
        ("", "File not found: "),  # as Webots says it; not the folder "." that "" names as a path
    ],
)
def test_mtn_new_of_what_is_not_a_file_name_returns_none_with_the_reason(robot, argument, words):
    assert api.mtn_new(argument) is None  # the documented failure
    error = api.mtn_get_error()
    assert words in error and len(error) < 300
    with pytest.raises(MtnError, match="the file name must be|File not found"):
        robot.mtn_new(argument)  # the Pythonic API raises it


def test_a_5000_character_name_says_how_long_it_was(robot):
    assert api.mtn_new("x" * 5000) is None
    assert api.mtn_get_error().endswith("... (5000 characters)")


def test_robot_die_needs_a_function(robot):
    with pytest.raises(TypeError, match="robot_die"):
        api.robot_die(42)


# ----------------------------------------------------------------------------- control characters

EVIL = "walk\x1b[2J\x07\nnext\x85"


def test_control_characters_in_mtn_strings_are_escaped_when_printed(robot, tmp_path, capsys):
    motion = Motion.from_poses(EVIL, [LF_J1], np.radians([[0.0], [10.0]]), [16], creator="me\r", design="DRX\x00")
    api.mtn_fprint(sys.stdout, motion)
    out = capsys.readouterr().out
    assert r"walk\x1b[2J\x07\nnext\x85" in out and r"me\r" in out and r"DRX\x00" in out
    assert not any(c in out for c in "\x1b\x07\r\x00\x85") and "\nnext" not in out

    path = tmp_path / "EVIL.MTN"
    write_mtn(motion, path)
    assert main(["mtn", "info", str(path)]) == 0
    out = capsys.readouterr().out
    assert r"walk\x1b[2J\x07\nnext\x85" in out and "\x1b" not in out and "\nnext" not in out
    assert main(["mtn", "info", str(path), "--json"]) == 0
    out = capsys.readouterr().out
    assert json.loads(out)["name"] == EVIL and "\x1b" not in out  # JSON escapes them itself


def test_the_star_import_gives_the_errors_the_api_raises():
    namespace = {}
    exec("from aibo_sim.controller import *", namespace)  # as a controller imports the API
    for name in ("DeviceError", "MtnError", "ImageAccessError", "SimulationEnd"):
        assert namespace[name] is getattr(api, name)
    with pytest.raises(namespace["ImageAccessError"]):
        api.camera_image_get_red(bytes(208 * 160 * 3), 208, 208, 0)


@pytest.mark.parametrize("command", ["info", "play"])
def test_a_missing_motion_on_the_command_line_lists_the_bundled_ones(command, tmp_path, capsys):
    bundled = ", ".join(sorted(p.name for p in (models_dir() / "motions").glob("*.MTN")))
    assert "SIT.MTN" in bundled
    assert main(["mtn", command, "SIT"]) == 2
    assert capsys.readouterr().err == f"aibo-sim: error: SIT: no such motion file, nor a bundled motion ({bundled})\n"
    archive = tmp_path / "NOSUCH.ODA"
    assert main(["mtn", command, f"{archive}:WALK"]) == 2
    assert capsys.readouterr().err == f"aibo-sim: error: {archive}: no such ODA archive (in '{archive}:WALK')\n"


def test_a_missing_device_with_control_characters_is_escaped_in_the_error(robot, tmp_path):
    path = tmp_path / "BAD.MTN"
    write_mtn(Motion.from_poses("bad", ["PRM:\x1b[31m"], np.radians([[0.0], [1.0]]), [16]), path)
    assert api.mtn_new(str(path)) is None
    assert api.mtn_get_error() == r"Missing device in model: PRM:\x1b[31m"


# ----------------------------------------------------------------------------- environments after close()


def test_an_environment_keeps_no_stepping_after_close():
    env = gymnasium.make("aibo_sim/HeadTrackBall-v0", camera=None)
    with pytest.raises(gymnasium.error.ResetNeeded, match="step before reset"):
        env.unwrapped.step(env.action_space.sample())  # without Gymnasium's OrderEnforcing wrapper
    env.reset(seed=0)
    env.step(env.action_space.sample())
    env.close()
    env.close()  # closing twice is harmless
    with pytest.raises(gymnasium.error.ClosedEnvironmentError, match="step after close"):
        env.step(env.action_space.sample())
    with pytest.raises(gymnasium.error.ClosedEnvironmentError, match="is closed"):
        env.reset(seed=1)
    with pytest.raises(gymnasium.error.ClosedEnvironmentError, match="HeadTrackBallEnv.render after close"):
        env.unwrapped.render()  # returned None without a render mode, as before close
    match = MatchEnv(robots=check_robots([RobotSpec("red", 1)], "test"), camera=None)
    match.close()
    with pytest.raises(gymnasium.error.ClosedEnvironmentError, match="MatchEnv.render after close"):
        match.render()


@pytest.mark.parametrize("call", ["robot_live", "robot_run", "robot_die"])
def test_robot_functions_refuse_what_is_not_callable_naming_the_call(robot, call):
    with pytest.raises(TypeError, match=rf"^{call}\(5\): the \w+ function must be callable"):
        getattr(api, call)(5)


# ---------------------------------------------------------------- the Python API's arguments (a reviewer's list)


@pytest.mark.parametrize(
    "arguments, message",
    [
        ({"frames": 2.5}, r"the number of frames \(or steps\) must be a whole number of at least 1, not 2\.5"),
        ({"frames": float("inf")}, r"the number of frames .* not inf"),  # it named --duration, after writing
        ({"frames": None}, r"the number of frames .* not None"),
        ({"frames": True}, r"the number of frames .* not True"),
        ({"frames": 3, "workers": 1.5}, r"^workers 1\.5: must be a whole number from 1 to the number of frames \(3\)"),
        ({"frames": 3, "formats": None}, r"^formats None: a sequence of format names"),
    ],
)
def test_dump_refuses_a_count_or_formats_of_the_wrong_kind_before_writing(tmp_path, arguments, message):
    from aibo_sim.dump import dump

    with pytest.raises(ValueError, match=message):
        dump(tmp_path / "out", controller=SCRIPTED, **arguments)
    assert not (tmp_path / "out").exists()


def test_dump_takes_a_numpy_count(tmp_path):
    from aibo_sim.dump import dump, load_dump

    dump(tmp_path / "out", controller=SCRIPTED, frames=np.int64(2), formats=("rgb",))  # json.dumps refused int64
    assert len(load_dump(tmp_path / "out")) == 2


def test_configs_robots_and_match_actions_of_the_wrong_kind_are_named(tmp_path, monkeypatch):
    from aibo_sim.config import WorldConfig
    from aibo_sim.match import run_match
    from aibo_sim.runner import run_controller
    from aibo_sim.team import TeamError

    with pytest.raises(
        TypeError, match=r"^world must be a WorldConfig \(WorldConfig.from_dict reads a recorded dict\)"
    ):
        run_controller(SCRIPTED, duration=0.1, world={"seed": 1})
    with pytest.raises(TypeError, match=r"^camera must be a CameraConfig"):
        Simulation(camera="ers7")
    with pytest.raises(
        TeamError, match=r"^--robots: robots are a robots file or RobotSpecs, not \[\{'number': 1, 'team': 'red'\}\]$"
    ):
        run_match([{"team": "red", "number": 1}], controller_path=SCRIPTED, duration=0.1)
    monkeypatch.chdir(tmp_path)  # the match's controllers write their joints.txt there
    robots = tmp_path / "robots.toml"
    robots.write_text('[[robot]]\nteam = "red"\nnumber = 1\n\n[[robot]]\nteam = "blue"\nnumber = 1\n')
    assert [(r.team, r.number) for r in check_robots(robots, "robots")] == [("red", 1), ("blue", 1)]
    assert run_match(str(robots), controller_path=SCRIPTED, duration=0.1, world=WorldConfig())["status"] == "done"
    env = MatchEnv(robots=[RobotSpec("red", 1), RobotSpec("blue", 1)], camera=None)
    try:
        env.reset(seed=0)
        with pytest.raises(TypeError, match="^actions must be a dict of agent name to action, not list$"):
            env.step([np.zeros(15)])
    finally:
        env.close()


def test_pixel_helpers_take_whole_numbers_as_python_ints():
    image = np.arange(208 * 160 * 3, dtype=np.uint8)
    with pytest.raises(TypeError, match=r"^camera_image_get_red: width, x and y must be ints, not 208, 104\.0, 80$"):
        api.camera_image_get_red(image, 208, 208 / 2, 80)
    # numpy's uint8 wrapped 3 * (100 * 200 + 100) round: a pixel of another place
    assert api.camera_image_get_red(image, np.uint8(200), np.uint8(100), np.uint8(100)) == image[3 * (100 * 200 + 100)]


def test_small_api_edges_a_reviewer_found(robot):
    assert api.mtn_new("a\0b") is None and "cannot hold a NUL character" in api.mtn_get_error()
    pan = api.robot_get_device("PRM:/r1/c1/c2-Joint2:12")
    with pytest.raises(DeviceError, match=r"position must be a finite number, not 1000"):
        api.servo_set_position(pan, 10**400)  # an OverflowError before
    with pytest.raises(DeviceError, match="invalid device tag True"):
        api.servo_enable_position(True, 32)  # tag 1 before


def test_values_that_were_taken_silently_are_refused():
    """Each was accepted and went on wrong: "123" a pose of (1, 2, 3), "no" a full-size camera, a
    NaN LED level a NaN colour, a NaN step a motion that never ends, NaN targets a NaN action."""
    from aibo_sim.config import CameraConfig, ParameterError, WorldConfig
    from aibo_sim.mtn import MotionPlayer

    for pose in ("123", (True, False, True)):
        with pytest.raises(ParameterError, match="must be 3 numbers"):
            WorldConfig(pose=pose)
    assert WorldConfig(pose=(n for n in (1, 2, 3))).pose == (1.0, 2.0, 3.0)
    with pytest.raises(ParameterError, match="^full 'no': must be true or false$"):
        CameraConfig.from_dict({"profile": "ers7", "full": "no"})
    sim = Simulation()
    try:
        with pytest.raises(ValueError, match="level must be a finite number in 0..1, not nan"):
            sim.set_led(ers7.LEDS[0].name, float("nan"))
        sim.set_led(ers7.LEDS[0].name, -5.0)  # clipped: off, where the colour went negative
        geoms = [sim.model.geom(name).id for name in ers7.LEDS[0].all_geoms]
        assert (sim.model.geom_rgba[geoms] >= 0).all()
    finally:
        sim.close()
    player = MotionPlayer(ramp(), "webots")
    with pytest.raises(ValueError, match="ms must be a finite number >= 0, not nan"):
        player.step(float("nan"))
    env = gymnasium.make("aibo_sim/HeadTrackBall-v0", camera_profile="ideal").unwrapped
    try:
        with pytest.raises(ValueError, match=r"^targets\[0\] \(neck_tilt\) is nan: targets must be finite$"):
            env.targets_to_action(np.full(3, np.nan))
    finally:
        env.close()


def test_names_listeners_and_motions_of_the_wrong_kind_are_named():
    from aibo_sim.match import run_match
    from aibo_sim.runner import run_controller
    from aibo_sim.team import RobotSpec

    sim = Simulation()
    try:
        for call in (lambda: sim.sensor("nope"), lambda: sim.distance_mm("nope"), lambda: sim.touched("nope", 0.5)):
            with pytest.raises(
                ValueError, match=r"^no (distance )?sensor named 'nope'; the (distance )?sensors: ir_near, "
            ):
                call()
        with pytest.raises(ValueError, match=r"^no LED named 'nope'; the LEDs: led_head_colour, "):
            sim.set_led("nope", 1.0)
    finally:
        sim.close()
    with pytest.raises(TypeError, match=r"^frame_listeners must be a sequence of callables, not \[5\]$"):
        run_controller(SCRIPTED, duration=0.1, frame_listeners=[5])  # "controller ... raised", blaming it
    with pytest.raises(TypeError, match=r"^robot_listeners must be a callable \(or None\), not 5$"):
        run_match([RobotSpec("red", 1), RobotSpec("blue", 1)], controller_path=SCRIPTED, robot_listeners=5)
    poses = np.zeros((2, 20))
    for segment in (float("nan"), float("inf"), None, 16 * 10**30):  # ValueError, OverflowError, TypeError before
        with pytest.raises(MtnError, match=r"^x: segment durations \[.*\] must be positive multiples of 16 ms$"):
            Motion.from_poses("x", None, poses, segment)
    with pytest.raises(MtnError, match="^x: poses must be a finite"):
        Motion.from_poses("x", None, [[0] * 20, [0]], 64)  # a ragged array: numpy's ValueError
    with pytest.raises(MtnError, match="^x: locators must be a sequence of locators, not the string"):
        Motion.from_poses("x", "PRM:/r1/c1-Joint2:11", np.zeros((2, 1)), 64)  # "duplicate locator" before


def test_encoder_arguments_and_recorded_configs_of_the_wrong_kind_are_named():
    from aibo_sim.config import CameraConfig, ParameterError, WorldConfig
    from openr_bridge.encoder import encode_frame
    from openr_bridge.errors import FrameError

    rgb = np.zeros((160, 208, 3), np.uint8)
    for arguments, message in (  # struct.error, a TypeError of string formatting, an AttributeError before
        ({"frame_number": -1}, "^frame_number must be a whole number of at least 0, not -1$"),
        ({"primitive_id": 2**33}, "^primitive_id must be a whole number from 0 to 4294967295, not 8589934592$"),
        ({"field_counter": "x"}, "^field_counter must be a whole number from 0 to 4294967295, not 'x'$"),
        ({"cdt": "x"}, r"^cdt must be an OCdtVectorData \(or None\), not str$"),
    ):
        with pytest.raises(FrameError, match=message):
            encode_frame(rgb, **arguments)
    with pytest.raises(ParameterError, match="^camera {}: has no 'profile'$"):  # KeyError before
        CameraConfig.from_dict({})
    with pytest.raises(ParameterError, match=r"^world \[\]: a recorded config is a dict"):  # AttributeError before
        WorldConfig.from_dict([])
    for bad, message in (  # a TypeError, an AttributeError: neither named the field
        ({"foo": 1}, r"^profile_options \{'foo': 1\}: not the profile's options \(.*'foo'\)$"),
        ("x", r"^profile_options 'x': not the profile's options"),
    ):
        with pytest.raises(ParameterError, match=message):
            CameraConfig.from_dict({"profile": "ers7", "profile_options": bad})
    with pytest.raises(ParameterError, match=r"^profile 'foo': not a camera profile"):  # not its options' fault
        CameraConfig.from_dict({"profile": "foo"})
    with pytest.raises(ParameterError, match=r"^world \{'posee': \[1, 2, 3\]\}: has none of scene, seed, pose"):
        WorldConfig.from_dict({"posee": [1, 2, 3]})  # the default world before, the misspelt key ignored
    assert WorldConfig.from_dict({"seed": 3, "status": "done"}) == WorldConfig(seed=3)  # run.json's other keys
    with pytest.raises(ParameterError, match="^scene '': an empty string names no file or folder$"):
        WorldConfig(scene="")  # '.: not a regular file' later, naming no parameter
    for field, values in (("pose", (10**400, 0, 0)), ("ball", (0, 10**400))):  # a bare OverflowError
        with pytest.raises(ParameterError, match=rf"^{field} \(.*\): must be {len(values)} numbers$"):
            WorldConfig(**{field: values})


def test_a_keyframe_and_a_latency_out_of_reach_are_named_before_any_work(capsys):
    for keyframe in (None, "lying"):  # a pybind11 TypeError, and MuJoCo's KeyError at reset
        with pytest.raises(  # named as the parameter (the command line's --keyframe before), the CLI's option there
            ValueError, match=rf"^keyframe {keyframe!r}: no such keyframe; the scene's: home, stand, sit$"
        ):
            Simulation(keyframe=keyframe)
    assert main(["render", "--settle", "0", "--keyframe", "lying"]) == 2
    assert (
        capsys.readouterr().err
        == "aibo-sim: error: --keyframe 'lying': no such keyframe; the scene's: home, stand, sit\n"
    )
    with pytest.raises(ValueError, match="^ball_type 'zz': must be one of robocup, pink$"):  # --ball-type before
        Simulation(ball_type="zz")
    sim = Simulation()
    try:
        with pytest.raises(ValueError, match="^keyframe 'x': no such keyframe"):
            sim.reset(keyframe="x")
    finally:
        sim.close()
    with pytest.raises(
        ValueError, match="^command_latency_frames must be a whole number from 0 to 125, not 1000000000$"
    ):
        Simulation(command_latency_frames=10**9)  # a MemoryError of 149 GiB before


def test_match_env_motion_player_and_motion_arguments_of_the_wrong_kind_are_named():
    from aibo_sim.envs.match import MatchEnv
    from aibo_sim.mtn import MotionPlayer
    from aibo_sim.team import RobotSpec

    robots = [RobotSpec("red", 1), RobotSpec("blue", 1)]
    with pytest.raises(TypeError, match=r"^scripted must be a dict of robot name to factory, not \['red_1'\]$"):
        MatchEnv(robots=robots, scripted=["red_1"], camera=None)  # dict()'s ValueError before
    with pytest.raises(TypeError, match=r"^scripted\['red_1'\] made None, not a scripted policy"):
        MatchEnv(robots=robots, scripted={"red_1": lambda sim: None}, camera=None)  # AttributeError at reset
    env = MatchEnv(robots=robots, camera=None)
    try:
        with pytest.raises(TypeError, match=r"^reset options must be a dict"):
            env.reset(options=[("ball", (0, 0))])
        with pytest.raises(ValueError, match=r"^no robot \[\] \(robots: red_1, blue_1\)$"):
            env.robot([])  # unhashable
    finally:
        env.close()
    player = MotionPlayer(ramp())
    assert np.array_equal(player.targets_rad_at(float("inf")), player.frame(player.num_frames - 1) / 1e6)  # held
    with pytest.raises(ValueError, match="t_ms must be a number of ms, not nan"):
        player.targets_rad_at(float("nan"))
    with pytest.raises(TypeError):
        player.frame(1.5)  # a frame between frames was given
    with pytest.raises(MtnError, match="name, creator and design must be strings"):
        Motion.from_poses(None, None, np.zeros((2, 20)), 64)  # failed only in write_mtn
    with pytest.raises(MtnError, match=r"^x: frame time 16\.5 ms is not a positive whole number$"):
        Motion("x", "c", "d", 16.5, ("PRM:/r1/c1-Joint2:11",), [[0]], [[0, 0, 0]], [])  # cut to 16 before
    joint = ("PRM:/r1/c1-Joint2:11",)
    for keyframes, interpolate, what in (
        ([[0.7], [1.9]], [1], "keyframes"),  # radians given for micro-radians: cut to 0 and 1 before
        ([[0], [1]], [1.5], "interpolate"),  # cut to 1
        ([[math.nan], [0]], [1], "keyframes"),  # numpy's ValueError
        ([["a"], [0]], [1], "keyframes"),
        ([[2**70], [0]], [1], "keyframes"),  # an OverflowError
        ([[0], [0, 1]], [1], "keyframes: rows of different lengths"),
    ):
        with pytest.raises(MtnError, match=rf"^x: {what}"):
            Motion("x", "c", "d", 16, joint, keyframes, [[0, 0, 0]] * 2, interpolate)
    assert Motion("x", "c", "d", 16, joint, [[1.0], [-2.0]], [[0, 0, 0]] * 2, [3.0]).keyframes.tolist() == [[1], [-2]]
    extremes = [[-(2**31), 2**31 - 1, 0]] * 2  # a file's s32 attitudes, the lowest one included
    assert Motion("x", "c", "d", 16, joint, [[0], [0]], extremes, [1]).attitudes.tolist() == extremes
    for beyond in (-(2**31) - 1, 2**31, -(2**63)):  # int64's lowest: np.abs overflowed and let it through
        with pytest.raises(MtnError, match="^x: keyframes must be whole numbers within 32 bits"):
            Motion("x", "c", "d", 16, joint, np.array([[beyond], [0]], np.int64), [[0, 0, 0]] * 2, [1])
    whole = Motion.from_poses("w", None, np.zeros((2, 20)), 64, frame_time_ms=16.0)  # as Motion takes it
    assert whole == Motion.from_poses("w", None, np.zeros((2, 20)), 64) and type(whole.frame_time_ms) is int
    for frame_time in (16.5, True, "16"):
        with pytest.raises(
            MtnError, match=rf"^w: segment durations \[64\] must be positive multiples of {frame_time!r} ms$"
        ):
            Motion.from_poses("w", None, np.zeros((2, 20)), 64, frame_time_ms=frame_time)


def test_console_motion_dump_and_motion_file_arguments_of_the_wrong_kind_are_named(robot, tmp_path):
    with pytest.raises(TypeError, match=r"^robot_console_printf\(b'hi\\n'\): the format must be a str$"):
        api.robot_console_printf(b"hi\n")  # stdout's "write() argument must be str"
    write_mtn(ramp(), tmp_path / "ramp.mtn")
    motion = api.mtn_new(str(tmp_path / "ramp.mtn"))
    with pytest.raises(TypeError, match=r"^mtn_fprint\(None, \.\.\.\): the file must be writable"):
        api.mtn_fprint(None, motion)  # an AttributeError before
    with pytest.raises(TypeError, match="^write_mtn: the motion must be a Motion, not NoneType$"):
        write_mtn(None, tmp_path / "a.mtn")
    assert not (tmp_path / "a.mtn").exists()
