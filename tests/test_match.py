"""Several robots on one field (issue 41): the world, the uniforms, contacts, the cameras, and
``aibo-sim run --robots`` with each robot's own controller."""

import json
import math
import signal
import threading
from pathlib import Path

import cv2
import mujoco
import numpy as np
import pytest

from aibo_sim.cli import main
from aibo_sim.config import CameraConfig, WorldConfig
from aibo_sim.field import UNIFORM_COLOURS
from aibo_sim.match import Lockstep, run_match
from aibo_sim.runner import ControllerFailed
from aibo_sim.sim import Simulation, load_model, robot_prefix
from aibo_sim.team import RobotSpec, check_robots, kickoff_pose

ROOT = Path(__file__).resolve().parents[1]
TRACKER = ROOT / "controllers" / "ball_tracker.py"
FOUR_A_SIDE = check_robots([RobotSpec(team, number) for team in ("red", "blue") for number in (1, 2, 3, 4)], "test")


def facing(red_x=-0.5, blue_x=0.2):
    """A red and a blue robot facing each other across the centre line."""
    return (RobotSpec("red", 4, (red_x, 0.0, 0.0)), RobotSpec("blue", 4, (blue_x, 0.0, 180.0)))


def test_one_robot_by_default_keeps_the_scene_as_it_was():
    model, default = load_model(), Simulation(camera=CameraConfig("ideal"))
    try:
        assert default.world.robots == [default] and default.prefix == ""
        assert default.model.ngeom == model.ngeom and default.model.nu == model.nu == 20
        assert mujoco.mj_name2id(default.model, mujoco.mjtObj.mjOBJ_GEOM, "uniform_left") < 0
    finally:
        default.close()


def test_eight_robots_each_with_its_own_joints_sensors_camera_and_uniform():
    sim = Simulation(robots=FOUR_A_SIDE, seed=5, camera=CameraConfig("ideal"))
    try:
        robots, model = sim.world.robots, sim.model
        assert len(robots) == 8 and robots[0] is sim and model.nu == 8 * 20
        assert [r.servos.ctrl.start for r in robots] == [20 * k for k in range(8)]
        assert len({r.camera.camera_id for r in robots}) == 8
        for robot in robots:
            x, y, yaw = robot.spec.pose
            position, heading, tilt = robot.body_pose()
            assert position[:2] == pytest.approx((x, y), abs=1e-9) and tilt < 0.1
            assert math.degrees(heading) == pytest.approx(yaw if yaw <= 180 else yaw - 360, abs=1e-6)
            geom = model.geom(robot_prefix(robot.index) + "uniform_left")
            assert tuple(model.geom_rgba[geom.id]) == pytest.approx(UNIFORM_COLOURS[robot.spec.team])
            assert geom.contype == 0 and geom.conaffinity == 0  # the uniform does not touch anything
        # each robot starts in the first robot's posture
        assert np.array_equal(robots[5].joint_positions(), sim.joint_positions())
        # noise streams: robot 1's is the world's seed, the others' differ from it and each other
        seeds = [r.robot_seed for r in robots]
        assert seeds[0] == 5 and len(set(seeds)) == 8
        sim.step_frames(25)
        assert not any(r.fallen() for r in robots)
    finally:
        sim.close()


def test_a_robot_running_into_another_pushes_it_and_does_not_pass_through():
    robots = (RobotSpec("red", 4, (-0.4, 0.0, 0.0)), RobotSpec("blue", 4, (0.0, 0.0, 0.0)))
    sim = Simulation(robots=robots, ball=False, camera=CameraConfig("ideal"))
    try:
        red, blue = sim.world.robots
        assert not sim.overlaps(0.0005)
        start = blue.body_pose()[0][0]
        sim.data.qvel[sim.model.jnt_dofadr[sim.model.body_jntadr[red._body]]] = 1.0  # red runs into blue's back
        deepest = 0.0
        for _ in range(40):
            sim.step_frames(1)
            deepest = max([deepest] + [d for a, b, d in sim.overlaps(0.0) if {a, b} == {"red 4", "blue 4"}])
        assert blue.body_pose()[0][0] > start + 0.001  # pushed
        assert red.body_pose()[0][0] < -0.25 and 0 < deepest < 0.01  # they touched, and red stopped behind blue
    finally:
        sim.close()


