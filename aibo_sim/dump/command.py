"""The ``aibo-sim dump`` subcommand."""

from __future__ import annotations

import argparse
import sys

from openr_bridge import FRAME_RATE_HZ

from ..config import DEFAULT_DURATION_S, MAX_MAGNITUDE
from ..mtn import MODES as MTN_MODES
from ..options import (
    add_robots_options,
    add_world_options,
    camera_config,
    finite_float,
    path_text,
    robots_of,
    world_config,
)
from ..robot import BACKENDS
from ..runner import check_duration
from .formats import DEFAULT_FORMATS, FORMATS
from .running import ENGINES, POLICIES, dump


def _dump_command(args) -> int:
    formats = tuple(f.strip() for f in args.formats.split(",") if f.strip())
    if "all" in formats and len(formats) > 1:
        raise ValueError(f"--formats {args.formats}: all (every format) cannot be combined with other names")
    formats = FORMATS if formats == ("all",) else formats
    if args.steps is not None and not 1 <= args.steps <= MAX_MAGNITUDE:
        raise ValueError(f"--steps must be a whole number from 1 to {MAX_MAGNITUDE:.0f}, not {args.steps}")
    if args.duration is not None:
        check_duration(args.duration)
    frames = args.steps if args.steps is not None else round((args.duration or DEFAULT_DURATION_S) * FRAME_RATE_HZ)
    if frames < 1:
        raise ValueError(
            f"--duration {args.duration:g} s holds no camera frame: give at least "
            f"{0.5 / FRAME_RATE_HZ:.3f} s (frames are 1/{FRAME_RATE_HZ} s apart)"
        )
    robots = robots_of(args, "dump")  # a match: one dump per robot
    # Ctrl-C and SIGTERM (``cli._SignalsStopCleanly``) stop it cleanly: writers abort, workers stop.
    summary = dump(
        args.out,
        controller=args.controller,
        env=args.env,
        policy=args.policy,
        frames=frames,
        backend=args.backend,
        world=world_config(args),
        camera=camera_config(args),
        formats=formats,
        resume=args.resume,
        workers=args.workers,
        engine=args.engine,
        ray_address=args.ray_address,
        mtn_mode=args.mtn_mode,
        memory_stick=args.memory_stick,
        robots=robots,
    )
    repaired = f", {summary.repaired_frames} with missing or damaged files rewritten" if summary.repaired_frames else ""
    shown = f"{summary.frames} frame{'s' * (summary.frames != 1)}"
    if robots is not None:
        shown += f" of {len(robots)} robot{'s' * (len(robots) != 1)}"
    print(
        f"dumped {shown} to {summary.out} ({summary.new_frames} written now{repaired}) in "
        f"{summary.wall_s:.1f} s: {summary.frames_per_s:.1f} frames/s, "
        f"{summary.bytes_written / 1e6 / max(summary.wall_s, 1e-9):.2f} MB/s"
    )
    asked = frames * (len(robots) if robots is not None else 1)
    if summary.frames < asked:  # not an error: said, as a forgotten robot_run goes unseen
        print(
            f"aibo-sim: note: the dump holds {summary.frames} of the {asked} frames asked: "
            "its controller ended first (a controller steps with robot_step, or with robot_run's function)",
            file=sys.stderr,
        )
    return 0


def add_dump_parser(subcommands) -> argparse.ArgumentParser:
    """Add the ``dump`` subcommand to the ``aibo-sim`` subparsers."""
    parser = subcommands.add_parser(
        "dump",
        help="write every camera frame of a headless run (images, YUV, OPEN-R)",
        description=sys.modules[__package__].__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "controller",
        nargs="?",
        type=path_text,
        help="controller file (or use --env); in a match, the controller of the robots that name none",
    )
    add_robots_options(parser)
    parser.add_argument("--env", help="gymnasium environment id, e.g. aibo_sim/HeadTrackBall-v0")
    parser.add_argument("--policy", choices=POLICIES, help="environment dumps: the policy (default random)")
    parser.add_argument("--out", type=path_text, required=True, help="dump folder: new, empty, or a dump to --resume")
    length = parser.add_mutually_exclusive_group()
    length.add_argument("--duration", type=finite_float, help="simulated seconds, 30 frames each (default 10)")
    length.add_argument("--steps", type=int, help="camera frames (controller) or environment steps")
    parser.add_argument(
        "--backend",
        choices=BACKENDS,
        help="controller dumps: what the controller sees (default sim); not for a memory stick",
    )
    parser.add_argument(
        "--mtn-mode",
        choices=MTN_MODES,
        help="controller dumps: MTN playback, OPEN-R interpolation (default openr) or Webots keyframe stepping",
    )
    parser.add_argument(
        "--memory-stick",
        type=path_text,
        metavar="DIR",
        help="controller dumps: OPEN-R memory stick folder for the openr backend",
    )
    add_world_options(parser)  # --scene, --pose, --ball, --seed (shard k of --workers: seed + k), camera
    parser.add_argument(
        "--formats",
        default=",".join(DEFAULT_FORMATS),
        help=f"comma-separated from {','.join(FORMATS)}, or all (default {','.join(DEFAULT_FORMATS)})",
    )
    parser.add_argument("--resume", action="store_true", help="continue an interrupted dump in --out")
    parser.add_argument("--workers", type=int, default=1, help="processes; the frames are split into shards")
    parser.add_argument(
        "--engine",
        choices=ENGINES,
        default="local",
        help="where the shards run: local processes (default) or Ray tasks (pip install 'aibo-sim[ray]')",
    )
    parser.add_argument(
        "--ray-address",
        metavar="ADDR",
        help="with --engine ray: a running Ray cluster's address (default: start a local Ray)",
    )
    parser.set_defaults(handler=_dump_command)
    return parser
