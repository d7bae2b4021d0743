"""The robots on the field for a match (RoboCup 2005 Four-Legged League: 4 against 4, red and blue).

A robots file (TOML) has one ``[[robot]]`` table per robot::

    [[robot]]
    team = "red"                            # required: red or blue
    number = 2                              # required: 1..4, 1 is the goalkeeper
    pose = [-1.35, 0.65, 0.0]               # optional: x, y (metres), yaw (degrees, as --pose); kickoff pose otherwise
    controller = "controllers/ball_tracker.py"  # optional: relative to the file's folder; the run's own otherwise

``--robot TEAM:NUMBER[:X,Y,YAW][:CONTROLLER]`` gives one robot on the command line. A bad
description is a ``TeamError`` of one line naming the file and the robot's ``[[robot]]`` line,
or the ``--robot`` argument. Poses are in the frame of ``field.py``: red defends the -X (yellow)
goal, blue the +X (sky-blue) one.
"""

from __future__ import annotations

import math
import os
import re
import reprlib
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

from .config import MAX_MAGNITUDE
from .field import (
    CENTRE_CIRCLE_RADIUS,
    FIELD_LENGTH,
    FIELD_WIDTH,
    FRINGE_END,
    FRINGE_SIDE,
    PENALTY_BOX_DEPTH,
    PENALTY_BOX_WIDTH,
)

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

TEAMS = ("red", "blue")
MAX_ROBOTS = 8
PLAYERS_PER_TEAM = 4
# Two robots' centres closer than this stand on one spot: the ERS-7's body is ~0.18 m wide.
MIN_SEPARATION = 0.2
POSE_LIMITS = (FIELD_LENGTH / 2 + FRINGE_END, FIELD_WIDTH / 2 + FRINGE_SIDE)  # |x|, |y|: on the carpet
ROBOT_KEYS = ("team", "number", "pose", "controller")

Pose = tuple[float, float, float]


class TeamError(ValueError):
    """A bad robots description; the message is one line naming the file (and line) or ``--robot``."""


@dataclass(frozen=True)
class RobotSpec:
    """One robot: its team (None: the lone robot without a uniform), player number (1..4, 1 is the
    goalkeeper), pose (x, y metres, yaw degrees as ``--pose``; None: the kickoff pose) and controller (a Python
    file, a C/C++ controller folder or file, or an OPEN-R memory stick folder; None: the run's own).
    ``given``: where it was described, for errors found later (a robots file's ``file:line``, or
    ``--robot red:2``); not part of the robot."""

    team: str | None
    number: int
    pose: Pose | None = None
    controller: str | None = None
    given: str | None = field(default=None, compare=False, repr=False)

    @property
    def name(self) -> str:
        """``red 2``; ``robot`` for the robot without a team."""
        return "robot" if self.team is None else f"{self.team} {self.number}"

    def as_dict(self) -> dict:
        """For run.json; ``from_dict`` reads it back."""
        pose = None if self.pose is None else list(self.pose)
        return {"team": self.team, "number": self.number, "pose": pose, "controller": self.controller}

    @classmethod
    def from_dict(cls, d: dict) -> RobotSpec:
        """The robot that ``as_dict`` wrote."""
        pose = d.get("pose")
        pose = None if pose is None else tuple(float(v) for v in pose)
        return cls(team=d["team"], number=int(d["number"]), pose=pose, controller=d.get("controller"))


DEFAULT_ROBOTS = (RobotSpec(team=None, number=1, pose=None, controller=None),)
"""One robot, today's behaviour: no uniform, the scene's own start pose, the run's controller."""


def kickoff_pose(team: str, number: int) -> Pose:
    """The kickoff pose of player ``number`` of ``team``: red in the -X half facing +X, blue the
    mirror image (turned half a turn about the centre spot). 1: goalkeeper in the middle of its
    penalty box; 2: left defender; 3: right wing; 4: striker just outside the centre circle."""
    if team not in TEAMS:
        raise ValueError(f"unknown team {team!r} (teams: {', '.join(TEAMS)})")
    half_length, half_width = FIELD_LENGTH / 2, FIELD_WIDTH / 2
    red = {
        1: (-half_length + PENALTY_BOX_DEPTH / 2, 0.0),
        2: (-half_length / 2, PENALTY_BOX_WIDTH / 2),
        3: (-half_length / 4, -half_width / 2),
        4: (-(CENTRE_CIRCLE_RADIUS + MIN_SEPARATION), 0.0),
    }
    if number not in red:
        raise ValueError(f"number {number!r} is not a player number (1..{PLAYERS_PER_TEAM})")
    x, y = red[number]
    return (x, y, 0.0) if team == "red" else (-x or 0.0, -y or 0.0, 180.0)  # or 0.0: no -0.0 in run.json


