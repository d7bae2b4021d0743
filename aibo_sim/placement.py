"""Where a run starts and writes, checked before it begins: the robot's pose and the ball's
position (``start_values``, ``place``, ``check_place``) and the output folder
(``out_path``, ``make_out_folder``).

An argument that cannot be used is a ``ParameterError`` naming the parameter (``pose``,
``ball``, ``scene``, ``out``); the command line names its option instead (``--pose``).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import mujoco

from .config import CameraConfig, ParameterError, refuse_empty_path
from .field import DEFAULT_BALL_TYPE
from .sim import ModelError, Simulation, ball_joint
from .team import off_the_carpet

PLACEMENT_OVERLAP_M = 0.005  # a placed robot or ball sunk deeper than this into something is an error


def out_path(path) -> Path:
    """The output folder ``out`` resolved: it, or a folder above it, may be a link to a folder,
    not a link to nothing (aibo-sim makes no folder through a link it did not make); a
    ``ParameterError`` naming it (an empty string names no folder: the working folder was written)."""
    refuse_empty_path("out", path)
    path = Path(path)
    for link in (path, *path.parents):
        if link.is_symlink() and not link.exists():
            where = "" if link == path else f" (its folder {link})"
            raise ParameterError.at("out", path, f"a link{where} to {os.readlink(link)}, which does not exist")
    return path.resolve()


def checked_out_path(path) -> Path:
    """``out_path``, and a ``ParameterError`` naming ``out`` if it is a file."""
    path = out_path(path)
    if path.exists() and not path.is_dir():
        raise ParameterError.at("out", path, "not a folder")
    return path


def make_out_folder(path) -> Path:
    """The output folder ``out`` (``checked_out_path``), made with its parents."""
    path = checked_out_path(path)
    path.mkdir(parents=True, exist_ok=True)
    return path


def check_place(
    scene, pose: tuple[float, float, float] | None, ball: tuple[float, float] | None, ball_type: str = DEFAULT_BALL_TYPE
) -> None:
    """``place``'s errors for these placements in ``scene``, before a command writes anything."""
    sim = Simulation(scene, camera=CameraConfig("ideal"), ball_type=ball_type)
    try:
        place(sim, pose, ball)
    finally:
        sim.close()


def _given(values) -> str:
    """Numbers as the command line gave them (``--ball 0.6 0.25``)."""
    return " ".join(f"{v:g}" for v in values)


def ball_off_the_field(sim, ball) -> str | None:
    """``off the carpet (|x| <= 3 m) of the default field`` where the ball at ``ball`` (x, y) would
    lie beyond the default field's walls; None inside them, and anywhere in a scene of one's own."""
    problem = off_the_carpet(*ball) if sim.default_field else None
    return None if problem is None else f"{problem} of the default field"


def ball_start_problem(sim, ball, data: mujoco.MjData) -> str | None:
    """Why the ball cannot start at ``ball`` (x, y) with everything else as in ``data`` (a copy: the
    ball is moved in it): ``lies off the carpet ...`` (``ball_off_the_field``), or ``would overlap
    blue 4 by 3.6 cm`` where it sinks deeper than ``PLACEMENT_OVERLAP_M`` into something, as run
    refuses them; None where it can."""
    off = ball_off_the_field(sim, ball)
    if off is not None:
        return f"lies {off}"
    model = sim.model
    start = model.jnt_qposadr[ball_joint(model)]
    data.qpos[start : start + 3] = (*ball, model.geom("ball").size[0])
    mujoco.mj_fwdPosition(model, data)
    for first, second, depth in sim.overlaps(PLACEMENT_OVERLAP_M, data):
        if "the ball" in (first, second):
            return f"would overlap {second if first == 'the ball' else first} by {depth * 100:.1f} cm"
    return None


def _place_ball(sim, ball: tuple[float, float] | None) -> None:
    """The ball at ``ball`` when given; a ``ParameterError`` naming ``ball`` where it cannot go
    (off the default field, or in a scene without a ball)."""
    if ball is not None:
        off = ball_off_the_field(sim, ball)
        if off is not None:
            raise ParameterError.at("ball", _given(ball), off)
        try:
            sim.place_ball(*ball)
        except ModelError as exc:
            raise ParameterError.at("ball", _given(ball), str(exc)) from None


def place(sim, pose: tuple[float, float, float] | None = None, ball: tuple[float, float] | None = None) -> None:
    """Put the robot at ``pose`` (x, y in metres, yaw in degrees) and the ball at ``ball`` (x, y),
    each when given; the scene's start otherwise. ``ParameterError`` naming ``ball`` when the
    scene's ball cannot be placed, and naming the parameter when what it placed would sink more
    than ``PLACEMENT_OVERLAP_M`` into something (a wall, a goal, the robot or the ball), which the
    first step would fling apart; naming ``scene`` when the scene's own start does."""
    if pose is not None:
        x, y, yaw_deg = pose
        problem = off_the_carpet(x, y) if sim.default_field else None  # a scene of one's own may be larger
        if problem is not None:
            raise ParameterError.at("pose", _given(pose), f"{problem} of the default field")
        sim.place_robot(x, y, math.radians(yaw_deg))
    _place_ball(sim, ball)
    placed = {"the robot": ("pose", pose), "the ball": ("ball", ball)}
    for first, second, depth in sim.overlaps(PLACEMENT_OVERLAP_M):
        pairs = ((first, second), (second, first))
        for subject, other in pairs:
            parameter, values = placed.get(subject, (None, None))
            if values is not None:
                raise ParameterError.at(
                    parameter, _given(values), f"{subject} would overlap {other} by {depth * 100:.1f} cm"
                )
        for subject, other in pairs:
            if subject in placed and subject != other:
                reason = f"{subject} starts inside {other} ({depth * 100:.1f} cm deep)"
                raise ParameterError.at(
                    "scene", sim.scene, f"{reason}; move it in the scene, or place it with", fix=placed[subject][0]
                )


def place_match(sim, ball: tuple[float, float] | None = None) -> None:
    """Put the ball of a match's world at ``ball`` (x, y) when given, then check that nothing
    starts inside something else deeper than ``PLACEMENT_OVERLAP_M``: a ``ParameterError`` naming
    ``ball`` for the ball placed so, a ValueError naming where a robot was described
    (``RobotSpec.given``: the robots file's line, or the ``--robot`` argument) for a robot."""
    _place_ball(sim, ball)
    robots = sim.world.robots
    names = {"the robot": robots[0].spec.name} if len(robots) == 1 else {}  # Simulation.overlaps' name for it
    given = {robot.spec.name: robot.spec.given for robot in robots}
    for first, second, depth in sim.overlaps(PLACEMENT_OVERLAP_M):
        first, second = names.get(first, first), names.get(second, second)
        if first == second:
            continue
        if ball is not None and "the ball" in (first, second):
            other = second if first == "the ball" else first
            raise ParameterError.at("ball", _given(ball), f"the ball would overlap {other} by {depth * 100:.1f} cm")
        robot, other = (first, second) if first in given else (second, first)
        reason = f"{robot} starts inside {other} ({depth * 100:.1f} cm deep)"
        if robot not in given:  # the scene's own start
            raise ParameterError.at("scene", sim.scene, reason)
        raise ValueError(f"{given[robot] or 'robots'}: {reason}")  # where it was described, else the argument