def test_every_robot_pushes_the_ball():
    robots = (RobotSpec("red", 1, (-2.0, 1.0, 0.0)), RobotSpec("blue", 3, (0.0, 0.0, 0.0)))
    sim = Simulation(camera=CameraConfig("ideal"), robots=robots)
    try:
        blue = sim.world.robots[1]  # a robot the match added, with its own contact bits
        sim.place_ball(0.24, 0.0)  # just ahead of its front paws
        sim.data.qvel[sim.model.jnt_dofadr[sim.model.body_jntadr[blue._body]]] = 1.5  # it runs into the ball
        for _ in range(40):
            sim.step_frames(1)
        assert sim.ball_position()[0] > 0.26  # pushed forward (5.7 cm here)
    finally:
        sim.close()


def test_each_camera_sees_the_other_robot_and_its_uniform_not_its_own():
    sim = Simulation(robots=facing(-0.5, 0.2), ball=False, camera=CameraConfig("ideal"))
    try:
        sim.step_frames(10)
        red, blue = sim.world.robots

        def uniform_pixels(robot, team):
            rgb = robot.camera.frame().rgb.astype(int)
            colour = np.array(UNIFORM_COLOURS[team][:3]) * 255
            hue = rgb / np.maximum(rgb.sum(axis=2, keepdims=True), 1)
            return int((np.abs(hue - colour / colour.sum()).sum(axis=2) < 0.12).sum())

        assert uniform_pixels(red, "blue") > 20 and uniform_pixels(blue, "red") > 20
        assert uniform_pixels(red, "red") == 0 and uniform_pixels(blue, "blue") == 0
        own = red.camera.own_geoms()
        bodies = sim.model.body_rootid[sim.model.geom_bodyid[own]]
        assert set(bodies) == {sim.model.body_rootid[red._body]}
    finally:
        sim.close()


def test_a_matchs_frames_made_in_parallel_equal_those_made_one_at_a_time():
    """World.frames draws the 8 cameras in threads at once: the same pictures, bit for bit, as each
    camera made in turn in a twin world, the model left as it was, and each renderer then drawing
    again from this thread (its context left current in none)."""
    parallel, serial = (Simulation(robots=FOUR_A_SIDE, seed=5) for _ in range(2))
    try:
        model = parallel.model
        groups, intrinsics = model.geom_group.copy(), model.cam_intrinsic.copy()
        cv2.setNumThreads(3)
        for _ in range(3):
            for sim in (parallel, serial):
                sim.step_frames(sim.frames_to_camera_frame())
            made = parallel.world.frames()
            assert cv2.getNumThreads() == 3  # OpenCV's setting back after the last camera's frame
            for frame, camera in zip(made, serial.world.cameras):
                expected = camera.frame()
                assert np.array_equal(frame.ycrcb, expected.ycrcb) and frame.index == expected.index
        assert [frame is camera.frame() for frame, camera in zip(made, parallel.world.cameras)] == [True] * 8
        assert np.array_equal(model.geom_group, groups) and np.array_equal(model.cam_intrinsic, intrinsics)
        seen = parallel.world.robots[0].camera.segmentation()  # this thread, after the pool's threads
        assert np.array_equal(seen, serial.world.robots[0].camera.segmentation())
        assert np.isin(seen, parallel.world.robots[0].camera.other_robots_geoms()).sum() > 100  # it sees robots
    finally:
        cv2.setNumThreads(-1)
        parallel.close()
        serial.close()


def test_lockstep_waits_for_every_robot_and_lets_a_finished_one_go():
    sim = Simulation(robots=facing(), ball=False, camera=CameraConfig("ideal"))
    try:
        world = sim.world
        world.lockstep = lockstep = Lockstep(world)
        red, blue = world.robots
        lockstep.leave(blue)  # blue's controller ended: red steps alone
        red.step_frames(3)
        assert world.frame == 3
    finally:
        sim.close()


def _tracker_robots():
    return [RobotSpec("red", 4, None, str(TRACKER)), RobotSpec("blue", 4, (0.6, 0.2, 180.0), str(TRACKER))]


