"""The command-line options that ``run``, ``render``, ``dump`` and ``mtn play`` share, with the
same names, defaults and meanings: the world (``--scene``, ``--pose``, ``--ball``, ``--ball-type``, ``--seed``)
and the head camera (``--camera-profile``, ``--camera-wb``, ``--camera-gain``,
``--camera-shutter``, ``--camera-full``).

A bad value (an unknown profile or setting, a pose or ball that is not a finite number or that
puts the robot or ball into something, a negative seed) stops the command with exit status 2
and one line that names the option: ``ArgumentParser`` below is the parser class of
``aibo-sim`` and, through ``add_subparsers``, of every subcommand.
"""

from __future__ import annotations

import argparse
import math
import re

from openr_bridge import CAMERA_DEFAULTS, CAMERA_SETTINGS

from .camera import PROFILES, CameraSettings
from .config import MAX_MAGNITUDE, NO_PATH, SEED_LIMIT, CameraConfig, ParameterError, WorldConfig
from .exit_status import EXIT_BAD_INPUT
from .field import BALL_TYPES, DEFAULT_BALL_TYPE
from .team import MAX_ROBOTS, PLAYERS_PER_TEAM, TEAMS

CAMERA_SETTING_OPTIONS = (("white_balance", "--camera-wb"), ("gain", "--camera-gain"), ("shutter", "--camera-shutter"))
WORLD_DESTS = ("scene", "pose", "ball", "ball_type", "seed")
CAMERA_DESTS = ("camera_profile", "camera_wb", "camera_gain", "camera_shutter", "camera_full")
LONG_WORD = 120  # an error line's paths and arguments are cut after this many characters
# An argument that is a negative number as float() reads it (-1e-3, -1., -inf), not an option's
# name: argparse takes only -1 and -1.5 for numbers ("--pose -1e-3 0 0: expected 3 arguments").
NEGATIVE_NUMBER = re.compile(r"^-(\d[\d_]*\.?[\d_]*|\.\d[\d_]*)(e[+-]?\d[\d_]*)?$|^-(inf|infinity|nan)$", re.IGNORECASE)


def option_name(parameter: str) -> str:
    """The option that gives a library function's ``parameter``: ``ball_type`` -> ``--ball-type``."""
    return "--" + parameter.replace("_", "-")


def error_line(message) -> str:
    """The error line of ``message`` (text or an exception), a ``ParameterError`` naming options
    (``--pose``) where it names parameters, each run of more than ``LONG_WORD`` characters without
    a space or a quote (a path, an argument: a file's text given in place of its name) cut,
    saying how long it was."""
    if isinstance(message, ParameterError):
        message = message.named(option_name)
    return re.sub(
        rf"[^\s:,'\"`()\[\]]{{{LONG_WORD + 1},}}",
        lambda m: f"{m[0][:LONG_WORD]}... ({len(m[0])} characters)",
        str(message),
    )