def _number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _pose_problem(pose: Sequence[float]) -> str | None:
    """Why ``pose`` cannot be a robot's pose (three finite numbers on the carpet), or None."""
    if not isinstance(pose, (list, tuple)) or len(pose) != 3 or not all(_number(v) for v in pose):
        return f"pose must be 3 numbers [x, y, yaw] (metres, degrees), not {pose!r}"
    if not all(math.isfinite(v) for v in pose):
        return f"pose {_show(pose)} is not finite numbers"
    if abs(pose[2]) > MAX_MAGNITUDE:
        return f"pose {_show(pose)}: yaw out of range (at most {MAX_MAGNITUDE:g} degrees in magnitude, as --pose)"
    return None


def check_on_the_carpet(robots: Sequence[RobotSpec]) -> None:
    """TeamError naming the first robot whose pose is off the default field's carpet (checked where
    the scene is known, as ``--pose`` is: a scene of one's own may be larger)."""
    for i, robot in enumerate(robots):
        problem = robot.pose is not None and off_the_carpet(robot.pose[0], robot.pose[1])
        if problem:
            raise TeamError(
                f"{robot.given or 'robots'}: {_label(i, robot.team, robot.number)}: pose {_show(robot.pose)} "
                f"is {problem} of the default field"
            )


def off_the_carpet(x: float, y: float) -> str | None:
    """``off the carpet (|x| <= 3 m)`` when (x, y) lies beyond the field's carpet, else None."""
    for axis, value, limit in (("x", x, POSE_LIMITS[0]), ("y", y, POSE_LIMITS[1])):
        if abs(value) > limit:
            return f"off the carpet (|{axis}| <= {limit:g} m)"
    return None


def _show(pose: Sequence[float]) -> str:
    return ",".join(f"{v:g}" for v in pose)


def _label(index: int, team, number) -> str:
    """``robot 3 (red 2)``: its place in the description, and its name once team and number are good."""
    if _team_and_number(team, number) is None:
        return f"robot {index + 1} ({team} {number})"
    return f"robot {index + 1}"


def _team_and_number(team, number) -> str | None:
    """Why ``team`` and ``number`` are not a team's player, or None."""
    if not isinstance(team, str):
        return f"team must be a string, not {team!r}"
    if team not in TEAMS:
        return f"unknown team {team!r} (teams: {', '.join(TEAMS)})"
    if not isinstance(number, int) or isinstance(number, bool):
        return f"number must be an integer, not {number!r}"
    if not 1 <= number <= PLAYERS_PER_TEAM:
        return f"number {number} is not a player number (1..{PLAYERS_PER_TEAM})"
    return None


