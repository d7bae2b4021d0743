"""The robots on the field: kickoff poses, robots files, --robot, and their one-line errors."""

from __future__ import annotations

import itertools
import json
import math
import os
from pathlib import Path

import pytest

from aibo_sim import field
from aibo_sim.team import (
    DEFAULT_ROBOTS,
    MAX_ROBOTS,
    MIN_SEPARATION,
    PLAYERS_PER_TEAM,
    TEAMS,
    RobotSpec,
    TeamError,
    check_robots,
    kickoff_pose,
    load_robots,
    parse_robot,
)

HALF_LENGTH, HALF_WIDTH = field.FIELD_LENGTH / 2, field.FIELD_WIDTH / 2
PLAYERS = [(team, number) for team in TEAMS for number in range(1, PLAYERS_PER_TEAM + 1)]


def robot_table(team: str = "red", number: int = 1, **more: str) -> str:
    """One ``[[robot]]`` table; ``more`` values are TOML text."""
    lines = ["[[robot]]", f'team = "{team}"', f"number = {number}"]
    lines += [f"{key} = {value}" for key, value in more.items()]
    return "\n".join(lines) + "\n"


def write(tmp_path: Path, text: str, name: str = "robots.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def load_error(tmp_path: Path, text: str) -> str:
    """The one-line message that loading ``text`` as a robots file gives."""
    path = write(tmp_path, text)
    with pytest.raises(TeamError) as info:
        load_robots(path)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{path}"), message
    return message


# --- RobotSpec ---


@pytest.mark.parametrize(
    "spec",
    [
        RobotSpec("red", 2, (-1.0, 0.5, 0.25), "controllers/ball_tracker.py"),
        RobotSpec("blue", 1, None, None),
        DEFAULT_ROBOTS[0],
    ],
)
def test_spec_round_trips_through_json(spec):
    back = RobotSpec.from_dict(json.loads(json.dumps(spec.as_dict())))
    assert back == spec
    assert set(spec.as_dict()) == {"team", "number", "pose", "controller"}


def test_names():
    assert RobotSpec("red", 2).name == "red 2"
    assert RobotSpec("blue", 4, (0, 0, 0)).name == "blue 4"
    assert DEFAULT_ROBOTS[0].name == "robot"
    assert DEFAULT_ROBOTS == (RobotSpec(team=None, number=1, pose=None, controller=None),)


# --- kickoff poses ---


def test_kickoff_poses_on_the_field_in_own_half_facing_the_other_goal():
    for team, number in PLAYERS:
        x, y, yaw = kickoff_pose(team, number)
        assert abs(x) < HALF_LENGTH and abs(y) < HALF_WIDTH, (team, number)
        if team == "red":
            assert x < 0 and yaw == 0.0, (team, number)
        else:
            assert x > 0 and yaw == 180.0, (team, number)


def test_kickoff_goalkeeper_in_its_penalty_box_and_striker_outside_the_centre_circle():
    for team, sign in (("red", -1), ("blue", 1)):
        x, y, _ = kickoff_pose(team, 1)
        assert sign * x > HALF_LENGTH - field.PENALTY_BOX_DEPTH and abs(y) < field.PENALTY_BOX_WIDTH / 2
        x, y, _ = kickoff_pose(team, 4)
        assert math.hypot(x, y) > field.CENTRE_CIRCLE_RADIUS
        assert abs(x) < HALF_LENGTH / 2  # near the centre, not back with the defenders
        for number in (2, 3):  # the field players stay out of the goalkeeper's box
            assert sign * kickoff_pose(team, number)[0] < HALF_LENGTH - field.PENALTY_BOX_DEPTH


def test_kickoff_poses_pairwise_separated():
    poses = {player: kickoff_pose(*player) for player in PLAYERS}
    for a, b in itertools.combinations(PLAYERS, 2):
        assert math.dist(poses[a][:2], poses[b][:2]) >= 2 * MIN_SEPARATION, (a, b)


def test_kickoff_pose_refuses_unknown_players():
    with pytest.raises(ValueError):
        kickoff_pose("green", 1)
    with pytest.raises(ValueError):
        kickoff_pose("red", 5)


# --- robots files ---


def test_four_against_four_loads(tmp_path):
    tables = [robot_table(team, number, controller='"ctl/striker.py"') for team, number in PLAYERS if number == 4]
    tables += [
        robot_table(team, number) for team, number in PLAYERS if number in (2, 3) or (team, number) == ("blue", 1)
    ]
    tables.append(robot_table("red", 1, pose="[-2.0, 0.3, 0.1]"))
    sub = tmp_path / "match"
    sub.mkdir()
    robots = load_robots(write(sub, "# a match\n" + "\n".join(tables)))
    assert len(robots) == MAX_ROBOTS
    assert sorted((r.team, r.number) for r in robots) == sorted(PLAYERS)
    by_name = {r.name: r for r in robots}
    assert by_name["red 1"].pose == (-2.0, 0.3, 0.1)
    assert by_name["blue 2"].pose == kickoff_pose("blue", 2)  # resolved
    assert all(r.pose is not None for r in robots)
    assert Path(by_name["red 4"].controller) == sub / "ctl" / "striker.py"
    assert Path(by_name["blue 4"].controller) == sub / "ctl" / "striker.py"
    assert by_name["red 2"].controller is None


def test_absolute_controller_kept(tmp_path):
    ctl = tmp_path / "elsewhere" / "ms"
    robots = load_robots(write(tmp_path, robot_table("blue", 3, controller=json.dumps(str(ctl)))))
    assert robots == (RobotSpec("blue", 3, kickoff_pose("blue", 3), str(ctl)),)


def test_inline_robot_array_loads(tmp_path):
    robots = load_robots(write(tmp_path, 'robot = [{team = "red", number = 4}, {team = "blue", number = 4}]\n'))
    assert [r.name for r in robots] == ["red 4", "blue 4"]


# The bad robot is always the third table, whose header is on line 9 (after a comment line).
GOOD = "# test\n" + robot_table("red", 1) + "\n" + robot_table("blue", 1)
BAD_LINE = 9


@pytest.mark.parametrize(
    ("table", "expected"),
    [
        (robot_table("green", 2), "robot 3: unknown team 'green' (teams: red, blue)"),
        (robot_table("red", 5), "robot 3: number 5 is not a player number (1..4)"),
        (robot_table("red", 0), "robot 3: number 0 is not a player number"),
        (robot_table("red", 2, colour='"red"'), "robot 3 (red 2): unknown key 'colour'"),
        ('[[robot]]\nteam = "red"\n', "robot 3: no number"),
        ("[[robot]]\nnumber = 2\n", "robot 3: no team"),
        ("[[robot]]\nteam = 1\nnumber = 2\n", "robot 3: team must be a string"),
        ('[[robot]]\nteam = "red"\nnumber = "2"\n', "robot 3: number must be an integer"),
        ('[[robot]]\nteam = "red"\nnumber = 2.0\n', "robot 3: number must be an integer"),
        (robot_table("red", 2, pose="[1, 2]"), "robot 3 (red 2): pose must be 3 numbers"),
        (robot_table("red", 2, pose='[1, 2, "x"]'), "robot 3 (red 2): pose must be 3 numbers"),
        (robot_table("red", 2, pose="[true, 0, 0]"), "robot 3 (red 2): pose must be 3 numbers"),
        (robot_table("red", 2, pose="[nan, 0, 0]"), "robot 3 (red 2): pose nan,0,0 is not finite numbers"),
        (robot_table("red", 2, pose="[0, 0, inf]"), "robot 3 (red 2): pose 0,0,inf is not finite"),
        (robot_table("red", 2, controller="3"), "robot 3 (red 2): controller must be a path"),
        (robot_table("red", 2, controller='""'), "robot 3 (red 2): controller must be a path"),
        (robot_table("red", 1), "robot 3 (red 1): red 1 is also robot 1 ({file}:2)"),
        (
            robot_table("red", 2, pose="[-2.275, 0, 0]"),
            "robot 3 (red 2): stands 0.10 m from robot 1 ({file}:2) (red 1)",
        ),
        (
            robot_table("red", 2, pose="[2.275, 0, 0]"),
            "robot 3 (red 2): stands 0.10 m from robot 2 ({file}:6) (blue 1)",
        ),
    ],
)
def test_bad_robot_names_file_line_and_robot(tmp_path, table, expected):
    message = load_error(tmp_path, GOOD + table)
    file = message.split(":", 1)[0]  # the other robot is named by its file and line too
    assert f"robots.toml:{BAD_LINE}: {expected.format(file=file)}" in message, message


def test_edge_of_carpet_and_exact_separation_accepted(tmp_path):
    edge = field.FIELD_LENGTH / 2 + field.FRINGE_END
    text = robot_table("red", 1, pose=f"[{-edge}, 0, 0]") + robot_table("red", 2, pose=f"[{-edge + 0.25}, 0, 0]")
    assert [r.pose[0] for r in load_robots(write(tmp_path, text))] == [-edge, -edge + 0.25]


def test_fifth_robot_of_a_team(tmp_path):
    text = "".join(robot_table("red", n) for n in (1, 2, 3, 4)) + robot_table("red", 1, pose="[0, 1, 0]")
    message = load_error(tmp_path, text)
    assert "robots.toml:13: robot 5 (red 1): more than 4 red robots" in message, message


def test_more_than_max_robots(tmp_path):
    text = "".join(robot_table(team, number) for team, number in PLAYERS) + robot_table("blue", 2, pose="[0, 1, 0]")
    message = load_error(tmp_path, text)
    assert f"robots.toml:{3 * MAX_ROBOTS + 1}: robot 9 (blue 2): more than 8 robots" in message, message


def test_toml_syntax_error_has_its_line(tmp_path):
    message = load_error(tmp_path, robot_table("red", 1) + "[[robot]]\nteam = \nnumber = 2\n")
    assert "robots.toml:5: invalid TOML: Invalid value (column 8)" in message, message


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("", "robots.toml: no robots"),
        ("# nothing\n", "robots.toml: no robots"),
        ("robot = []\n", "robots.toml: no robots"),
        ("# top\nteams = 2\n" + robot_table(), "robots.toml:2: unknown key 'teams'"),
        ("[robot]\nteam = 'red'\nnumber = 1\n", "robots.toml:1: 'robot' must be [[robot]] tables"),
        ("robot = 3\n", "robots.toml:1: 'robot' must be [[robot]] tables"),
    ],
)
def test_bad_file_level(tmp_path, text, expected):
    message = load_error(tmp_path, text)
    assert expected in message, message