class ArgumentParser(argparse.ArgumentParser):
    """argparse's parser, except that a usage error is one line on stderr (exit status 2):
    ``aibo-sim run: error: argument --ball: 'nan' is not a finite number (see aibo-sim run --help)``,
    and an argument no parser knows is named by the command it was given to (``aibo-sim render``);
    a negative number is a value whatever its form (``NEGATIVE_NUMBER``)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NEGATIVE_NUMBER  # argparse's own, an attribute of each parser

    def error(self, message: str):
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {error_line(message)} (see {self.prog} --help)\n")

    def parse_known_args(self, args=None, namespace=None):
        namespace, extras = super().parse_known_args(args, namespace)
        if extras:  # a subcommand's parser reports them itself; argparse's root would name only itself
            self.error(f"unrecognized arguments: {' '.join(extras)}")
        return namespace, extras


def finite_float(text: str) -> float:
    """argparse type: a finite number (NaN, infinities and magnitudes beyond 1e6 are refused,
    naming the value; argparse adds the option's name)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    if abs(value) > MAX_MAGNITUDE:
        raise argparse.ArgumentTypeError(f"{text!r} is out of range (at most {MAX_MAGNITUDE:g} in magnitude)")
    return value


def path_text(text: str) -> str:
    """argparse type: a file or folder name, which an empty string is not (a path made of it
    would name the current folder)."""
    if not text:
        raise argparse.ArgumentTypeError(NO_PATH)
    return text


def seed_number(text: str) -> int:
    """argparse type: a seed, a whole number from 0 to 2**64 - 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if not 0 <= value < SEED_LIMIT:
        raise argparse.ArgumentTypeError(f"{text!r} is out of range (a seed is a whole number from 0 to 2**64 - 1)")
    return value


def add_world_options(parser: argparse.ArgumentParser, ball_default: str = "the scene's") -> None:
    """--scene, --pose, --ball, --ball-type, --seed and the camera options; ``world_config`` and
    ``camera_config`` make the configs of them. ``ball_default`` says where the ball is without --ball."""
    parser.add_argument(
        "--scene", type=path_text, metavar="FILE", help="MJCF scene file, FILE.xml (default: the RoboCup 2005 field)"
    )
    parser.add_argument(
        "--pose",
        type=finite_float,
        nargs=3,
        metavar=("X", "Y", "YAW_DEG"),
        help="robot position on the field (m) and heading (deg); default: the scene's start",
    )
    parser.add_argument(
        "--ball",
        type=finite_float,
        nargs=2,
        metavar=("X", "Y"),
        help=f"ball position on the field (m); default: {ball_default}",
    )
    parser.add_argument(
        "--ball-type",
        choices=BALL_TYPES,
        default=DEFAULT_BALL_TYPE,
        help="the scene's ball: robocup (the scene's own, unchanged: on the default field the orange RoboCup "
        "ball, 84 mm; default) or pink (Sony's pink AIBO ball, 70 mm, which Sony's samples look for; "
        "scene_webots.xml's own)",
    )
    parser.add_argument(
        "--seed",
        type=seed_number,
        default=0,
        metavar="N",
        help="random seed (IR and camera noise, randomised choices; default 0)",
    )
    parser.add_argument(
        "--camera-profile",
        choices=tuple(PROFILES),
        default="ers7",
        help="head camera model: ers7 (the calibrated sensor, default) or ideal (the rendered picture)",
    )
    for name, option in CAMERA_SETTING_OPTIONS:
        parser.add_argument(
            option,
            choices=tuple(CAMERA_SETTINGS[name][1]),
            default=CAMERA_DEFAULTS[name],
            help=f"camera {name.replace('_', ' ')} at the start (default {CAMERA_DEFAULTS[name]})",
        )
    parser.add_argument("--camera-full", action="store_true", help="render 416x320 (else the 208x160 layer)")


def world_config(args: argparse.Namespace) -> WorldConfig:
    """The world the options ``--scene``, ``--seed``, ``--pose``, ``--ball``, ``--ball-type`` describe."""
    return WorldConfig(
        args.scene, args.seed, args.pose and tuple(args.pose), args.ball and tuple(args.ball), args.ball_type
    )


def camera_config(args: argparse.Namespace) -> CameraConfig:
    """The camera the camera options describe."""
    return CameraConfig(
        args.camera_profile, args.camera_full, CameraSettings(args.camera_wb, args.camera_gain, args.camera_shutter)
    )


def add_robots_options(parser: argparse.ArgumentParser) -> None:
    """--robots FILE and the repeated --robot: the robots of a match (``robots_of`` reads them)."""
    parser.add_argument(
        "--robots",
        type=path_text,
        metavar="FILE",
        help=f"a match: a TOML file of [[robot]] tables (team {'|'.join(TEAMS)}, number 1-{PLAYERS_PER_TEAM}, "
        f"optional pose [x, y, yaw_deg] and controller), up to {MAX_ROBOTS} robots; each robot's frames go to "
        "--out/robotN",
    )
    parser.add_argument(
        "--robot",
        action="append",
        default=[],
        metavar="TEAM:NUMBER[:X,Y,YAW_DEG][:CONTROLLER]",
        help="a match robot (repeat for each; instead of --robots), e.g. red:4 or blue:1:2.4,0,180",
    )


def robots_of(args: argparse.Namespace, command: str) -> list | None:
    """The robots (``team.RobotSpec``) of ``--robots FILE`` or the repeated ``--robot``, or None for
    one robot; ValueError naming the option that cannot go with them (``command``: run or dump)."""
    from .match import refuse_single_robot_options
    from .team import check_robots, load_robots, parse_robot

    if args.robots is None and not args.robot:
        return None
    if args.robots is not None and args.robot:
        raise ValueError("--robots and --robot: give the robots one way, not both")
    options = {"--pose": args.pose, "--backend": args.backend, "--mtn-mode": args.mtn_mode}
    refuse_single_robot_options(command, {**options, "--memory-stick": args.memory_stick})
    if args.robots is not None:
        return load_robots(args.robots)
    return check_robots([parse_robot(text) for text in args.robot], "--robot")