def test_a_match_writes_each_robots_frames_and_is_deterministic(tmp_path):
    for name in ("a", "b"):
        summary = run_match(
            _tracker_robots(),
            duration=0.5,
            out=tmp_path / name,
            progress=False,
            world=WorldConfig(seed=4, ball=(0.1, 0.1)),
        )
        assert summary["status"] == "done" and summary["simulated_s"] == pytest.approx(0.5, abs=0.008)
    match = json.loads((tmp_path / "a" / "run.json").read_text())
    assert [
        RobotSpec.from_dict({k: r[k] for k in ("team", "number", "pose", "controller")}) for r in match["robots"]
    ] == list(check_robots(_tracker_robots(), "test"))
    for index in (1, 2):
        folder = tmp_path / "a" / f"robot{index}"
        names = sorted(p.name for p in (folder / "frames").iterdir())
        assert len(names) == 15
        robot_json = json.loads((folder / "run.json").read_text())
        assert robot_json["status"] == "done" and robot_json["team"] == ("red" if index == 1 else "blue")
        for name in names:
            assert (folder / "frames" / name).read_bytes() == (
                tmp_path / "b" / f"robot{index}" / "frames" / name
            ).read_bytes()
    red = cv2.imread(str(tmp_path / "a" / "robot1" / "frames" / "000014.png"))
    blue = cv2.imread(str(tmp_path / "a" / "robot2" / "frames" / "000014.png"))
    assert not np.array_equal(red, blue)  # each its own camera


def test_a_failing_controller_fails_the_match_and_the_others_run_to_the_end(tmp_path):
    crash = tmp_path / "crash.py"
    crash.write_text("from aibo_sim.controller import *\nrobot_step(64)\nraise RuntimeError('boom')\n")
    steps = tmp_path / "steps.py"
    steps.write_text("from aibo_sim.controller import *\nwhile True:\n    robot_step(40)\n")
    robots = [RobotSpec("red", 4, None, str(crash)), RobotSpec("blue", 4, None, str(steps))]
    with pytest.raises(ControllerFailed, match="(?s)red 4: .*boom"):
        run_match(robots, duration=0.4, out=tmp_path / "out", progress=False, camera=CameraConfig("ideal"))
    match = json.loads((tmp_path / "out" / "run.json").read_text())
    assert match["status"] == "failed" and match["simulated_s"] == pytest.approx(0.4, abs=0.008)
    assert [r["status"] for r in match["robots"]] == ["failed", "done"]


def ctrl_c_at(seconds: float):
    """A frame listener that sends SIGINT to the main thread, as Ctrl-C does, once the match is
    ``seconds`` in (so that it lands while the match waits for its robots, not during its setup)."""
    sent = []

    def listener(program):
        if program.time_ms >= seconds * 1000 and not sent:
            sent.append(True)
            signal.pthread_kill(threading.main_thread().ident, signal.SIGINT)

    return listener


def test_ctrl_c_ends_a_match_after_every_robots_controller_has_ended(tmp_path):
    # The robots' robot_die functions (slow ones) have run when run_match raises: it waited for
    # every robot's thread, which a join interrupted by the signal would not have done.
    slow_die = tmp_path / "slow_die.py"
    slow_die.write_text(
        "import time\nfrom aibo_sim.controller import *\n"
        "def die():\n    time.sleep(0.3)\n    open(f'died_{time.monotonic_ns()}', 'w').close()\n"
        "robot_die(die)\nwhile True:\n    robot_step(8)\n"
    )
    robots = [RobotSpec("red", 1, None, str(slow_die)), RobotSpec("blue", 1, None, str(slow_die))]
    with pytest.raises(KeyboardInterrupt):
        run_match(
            robots,
            duration=60,
            out=tmp_path / "out",
            progress=False,
            camera=CameraConfig("ideal"),
            frame_listeners=[ctrl_c_at(0.2)],
        )
    assert len(list((tmp_path / "out").glob("died_*"))) == 2
    assert json.loads((tmp_path / "out" / "run.json").read_text())["status"] == "interrupted"