def test_missing_and_unreadable_files(tmp_path):
    fifo = tmp_path / "fifo.toml"
    os.mkfifo(fifo)  # read as a file, it would wait for a writer
    for path, why in (
        (tmp_path / "absent.toml", "cannot read the robots file"),
        (tmp_path, "not a regular file"),
        (fifo, "not a regular file"),
    ):
        with pytest.raises(TeamError) as info:
            load_robots(path)
        assert str(info.value).startswith(f"{path}: {why}")
        assert "\n" not in str(info.value)
    binary = tmp_path / "binary.toml"
    binary.write_bytes(b"\xff\xfe\x00robot")
    with pytest.raises(TeamError, match="binary.toml: not a text file"):
        load_robots(binary)


# --- check_robots and --robot ---


def test_check_robots_resolves_and_keeps_the_default_robot():
    assert check_robots(DEFAULT_ROBOTS, "--robot") == DEFAULT_ROBOTS
    robots = check_robots([parse_robot("red:4"), parse_robot("blue:1:2.4,0,180")], "--robot")
    assert robots == (RobotSpec("red", 4, kickoff_pose("red", 4)), RobotSpec("blue", 1, (2.4, 0.0, 180)))


@pytest.mark.parametrize(
    ("robots", "expected"),
    [
        ([], "--robot: no robots"),
        (["red:2", "red:2:0,1,0"], "--robot red:2:0,1,0: robot 2 (red 2): red 2 is also robot 1 (--robot red:2)"),
        (
            ["red:2:0,0,0", "blue:2:0.1,0.1,0"],
            "--robot blue:2:0.1,0.1,0: robot 2 (blue 2): stands 0.14 m from robot 1 (--robot red:2:0,0,0) (red 2)",
        ),
        ([RobotSpec("red", 1), RobotSpec("red", 1)], "--robot: robot 2 (red 1): red 1 is also robot 1"),
    ],
)
def test_check_robots_errors(robots, expected):
    with pytest.raises(TeamError) as info:
        check_robots([parse_robot(r) if isinstance(r, str) else r for r in robots], "--robot")
    assert str(info.value).startswith(expected), str(info.value)