def check_robots(robots: Sequence[RobotSpec] | str | os.PathLike, where: str) -> tuple[RobotSpec, ...]:
    """The checks across robots (how many, a team's numbers given twice, separation), with each
    robot's kickoff pose filled in where it has none. An error names the robot where it was
    described (``RobotSpec.given``: a robots file's line, a ``--robot`` argument), else ``where``
    (the description: a file, ``--robot``); TeamError otherwise. A path is a robots file
    (``load_robots``); anything but it or ``RobotSpec``s is a TeamError naming ``where``."""
    if isinstance(robots, (str, os.PathLike)):
        return load_robots(robots)
    given, robots = robots, tuple(robots) if isinstance(robots, Iterable) else None
    if robots is None or not all(isinstance(robot, RobotSpec) for robot in robots):
        raise TeamError(f"{where}: robots are a robots file or RobotSpecs, not {reprlib.repr(given)}")

    def fail(i: int, message: str):
        raise TeamError(f"{robots[i].given or where}: {_label(i, robots[i].team, robots[i].number)}: {message}")

    def place(i: int) -> str:
        return f"robot {i + 1}" + (f" ({robots[i].given})" if robots[i].given else "")

    if not robots:
        raise TeamError(f"{where}: no robots")
    if any(robot.team is None for robot in robots):
        if len(robots) == 1:
            return tuple(robots)
        fail(next(i for i, robot in enumerate(robots) if robot.team is None), "a robot without a team must be alone")
    if len(robots) > MAX_ROBOTS:
        fail(MAX_ROBOTS, f"more than {MAX_ROBOTS} robots")
    seen: dict[tuple[str, int], int] = {}
    for i, robot in enumerate(robots):
        problem = _team_and_number(robot.team, robot.number) or (robot.pose is not None and _pose_problem(robot.pose))
        if problem:
            fail(i, problem)
        if sum(1 for other in robots[: i + 1] if other.team == robot.team) > PLAYERS_PER_TEAM:
            fail(i, f"more than {PLAYERS_PER_TEAM} {robot.team} robots")
        first = seen.setdefault((robot.team, robot.number), i)
        if first != i:
            fail(i, f"{robot.name} is also {place(first)}")
    resolved = tuple(
        robot if robot.pose is not None else replace(robot, pose=kickoff_pose(robot.team, robot.number))
        for robot in robots
    )
    for i, robot in enumerate(resolved):
        for j in range(i):
            distance = math.dist(robot.pose[:2], resolved[j].pose[:2])
            if distance < MIN_SEPARATION:
                fail(
                    i,
                    f"stands {distance:.2f} m from {place(j)} ({resolved[j].name}): "
                    f"closer than {MIN_SEPARATION:g} m (robots ~0.18 m wide)",
                )
    return resolved


def _header_lines(text: str) -> list[int]:
    """The line (from 1) of each ``[[robot]]`` table header in ``text``, in order."""
    header = re.compile(r"""\s*\[\[\s*(robot|"robot"|'robot')\s*\]\]\s*(#.*)?""")
    return [n for n, line in enumerate(text.splitlines(), 1) if header.fullmatch(line)]


def _key_line(text: str, key: str) -> int | None:
    """The first line that defines top-level ``key`` (``key = ...``, ``[key]``, ``[[key]]``), or None."""
    pattern = re.compile(rf"""\s*\[*\s*("{re.escape(key)}"|'{re.escape(key)}'|{re.escape(key)})\s*[\]=.]""")
    return next((n for n, line in enumerate(text.splitlines(), 1) if pattern.match(line)), None)


def _table_robot(table: dict, folder: Path) -> RobotSpec:
    """The robot of one ``[[robot]]`` table; ValueError saying what is wrong otherwise."""
    unknown = [key for key in table if key not in ROBOT_KEYS]
    if unknown:
        raise ValueError(f"unknown key {unknown[0]!r} (keys: {', '.join(ROBOT_KEYS)})")
    for key in ("team", "number"):
        if key not in table:
            raise ValueError(f"no {key}")
    team, number = table["team"], table["number"]
    problem = _team_and_number(team, number)
    if problem:
        raise ValueError(problem)
    pose = table.get("pose")
    if pose is not None:
        problem = _pose_problem(pose)
        if problem:
            raise ValueError(problem)
        pose = tuple(float(v) for v in pose)
    controller = table.get("controller")
    if controller is not None:
        if not isinstance(controller, str) or not controller.strip():
            raise ValueError(f"controller must be a path (a non-empty string), not {controller!r}")
        controller = str(folder / Path(controller).expanduser())
    return RobotSpec(team=team, number=number, pose=pose, controller=controller)


