"""The command-line options that ``run``, ``render``, ``dump`` and ``mtn play`` share, with the
same names and meanings: the world (``--scene``, ``--pose``, ``--ball``, ``--seed``) and the
head camera (``--camera-profile``, ``--camera-wb``, ``--camera-gain``, ``--camera-shutter``,
``--camera-full``)."""

from __future__ import annotations

import argparse
import math

from openr_bridge import CAMERA_DEFAULTS, CAMERA_SETTINGS

from .camera import PROFILES, CameraSettings


def finite_float(text: str) -> float:
    """argparse type: a finite number (NaN and infinities are refused, naming the value)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value) or abs(value) > 1e6:
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number of reasonable size")
    return value


def add_world_options(parser: argparse.ArgumentParser, camera: bool = True) -> None:
    """--scene, --pose, --ball, --seed and (with ``camera``) the camera options."""
    parser.add_argument("--scene", help="MJCF scene file (default: the RoboCup 2005 field)")
    parser.add_argument("--pose", type=finite_float, nargs=3, metavar=("X", "Y", "YAW_DEG"),
                        help="robot position on the field (m) and heading (deg); default: the scene's start")
    parser.add_argument("--ball", type=finite_float, nargs=2, metavar=("X", "Y"), help="ball position on the field (m)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (IR and camera noise, randomised choices)")
    if not camera:
        return
    parser.add_argument("--camera-profile", choices=tuple(PROFILES), default="ers7",
                        help="head camera model: ers7 (the calibrated sensor, default) or ideal (the rendered picture)")
    for name, option in (("white_balance", "--camera-wb"), ("gain", "--camera-gain"), ("shutter", "--camera-shutter")):
        parser.add_argument(option, choices=tuple(CAMERA_SETTINGS[name][1]), default=CAMERA_DEFAULTS[name],
                            help=f"camera {name.replace('_', ' ')} at the start (default {CAMERA_DEFAULTS[name]})")
    parser.add_argument("--camera-full", action="store_true", help="render 416x320 (else the 208x160 layer)")


def camera_options(args: argparse.Namespace) -> dict:
    """Keyword arguments for ``Simulation`` (and ``run_controller``) from the camera options."""
    return {"camera_profile": args.camera_profile, "camera_full": args.camera_full,
            "camera_settings": CameraSettings(args.camera_wb, args.camera_gain, args.camera_shutter)}