def test_check_robots_refuses_a_teamless_robot_among_others():
    with pytest.raises(TeamError, match="without a team must be alone"):
        check_robots([*DEFAULT_ROBOTS, RobotSpec("red", 1)], "--robot")


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("red:2", RobotSpec("red", 2)),
        ("blue:1:2.4,0,180", RobotSpec("blue", 1, (2.4, 0.0, 180))),
        (
            "red:4:-0.6,0,0:controllers/ball_tracker.py",
            RobotSpec("red", 4, (-0.6, 0.0, 0.0), "controllers/ball_tracker.py"),
        ),
        ("red:3::controllers/ball_tracker.py", RobotSpec("red", 3, None, "controllers/ball_tracker.py")),
        ("red:3:controllers/ball_tracker_c", RobotSpec("red", 3, None, "controllers/ball_tracker_c")),
        ("blue:2:", RobotSpec("blue", 2)),
        ("blue:2:1,1,0:C:/ms", RobotSpec("blue", 2, (1.0, 1.0, 0.0), "C:/ms")),
    ],
)
def test_parse_robot_forms(text, expected):
    assert parse_robot(text) == expected


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("red", "expected TEAM:NUMBER"),
        ("green:2", "unknown team 'green' (teams: red, blue)"),
        ("Red:2", "unknown team 'Red'"),
        ("red:5", "number 5 is not a player number (1..4)"),
        ("red:0", "number 0 is not a player number"),
        ("red:two", "number 'two' is not a player number"),
        ("red:", "number '' is not a player number"),
        ("red:2:1,2", "pose '1,2' must be 3 numbers X,Y,YAW"),
        ("red:2:1,2,x:ctl.py", "pose '1,2,x' must be 3 numbers"),
        ("red:2:1.5", "pose '1.5' must be 3 numbers"),
        ("red:2:nan,0,0", "pose nan,0,0 is not finite numbers"),
    ],
)
def test_parse_robot_errors(text, expected):
    with pytest.raises(TeamError) as info:
        parse_robot(text)
    message = str(info.value)
    assert message.startswith(f"--robot {text}: {expected}"), message
    assert "\n" not in message