def load_robots(path: str | Path) -> tuple[RobotSpec, ...]:
    """The robots of a TOML robots file (one ``[[robot]]`` table each, keys ``team``, ``number``,
    optional ``pose`` and ``controller``), each pose resolved (``check_robots``); a relative
    controller path is taken from the file's folder. TeamError of one line otherwise."""
    where = str(path)
    if Path(path).exists() and not Path(path).is_file():  # a folder; a FIFO would block
        raise TeamError(f"{where}: not a regular file")
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise TeamError(f"{where}: cannot read the robots file ({exc.strerror or exc})") from None
    except UnicodeDecodeError:
        raise TeamError(f"{where}: not a text file (UTF-8 TOML)") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        message = str(exc).splitlines()[0] if str(exc) else "syntax error"
        found = re.search(r"\s*\(at line (\d+), column (\d+)\)$", message)
        if found:
            message = f"{message[: found.start()]} (column {found[2]})"
            where = f"{where}:{found[1]}"
        elif message.endswith("(at end of document)"):
            where = f"{where}:{max(1, len(text.splitlines()))}"
        raise TeamError(f"{where}: invalid TOML: {message}") from None
    for key in data:
        if key != "robot":
            line = _key_line(text, key)
            at = where if line is None else f"{where}:{line}"
            raise TeamError(f"{at}: unknown key {key!r} (a robots file has only [[robot]] tables)")
    tables = data.get("robot", [])
    if not isinstance(tables, list) or not all(isinstance(table, dict) for table in tables):
        line = _key_line(text, "robot")
        at = where if line is None else f"{where}:{line}"
        raise TeamError(f"{at}: 'robot' must be [[robot]] tables, one a robot")
    if not tables:
        raise TeamError(f"{where}: no robots (one [[robot]] table a robot)")
    lines = _header_lines(text)
    if len(lines) != len(tables):  # robot = [{...}] inline: the line of its key names them all
        lines = [_key_line(text, "robot")] * len(tables)
    folder = Path(path).parent
    robots = []
    for i, table in enumerate(tables):
        at = where if lines[i] is None else f"{where}:{lines[i]}"
        try:
            robots.append(replace(_table_robot(table, folder), given=at))
        except ValueError as exc:
            raise TeamError(f"{at}: {_label(i, table.get('team'), table.get('number'))}: {exc}") from None
    return check_robots(robots, str(path))


def check_controllers(robots: Sequence[RobotSpec], controller, command: str) -> None:
    """TeamError naming, where it was given, the first robot without a controller when the
    command (``run``, ``dump``) has no CONTROLLER of its own for it."""
    missing = [robot for robot in robots if robot.controller is None] if controller is None else []
    if missing:
        first, more = missing[0], f" (and {len(missing) - 1} more)" if len(missing) > 1 else ""
        raise TeamError(
            f"{first.given or '--robots'}: {first.name} has no controller{more}: name one in its entry "
            f"or give {command}'s CONTROLLER"
        )


def parse_robot(text: str) -> RobotSpec:
    """The robot of ``--robot TEAM:NUMBER[:X,Y,YAW][:CONTROLLER]`` (``red:2``, ``blue:1:2.4,0,3.1416``,
    ``red:4:-0.6,0,0:controllers/ball_tracker.py``, ``red:3::ctl.py``: an empty pose is the kickoff
    pose). With three fields the third is the pose when it has a comma or is a number, else the
    controller. The pose is not resolved (``check_robots`` does). TeamError naming the argument otherwise."""

    def fail(message: str):
        raise TeamError(f"--robot {text}: {message}")

    parts = text.split(":", 3)
    if len(parts) < 2:
        fail("expected TEAM:NUMBER[:X,Y,YAW][:CONTROLLER], e.g. red:2")
    team, number_text = parts[0], parts[1]
    if not re.fullmatch(r"[0-9]+", number_text):
        fail(f"number {number_text!r} is not a player number (1..{PLAYERS_PER_TEAM})")
    number = int(number_text)
    problem = _team_and_number(team, number)
    if problem:
        fail(problem)
    pose_text, controller = "", None
    if len(parts) == 3:
        if "," in parts[2] or _is_float(parts[2]):
            pose_text = parts[2]
        else:
            controller = parts[2] or None
    elif len(parts) == 4:
        pose_text, controller = parts[2], parts[3] or None
    pose = None
    if pose_text:
        fields = pose_text.split(",")
        if len(fields) != 3 or not all(_is_float(f) for f in fields):
            fail(f"pose {pose_text!r} must be 3 numbers X,Y,YAW (metres, degrees)")
        pose = tuple(float(f) for f in fields)
        problem = _pose_problem(pose)
        if problem:
            fail(problem)
    return RobotSpec(team=team, number=number, pose=pose, controller=controller, given=f"--robot {text}")


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True