@pytest.mark.slow
def test_a_signal_ends_a_match_whose_python_controller_is_stuck_with_every_run_json_interrupted(tmp_path):
    """A controller stuck in its own code never steps again: the match waits STOP_WAIT_S for it,
    then writes its run.json files (they stayed "incomplete")."""
    import time

    from aibo_sim import match

    stuck = tmp_path / "stuck.py"  # stuck from t = 0.1 s for 10 s of wall time (or until released), then steps
    stuck.write_text(
        "import os.path, time\nfrom aibo_sim.controller import *\n"
        "while robot_get_time() < 0.1:\n    robot_step(8)\n"
        "until = time.monotonic() + 10\n"
        f"while time.monotonic() < until and not os.path.exists({str(tmp_path / 'release')!r}):\n"
        "    time.sleep(0.05)\n"
        "robot_step(8)\n"
    )
    robots = [RobotSpec("red", 1, None, str(TRACKER)), RobotSpec("blue", 1, None, str(stuck))]
    timer = threading.Timer(2.0, signal.pthread_kill, [threading.main_thread().ident, signal.SIGINT])
    timer.start()
    started = time.monotonic()
    try:
        with pytest.raises(KeyboardInterrupt):
            run_match(robots, duration=60, out=tmp_path / "out", progress=False, camera=CameraConfig("ideal"))
    finally:
        timer.cancel()
    assert time.monotonic() - started < 2.0 + match.STOP_WAIT_S + 5
    for run_json in (tmp_path / "out" / "run.json", tmp_path / "out" / "robot2" / "run.json"):
        assert json.loads(run_json.read_text())["status"] == "interrupted", run_json
    # The stuck thread, left running, ends at its next step: released, so that its wait notices
    # do not land in a later test's output.
    (tmp_path / "release").touch()
    deadline = time.monotonic() + 10
    while any(t.name == "aibo-sim wait notices" for t in threading.enumerate()) and time.monotonic() < deadline:
        time.sleep(0.05)


def test_two_teams_modules_of_one_name_are_refused_before_anything_is_written(tmp_path, capsys):
    """One interpreter runs a match's Python controllers: blue's `import strategy` would get red's."""
    for team in ("redteam", "blueteam"):
        (tmp_path / team).mkdir()
        (tmp_path / team / "strategy.py").write_text(f"NAME = {team!r}\n")
        (tmp_path / team / "player.py").write_text(
            "from aibo_sim.controller import *\nimport strategy\nrobot_step(8)\n"
        )
    robots = ["--robot", f"red:4::{tmp_path / 'redteam' / 'player.py'}", "--robot"]
    blue = f"blue:4::{tmp_path / 'blueteam' / 'player.py'}"
    assert main(["run", *robots, blue, "--duration", "0.1", "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert (
        error.count("\n") == 1
        and (
            f"red 4's {tmp_path / 'redteam' / 'strategy.py'} and blue 4's {tmp_path / 'blueteam' / 'strategy.py'} are "
            "both the module 'strategy': the Python controllers of a match share one interpreter"
        )
        in error
    )
    assert not (tmp_path / "out").exists()
    # One folder for both robots is one module: the same file.
    blue = f"blue:4::{tmp_path / 'redteam' / 'player.py'}"
    assert (
        main(["run", *robots, blue, "--duration", "0.1", "--out", str(tmp_path / "out"), "--camera-profile", "ideal"])
        == 0
    )


def test_a_thread_a_match_controller_started_that_raises_fails_that_robot(tmp_path, capsys):
    """As in a run of one robot; the robot is the one whose code the thread ran (its traceback)."""
    threads = tmp_path / "threads.py"
    threads.write_text(
        "import threading\nfrom aibo_sim.controller import *\n\n"
        "def worker():\n    raise RuntimeError('worker failed')\n\n"
        "robot_live(lambda: threading.Thread(target=worker, name='worker').start())\n"
        "robot_run(lambda ms: 32)\n"
    )
    robots = ["--robot", "red:4", "--robot", f"blue:4::{threads}", "--camera-profile", "ideal"]
    assert main(["run", str(TRACKER), *robots, "--duration", "0.3", "--out", str(tmp_path / "out")]) == 1
    assert "blue 4: its thread 'worker' raised RuntimeError: worker failed" in capsys.readouterr().err
    summary = json.loads((tmp_path / "out" / "run.json").read_text())
    assert summary["status"] == "failed" and [robot["status"] for robot in summary["robots"]] == ["done", "failed"]
    assert summary["robots"][1]["error"] == "its thread 'worker' raised RuntimeError: worker failed"


def test_run_robots_file_on_the_command_line(tmp_path, capsys):
    robots = tmp_path / "robots.toml"
    robots.write_text(
        '[[robot]]\nteam = "red"\nnumber = 2\n\n[[robot]]\nteam = "blue"\nnumber = 3\npose = [1, 0, 180]\n'
    )
    out = tmp_path / "out"
    status = main(
        [
            "run",
            str(TRACKER),
            "--robots",
            str(robots),
            "--duration",
            "0.2",
            "--out",
            str(out),
            "--camera-profile",
            "ideal",
        ]
    )
    assert status == 0 and "a match of 2 robots" in capsys.readouterr().out
    assert len(list((out / "robot2" / "frames").iterdir())) == 6
    assert json.loads((out / "robot2" / "run.json").read_text())["pose"] == [1.0, 0.0, 180.0]


@pytest.mark.parametrize(
    "arguments, message",
    [
        (["--robot", "green:1"], "--robot green:1: unknown team 'green'"),
        (["--robot", "red:1", "--robot", "red:1"], "red 1 is also robot 1"),
        ([f"--robot=red:{n % 4 + 1}:{n * 0.3 - 2},1,0" for n in range(5)], "red"),
        ([f"--robot={t}:{n}" for t in ("red", "blue") for n in (1, 2, 3, 4)] + ["--robot", "red:1:0,1,0"], "8"),
        (
            ["--robot", "red:1:0,0,0", "--robot", "blue:1:0.25,0,0"],
            "--robot blue:1:0.25,0,0: blue 1 starts inside red 1",
        ),
        (["--robot", "red:1:0,0,1e300"], "--robot red:1:0,0,1e300: pose 0,0,1e+300: yaw out of range"),
        (
            ["--robot", "red:1", "--pose", "0", "0", "0"],
            "--pose applies to a run of one robot: in a match, each robot's pose comes from its entry",
        ),
        (["--robot", "red:1", "--robot", "blue:1", "--view-robot", "2"], "--view-robot applies to --view in a match"),
        (["--view-robot", "1"], "--view-robot applies to --view in a match"),
        (["--robot", "red:1:2.95,0,0"], "--robot red:1:2.95,0,0: red 1 starts inside wall_skyblue"),
        (["--robot", "red:1:0,0,0", "--ball", "0.05", "0.07"], "--ball 0.05 0.07: the ball would overlap red 1 by"),
        (["--robot", "red:1::missing.py"], "error: --robot red:1::missing.py: red 1: /"),
    ],
)
def test_bad_robots_exit_2_with_one_line_and_no_folder(arguments, message, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", str(TRACKER), "--duration", "0.1", "--out", str(out), *arguments]) == 2
    error = capsys.readouterr().err
    assert message in error and error.count("\n") == 1
    assert not out.exists()


@pytest.mark.parametrize("command", ["run", "dump"])
def test_a_c_controller_that_does_not_compile_is_named_by_its_robots_line(command, tmp_path, capsys):
    """The compiler's error came without the robots file's line and the robot."""
    (tmp_path / "bad.c").write_text("#include <device/robot.h>\nint main(void) { robot_step(32) return 0; }\n")
    robots = tmp_path / "robots.toml"
    robots.write_text(
        f'[[robot]]\nteam = "red"\nnumber = 4\ncontroller = "{TRACKER}"\n\n'
        '[[robot]]\nteam = "blue"\nnumber = 4\ncontroller = "bad.c"\n'
    )
    length = ["--duration", "0.1"] if command == "run" else ["--steps", "2"]
    assert main([command, "--robots", str(robots), *length, "--out", str(tmp_path / "out")]) == 2
    first = capsys.readouterr().err.splitlines()[0]
    assert first == f"aibo-sim: error: {robots}:6: blue 4: {tmp_path / 'bad.c'}: compiling failed:", first
    assert not (tmp_path / "out").exists()


def test_robots_written_as_an_inline_array_are_named_by_its_line(tmp_path, capsys):
    robots = tmp_path / "robots.toml"
    robots.write_text('# two robots\nrobot = [{team = "red", number = 2}, {team = "red", number = 2}]\n')
    assert main(["run", str(TRACKER), "--duration", "0.1", "--robots", str(robots)]) == 2
    assert (
        capsys.readouterr().err == f"aibo-sim: error: {robots}:2: robot 2 (red 2): red 2 is also robot 1 ({robots}:2)\n"
    )


@pytest.mark.parametrize("command", ["run", "dump"])
def test_a_robot_without_a_controller_is_named_where_it_was_given(command, tmp_path, capsys):
    robots = tmp_path / "robots.toml"
    robots.write_text(
        '[[robot]]\nteam = "red"\nnumber = 2\ncontroller = "ctl.py"\n\n[[robot]]\nteam = "blue"\nnumber = 1\n'
    )
    (tmp_path / "ctl.py").write_text("x = (\n")
    out = ["--out", str(tmp_path / "out")]
    cases = [
        (["--robot", "red:2"], f"--robot red:2: red 2 has no controller: name one in its entry or give {command}'s"),
        (["--robots", str(robots)], f"{robots}:6: blue 1 has no controller"),
        (["--robots", str(robots), str(TRACKER)], f"{robots}:1: red 2: {tmp_path / 'ctl.py'}, line 1: SyntaxError"),
    ]
    for arguments, message in cases:
        assert main([command, *arguments, *out]) == 2
        error = capsys.readouterr().err
        assert error.startswith("aibo-sim: error: " + message) and error.count("\n") == 1, error
        assert not (tmp_path / "out").exists()


def test_a_match_never_leaves_another_runs_files_beside_its_own(tmp_path, capsys):
    out = tmp_path / "out"
    match = ["--camera-profile", "ideal", "--duration", "0.05", "--out", str(out)]
    three = ["--robot", "red:4", "--robot", "blue:1", "--robot", "blue:2"]
    assert main(["run", str(TRACKER), *three, *match]) == 0
    assert main(["run", str(TRACKER), "--robot", "red:4", *match]) == 2
    assert capsys.readouterr().err.endswith(
        f"{out} holds an earlier match's robot2 and 1 more (this match has 1 robot): its files would lie beside "
        "this match's; remove it or choose another --out\n"
    )
    assert main(["run", str(TRACKER), *match]) == 2
    assert "holds a match's run.json and robot folders: a run of one robot would leave them" in capsys.readouterr().err
    assert main(["run", str(TRACKER), *three, *match]) == 0  # the same match again: replaced
    assert json.loads((out / "run.json").read_text())["status"] == "done"
    single = tmp_path / "single"
    assert main(["run", str(TRACKER), "--camera-profile", "ideal", "--duration", "0.05", "--out", str(single)]) == 0
    assert main(["run", str(TRACKER), "--robot", "red:4", *match[:-1], str(single)]) == 2
    assert "holds a run of one robot (run.json and its frames): a match would leave" in capsys.readouterr().err
    assert not (single / "robot1").exists()


def test_a_match_says_it_is_incomplete_in_its_run_json_while_it_runs(tmp_path):
    seen = []
    out = tmp_path / "out"
    robots = [RobotSpec("red", 1, None, str(TRACKER)), RobotSpec("blue", 1, None, str(TRACKER))]
    listener = lambda program: seen or seen.append(json.loads((out / "run.json").read_text()))  # noqa: E731
    run_match(robots, duration=0.05, out=out, progress=False, camera=CameraConfig("ideal"), frame_listeners=[listener])
    assert seen[0] == {
        "match": True,
        "status": "incomplete",
        "robots": [r.as_dict() for r in check_robots(robots, "t")],
    }
    assert json.loads((out / "run.json").read_text())["status"] == "done"


@pytest.mark.parametrize("command", ["run", "dump"])
def test_a_match_scene_without_the_robot_or_ball_is_one_line_and_no_folder(command, tmp_path, capsys):
    empty = tmp_path / "empty.xml"
    empty.write_text("<mujoco><worldbody/></mujoco>")
    no_ball = ROOT / "models" / "ers7.xml"  # the robot alone: no ball to place
    length = ["--duration", "0.1"] if command == "run" else ["--steps", "2"]
    for scene, ball, message in (
        (empty, [], f"{empty}: no ERS-7 robot in this scene"),
        (no_ball, ["--ball", "1", "0"], "--ball 1 0: this scene has no body named 'ball' to place"),
    ):
        arguments = [command, str(TRACKER), "--robot", "red:1:0,0,0", "--scene", str(scene), *ball, *length]
        assert main([*arguments, "--out", str(tmp_path / "out")]) == 2
        error = capsys.readouterr().err
        assert message in error and error.count("\n") == 1
        assert not (tmp_path / "out").exists()


def test_a_robot_placed_inside_a_goal_is_named_by_its_robots_files_line(tmp_path, capsys):
    robots = tmp_path / "robots.toml"
    robots.write_text(
        "[[robot]]\nteam = 'red'\nnumber = 1\n\n[[robot]]\nteam = 'blue'\nnumber = 3\npose = [2.9, 0, 0]\n"
    )
    assert main(["run", str(TRACKER), "--duration", "0.1", "--robots", str(robots)]) == 2
    error = capsys.readouterr().err
    assert error.startswith(f"aibo-sim: error: {robots}:5: blue 3 starts inside ") and error.count("\n") == 1


def test_kickoff_poses_of_a_full_match_do_not_overlap():
    sim = Simulation(robots=FOUR_A_SIDE, camera=CameraConfig("ideal"))
    try:
        assert not [pair for pair in sim.overlaps(0.001) if "the ball" not in pair[:2]]
        assert {r.spec.pose for r in sim.world.robots} == {
            kickoff_pose(t, n) for t in ("red", "blue") for n in range(1, 5)
        }
    finally:
        sim.close()


@pytest.mark.slow
def test_every_kind_of_controller_plays_in_one_match(tmp_path):
    """A memory stick (ball_tracker_c built with build-ms and Sony's Makefile form), the same C
    controller compiled for the host, and the Python tracker, each on its own robot."""
    import subprocess

    from aibo_sim.openr.build_ms import build_ms
    from aibo_sim.openr.sdk import sdk_root

    stick = tmp_path / "tracker_ms"
    build_ms(ROOT / "controllers" / "ball_tracker_c", stick)
    made = subprocess.run(["make", f"OPENRSDK_ROOT={sdk_root()}", "install"], cwd=stick, capture_output=True, text=True)
    assert made.returncode == 0, made.stdout + made.stderr
    robots = [
        RobotSpec("red", 4, (-0.5, 0.0, 0.0), str(stick)),
        RobotSpec("blue", 4, (0.5, 0.0, 180.0), str(ROOT / "controllers" / "ball_tracker_c")),
        RobotSpec("red", 2, None, str(TRACKER)),
    ]
    summary = run_match(
        robots,
        duration=1.0,
        out=tmp_path / "out",
        progress=False,
        world=WorldConfig(ball=(0.0, 0.1)),
        camera=CameraConfig(full=True),
    )
    assert [r["backend"] for r in summary["robots"]] == ["memory stick", "c", "python"]
    # each robot's pictures: the stick's layer H, as its controller took them; the others' the full frame
    sizes = [(r["camera"]["width"], r["camera"]["height"]) for r in summary["robots"]]
    assert sizes == [(208, 160), (416, 320), (416, 320)]
    assert cv2.imread(str(next((tmp_path / "out" / "robot1" / "frames").glob("*.png")))).shape == (160, 208, 3)
    assert [r["status"] for r in summary["robots"]] == ["done"] * 3
    # the pictures each controller took; the stick's controller sees them 32 ms late (docs/openr.md)
    assert [r["camera_frames"] for r in summary["robots"]] == [29, 30, 30]
    assert (tmp_path / "out" / "robot1" / "console.log").is_file()


def test_robot_get_name_tells_a_shared_controller_which_robot_it_drives(tmp_path):
    """Every robot was "ERS-7": one controller run by several could not tell its team nor its goal."""
    python = tmp_path / "names.py"
    python.write_text("from aibo_sim.controller import *\nopen(robot_get_name() + '.py.txt', 'w').close()\n")
    c = tmp_path / "names.c"
    c.write_text(
        "#include <stdio.h>\n#include <device/robot.h>\nint main(void) {\n  char name[64];\n"
        '  snprintf(name, sizeof name, "%s.c.txt", robot_get_name());\n  fclose(fopen(name, "w"));\n  return 0;\n}\n'
    )
    robots = [RobotSpec("red", 3, None, str(python)), RobotSpec("blue", 2, None, str(c))]
    run_match(robots, duration=0.05, out=tmp_path / "out", progress=False, camera=CameraConfig("ideal"))
    run_match([RobotSpec(None, 1, None, str(python))], duration=0.05, out=tmp_path / "alone", progress=False)
    assert sorted(p.name for p in (tmp_path / "out").glob("*.txt")) == ["blue 2.c.txt", "red 3.py.txt"]
    assert [p.name for p in (tmp_path / "alone").glob("*.txt")] == ["ERS-7.py.txt"]


def test_an_api_call_from_another_thread_of_a_match_controller_says_why_it_has_no_robot(tmp_path):
    controller = tmp_path / "threaded.py"
    controller.write_text(
        "import threading\nfrom aibo_sim.controller import *\nerrors = []\n"
        "def read():\n    try:\n        robot_get_time()\n"
        "    except RuntimeError as exc:\n        errors.append(str(exc))\n"
        "reader = threading.Thread(target=read, name='reader')\nreader.start()\nreader.join()\n"
        "open('error.txt', 'w').write(errors[0])\nrobot_step(8)\n"
    )
    robots = [RobotSpec("red", 1, None, str(controller)), RobotSpec("blue", 1, None, str(TRACKER))]
    run_match(robots, duration=0.05, out=tmp_path / "out", progress=False, camera=CameraConfig("ideal"))
    assert (tmp_path / "out" / "error.txt").read_text() == (
        "no robot in thread 'reader': in a match, a controller's API calls must come from the thread that runs it"
    )


@pytest.mark.parametrize(
    "robots, message",
    [
        ([], "^robots: no robots$"),
        ([RobotSpec("red", 4), RobotSpec("red", 4)], "red 4 is also robot 1"),
        (
            [RobotSpec("red", 4, (9.0, 0.0, 0.0))],
            r"^robots: robot 1 \(red 4\): pose 9,0,0 is off the carpet \(\|x\| <= 3 m\) of the default",
        ),
        (
            [RobotSpec("red", 4), RobotSpec("blue", 2, (0.0, -3.0, 0.0), given="--robot blue:2:0,-3,0")],
            r"^--robot blue:2:0,-3,0: robot 2 \(blue 2\): pose 0,-3,0 is off the carpet \(\|y\| <= 2 m\)",
        ),
        ([RobotSpec("green", 4)], "unknown team 'green'"),
    ],
)
def test_a_simulation_checks_its_robots(robots, message):
    with pytest.raises(ValueError, match=message):
        Simulation(camera=CameraConfig("ideal"), robots=robots)


def test_a_robot_off_the_default_carpet_is_refused_on_the_default_field_only():
    """As --pose: a scene of one's own may be larger (a match's robots were refused in any scene)."""
    sim = Simulation(ROOT / "models" / "scene_webots.xml", camera=CameraConfig("ideal"), robots=[OFF_THE_CARPET])
    assert np.allclose(sim.world.robots[0].body_pose()[0][:2], (3.5, 0.0), atol=0.01)
    sim.close()
    with pytest.raises(ValueError, match=r"pose 3\.5,0,0 is off the carpet \(\|x\| <= 3 m\) of the default field$"):
        Simulation(camera=CameraConfig("ideal"), robots=[OFF_THE_CARPET])


OFF_THE_CARPET = RobotSpec("red", 4, (3.5, 0.0, 0.0))


def test_a_match_announces_a_python_controller_that_computes_long_naming_its_robot(tmp_path, monkeypatch, capsys):
    """As in a run of one robot (serve.WAIT_NOTICE_S without an API call): the others wait for it."""
    from aibo_sim.cbind import serve

    monkeypatch.setattr(serve, "WAIT_NOTICE_S", 0.2)
    busy = tmp_path / "busy.py"
    busy.write_text("import time\nfrom aibo_sim.controller import *\nrobot_step(40)\ntime.sleep(0.5)\nrobot_step(8)\n")
    robots = [RobotSpec("red", 1, None, str(TRACKER)), RobotSpec("blue", 1, None, str(busy))]
    run_match(robots, duration=0.1, out=None, progress=False, camera=CameraConfig("ideal"))
    err = capsys.readouterr().err
    assert (
        "aibo-sim: waiting for controller busy.py of blue 1: no API call for 0.2 s of wall time (simulated time "
        "stays at t = 0.040 s)\n"
    ) in err
