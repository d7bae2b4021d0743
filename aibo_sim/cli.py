"""The ``aibo-sim`` command: run controllers, render the camera, inspect and play MTN files."""

from __future__ import annotations

import argparse
import dataclasses
import io
import json
import os
import select
import signal
import sys
import threading
import time
from pathlib import Path

import numpy as np

from openr_bridge import FULL_HEIGHT, FULL_WIDTH, LAYER_SIZE

from . import interrupted_while_loading
from .config import DEFAULT_DURATION_S
from .exit_status import (
    EXIT_BAD_INPUT,
    EXIT_BROKEN_PIPE,
    EXIT_CONTROLLER,
    EXIT_DIVERGED,
    EXIT_INTERRUPTED,
    EXIT_TERMINATED,
    STOP_GRACE_S,
    exit_now,
)
from .mtn import MODES as MTN_MODES
from .options import (
    ArgumentParser,
    add_robots_options,
    add_world_options,
    camera_config,
    error_line,
    finite_float,
    path_text,
    robots_of,
    world_config,
)
from .placement import make_out_folder, place
from .robot import BACKENDS


def _run_match(args, robots) -> int:
    from .match import run_match
    from .viewer import LiveViewer

    if args.view_robot is not None and not 1 <= args.view_robot <= len(robots):
        raise ValueError(f"--view-robot {args.view_robot}: the match has robots 1 to {len(robots)}")
    viewer = LiveViewer((args.view_robot or 1) - 1) if args.view else None
    try:
        summary = run_match(
            robots,
            controller_path=args.controller,
            duration=args.duration,
            world=world_config(args),
            camera=camera_config(args),
            out=args.out,
            frame_listeners=[viewer] if viewer else (),
        )
    finally:
        if viewer is not None:
            viewer.close()
    frames, count = sum(robot["camera_frames"] for robot in summary["robots"]), len(summary["robots"])
    folders = "robot1" if count == 1 else f"robot1..{count}"
    print(
        f"ran a match of {count} robot{'s' * (count > 1)}: {summary['simulated_s']:.2f} s simulated in "
        f"{summary['wall_s']:.2f} s (real-time factor {summary['real_time_factor']:.1f}), {frames} camera frames "
        "written" + (f" to {args.out}/{folders}" if args.out else "")
    )
    return 0


def _run(args) -> int:
    from .runner import MEMORY_STICK, run_controller
    from .viewer import LiveViewer

    robots = robots_of(args, "run")
    if robots is None and args.controller is None:
        raise ValueError("run needs a CONTROLLER (or --robots FILE / --robot naming each robot's)")
    if args.view_robot is not None and (robots is None or not args.view):
        raise ValueError("--view-robot applies to --view in a match (--robots, --robot)")
    if robots is not None:
        return _run_match(args, robots)
    viewer = LiveViewer() if args.view else None
    try:
        summary = run_controller(
            args.controller,
            backend=args.backend,
            duration=args.duration,
            out=args.out,
            mtn_mode=args.mtn_mode,
            memory_stick=args.memory_stick,
            frame_listeners=[viewer] if viewer else (),
            world=world_config(args),
            camera=camera_config(args),
        )
    finally:
        if viewer is not None:
            viewer.close()
    path = Path(summary.controller)
    name = path.name if path.name.upper() != "MS" else f"{path.parent.name}/{path.name}"  # a program's MS folder
    what = (
        f"memory stick {name} on the host OPEN-R runtime"
        if summary.backend == MEMORY_STICK
        else f"{name} on the {summary.backend} backend"
    )
    print(
        f"ran {what}: {summary.simulated_s:.2f} s simulated "
        f"in {summary.wall_s:.2f} s (real-time factor {summary.real_time_factor:.1f}), "
        f"{summary.camera_frames} camera frames written" + (f" to {args.out}" if args.out else "")
    )
    if summary.simulated_s < args.duration - 1e-6:  # not an error: said, as a forgotten robot_run goes unseen
        ended, why = (
            ("its objects shut the robot down", "")
            if summary.backend == MEMORY_STICK
            else ("the controller ended", " (a controller steps with robot_step, or with robot_run's function)")
        )
        print(
            f"aibo-sim: note: {ended} at t = {summary.simulated_s:.3f} s, before --duration {args.duration:g} s{why}",
            file=sys.stderr,
        )
    return 0


def _render(args) -> int:
    from .dump.formats import frame_metadata
    from .files import png, write_files_atomic
    from .render import Renderer

    if args.settle < 0:
        raise ValueError(f"--settle must be at least 0 seconds, not {args.settle}")
    out = Path(args.out)
    sim = _settled_simulation(args, args.camera_profile)
    try:
        camera_frame = sim.camera.frame()
        images = {"head_camera.png": camera_frame.rgb}
        # The picture's camera as run.json and a dump's meta.json record it (profile, lens, settings)
        # and its frame as frames.jsonl does (camera pose, joints, the ball's pixel).
        description = {"camera": sim.camera.describe(), "frame": frame_metadata(sim, camera_frame.index)}
        third = Renderer(sim.model, 640, 480, quality="high")
        try:
            images["tracking.png"] = third.render(sim.camera.exposure_data(), "tracking")  # the same instant
        finally:
            third.close()
    finally:
        sim.close()
    if args.side_by_side is not None:
        images["side_by_side.png"] = _side_by_side(args)
    folder = make_out_folder(out)  # resolved: --out may be a link, or lie under one
    files = {folder / name: png(np.ascontiguousarray(rgb[:, :, ::-1])) for name, rgb in images.items()}
    files[folder / "head_camera.json"] = (json.dumps(description, indent=2) + "\n").encode()
    write_files_atomic(files)  # all of them or, on a full disk, none: an earlier set stays whole
    for name, rgb in images.items():
        print(f"wrote {out / name} ({rgb.shape[1]}x{rgb.shape[0]})")
    print(f"wrote {out / 'head_camera.json'} (the head camera's lens, settings and pose)")
    return 0


def _settled_simulation(args, profile: str):
    """The render command's simulation: its world, camera options (with ``profile``), settled."""
    from .sim import FRAME_MS, Simulation

    world = world_config(args)
    sim = Simulation(  # an unknown --keyframe is a ValueError listing the scene's
        world.scene,
        seed=world.seed,
        keyframe=args.keyframe,
        ball_type=world.ball_type,
        camera=dataclasses.replace(camera_config(args), profile=profile),
    )
    try:
        place(sim, world.pose, world.ball)
        frames = int(args.settle * 1000 / FRAME_MS + 0.5)  # half a frame up: 0.5 s is 63 frames, its 30 fps frame 15
        if frames:
            sim.step_frames(frames)
    except BaseException:
        sim.close()
        raise
    return sim


def _side_by_side(args) -> np.ndarray:
    """[a real ERS-7 frame |] the ers7 profile's picture | the ideal one, each shown at 416x320."""
    import cv2

    import openr_bridge

    from .files import decode_image

    pictures = []
    if args.side_by_side:  # a real frame as Tekkotsu's EasyTrain stores it: R, G, B = Y, Cb, Cr
        if not Path(args.side_by_side).is_file():
            what = "not a regular file" if Path(args.side_by_side).exists() else "no such file"
            raise FileNotFoundError(f"--side-by-side {args.side_by_side}: {what}")
        try:
            data = Path(args.side_by_side).read_bytes()
        except OSError as exc:
            raise OSError(f"--side-by-side {args.side_by_side}: cannot read: {exc.strerror or exc}") from None
        real = decode_image(data, cv2.IMREAD_UNCHANGED)
        sizes = (*LAYER_SIZE[:3], (FULL_WIDTH, FULL_HEIGHT))  # layers H, M, L; the full picture
        found = None if real is None else (real.shape[1], real.shape[0], real.shape[2] if real.ndim == 3 else 1)
        if found is None or found[:2] not in sizes or found[2] not in (3, 4):
            raise ValueError(
                f"--side-by-side {args.side_by_side}: not an EasyTrain frame ("
                + ("unreadable" if found is None else "{}x{}, {} channel(s)".format(*found))
                + f"): a colour PNG (R, G, B = Y, Cb, Cr) of {', '.join(f'{w}x{h}' for w, h in sizes)}"
            )
        cr, cb, y = cv2.split(decode_image(data, cv2.IMREAD_COLOR))
        pictures.append(openr_bridge.ycrcb_to_rgb(y, cr, cb))  # as the wrapper's camera_get_image shows it
    for profile in ("ers7", "ideal"):
        sim = _settled_simulation(args, profile)
        try:
            pictures.append(sim.camera.frame().rgb)
        finally:
            sim.close()
    return np.hstack([cv2.resize(p, (FULL_WIDTH, FULL_HEIGHT), interpolation=cv2.INTER_NEAREST) for p in pictures])


def _build_ms(args) -> int:
    from .openr.build_ms import build_ms

    out = build_ms(args.controller, args.out)
    print(
        f"wrote the memory-stick project {out}: build it for the simulator with\n"
        f"  make -C {out} OPENRSDK_ROOT=$(aibo-sim openr sdk) install\n"
        f"then run it with: aibo-sim run {out / 'MS'}\n"
        f"(for the robot: make -C {out} install with Sony's OPEN-R SDK in /usr/local/OPEN_R_SDK)"
    )
    return 0


def _openr_sdk(args) -> int:
    from .openr.sdk import sdk_root

    print(sdk_root())
    return 0


def _motion_file(name: str) -> Path:
    """A motion file path, or the name of a bundled motion (WALKFWD.MTN ...)."""
    from .robot import find_file
    from .sim import models_dir

    return find_file(name, [Path("."), models_dir() / "motions"])


def _read_motion(name: str):
    """The motion ``name`` names: an MTN file, a bundled motion's name, or ``ARCHIVE.ODA:MOTION``,
    a motion in one of Sony's ODA archives (an archive alone: an error listing its motions)."""
    from .mtn import MAGIC, ODA_MAGIC, MtnError, read_mtn, read_oda_motion
    from .sim import models_dir

    path = _motion_file(name)
    archive, _, motion = name.rpartition(":")
    if not (path.exists() or path.is_symlink()):
        if archive and _motion_file(archive).exists():
            return read_oda_motion(_motion_file(archive), motion)
        if archive:
            raise FileNotFoundError(f"{archive}: no such ODA archive (in {name!r})")
        bundled = ", ".join(sorted(p.name for p in (models_dir() / "motions").glob("*.MTN")))
        raise FileNotFoundError(f"{name}: no such motion file, nor a bundled motion ({bundled})")
    try:
        return read_mtn(path)
    except MtnError as error:
        if error.offset != 0 or not path.is_file():
            raise
        with path.open("rb") as file:
            magic = file.read(4)
        if magic == ODA_MAGIC:
            return read_oda_motion(path, None)  # raises, naming the archive's motions
        if len(magic) < len(MAGIC):
            raise
        why = f"wrong magic {magic!r}: neither an MTN motion ({MAGIC!r}) nor an ODA archive ({ODA_MAGIC!r})"
        raise MtnError(error.source, 0, why) from None


def _mtn_info(args) -> int:
    from .mtn import format_motion_info, motion_info

    info = motion_info(_read_motion(args.file))
    print(json.dumps(info, indent=2) if args.json else format_motion_info(info))
    return 0


def _mtn_play(args) -> int:
    from .motions import play_motion

    if args.no_ball and args.ball is not None:
        raise ValueError("--ball and --no-ball exclude each other")
    result = play_motion(
        _read_motion(args.file),
        repeat=args.repeat,
        mode=args.mode,
        world=world_config(args),
        camera=camera_config(args),
    )
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        dx, dy = result["displacement_m"]
        x, y, yaw = result["end_pose"]
        share = result["paw_stance_share"]
        paw_share = "no stance (never touched the ground)" if share is None else f"{100 * share:.0f} % of the stance"
        print(
            f"displacement {dx:+.3f} m forward, {dy:+.3f} m left ({result['distance_m']:.3f} m), "
            f"heading {result['heading_change_deg']:+.1f} deg, {'FELL' if result['fell'] else 'did not fall'}, "
            f"{result['duration_s']:.2f} s; ended at x {x:+.3f} m, y {y:+.3f} m, yaw {yaw:+.1f} deg; "
            f"kinematic distance {result['kinematic_distance_m']:+.3f} m; peak leg joint speed "
            f"{result['peak_leg_joint_speed_rad_s']:.1f} rad/s; paws carry {paw_share}; "
            f"from the {result['start_keyframe']} keyframe"
        )
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = ArgumentParser(
        prog="aibo-sim",
        description="Sony Aibo ERS-7 simulator: run controllers, render the camera, inspect and play MTN files, "
        "dump camera frames.",
    )
    commands = parser.add_subparsers(dest="command", required=True)

    run = commands.add_parser("run", help="run a controller headless")
    run.add_argument(
        "controller",
        type=path_text,
        nargs="?",
        help="controller (Webots-era Aibo API): a Python file, or a C or C++ file or folder (compiled with "
        "the system compiler); or a memory stick folder (OPEN-R/MW/CONF/OBJECT.CFG: its OPEN-R objects "
        "run on the host runtime). In a match, the controller of the robots that name none",
    )
    add_robots_options(run)
    run.add_argument("--backend", choices=BACKENDS, help="the controller's robot side: sim (default) or openr")
    run.add_argument(
        "--duration",
        type=finite_float,
        default=DEFAULT_DURATION_S,
        help=f"simulated seconds (default {DEFAULT_DURATION_S:g})",
    )
    run.add_argument("--out", type=path_text, help="folder for camera frames, the controller's files and run.json")
    run.add_argument(
        "--mtn-mode",
        choices=MTN_MODES,
        help="MTN playback: OPEN-R interpolation (default openr) or Webots keyframe stepping",
    )
    run.add_argument(
        "--memory-stick", type=path_text, metavar="DIR", help="OPEN-R memory stick folder for the openr backend"
    )
    run.add_argument(
        "--view",
        action="store_true",
        help="watch it in MuJoCo's viewer, in real time (needs a display; space pauses, right arrow steps)",
    )
    run.add_argument(
        "--view-robot",
        type=int,
        metavar="N",
        help="in a match, the robot --view follows and whose camera it shows (default 1)",
    )
    add_world_options(run)
    run.set_defaults(handler=_run)

    render = commands.add_parser("render", help="render the head camera and a third-person view")
    render.add_argument("--keyframe", default="stand", help="the scene's keyframe to start from (default stand)")
    render.add_argument("--settle", type=finite_float, default=0.5, help="seconds to simulate first (default 0.5)")
    render.add_argument(
        "--out",
        type=path_text,
        default="renders",
        help="folder for head_camera.png, head_camera.json (its lens, settings, pose) and tracking.png",
    )
    render.add_argument(
        "--side-by-side",
        nargs="?",
        const="",
        metavar="EASYTRAIN_PNG",
        help="also write side_by_side.png: the ers7 and ideal pictures of the view, after a real "
        "ERS-7 frame when one is given (Tekkotsu EasyTrain PNG, R, G, B = Y, Cb, Cr)",
    )
    add_world_options(render)
    render.set_defaults(handler=_render)

    mtn = commands.add_parser("mtn", help="OPEN-R motion files").add_subparsers(dest="mtn_command", required=True)
    info = mtn.add_parser("info", help="print a file's name, creator, design, frames, length, locators")
    info.add_argument(
        "file",
        type=path_text,
        help="an MTN file, the name of a bundled motion (WALKFWD.MTN, TURNL.MTN, ...), or ARCHIVE.ODA:MOTION, a "
        "motion in one of Sony's ODA archives (an archive alone lists its motions)",
    )
    info.add_argument("--json", action="store_true")
    info.set_defaults(handler=_mtn_info)
    play = mtn.add_parser(
        "play",
        help="play a file on the robot and report how it moved",
        description="Play a motion on the robot, standing (sitting for a motion whose name says it starts "
        "sitting, as Sony's a_sit#...) and report how it moved. It takes "
        "the options of every aibo-sim command; it renders no camera frame and reads no "
        "noisy sensor, so --seed and the camera options leave its report unchanged.",
    )
    play.add_argument("file", type=path_text, help="an MTN file, the name of a bundled motion, or ARCHIVE.ODA:MOTION")
    play.add_argument("--repeat", type=int, default=1)
    play.add_argument(
        "--mtn-mode",
        "--mode",
        dest="mode",
        choices=MTN_MODES,
        default="openr",
        help="how the motion plays, as run's --mtn-mode (--mode: its earlier name)",
    )
    play.add_argument("--json", action="store_true")
    play.add_argument(
        "--no-ball", action="store_true", help="no ball in the scene: the default, unless --ball places one"
    )
    add_world_options(play, ball_default="no ball")  # the camera options too: one option set for every command
    play.set_defaults(handler=_mtn_play)

    openr = commands.add_parser("openr", help="real OPEN-R programs: the host OPEN-R SDK").add_subparsers(
        dest="openr_command", required=True
    )
    sdk = openr.add_parser(
        "sdk",
        help="print the host OPEN-R SDK's folder (made on first use), for Sony's Makefiles: "
        "make OPENRSDK_ROOT=$(aibo-sim openr sdk) install",
    )
    sdk.set_defaults(handler=_openr_sdk)
    build_ms = commands.add_parser(
        "build-ms",
        help="write a memory-stick project for a C or C++ controller: the "
        "controller with the Webots OPEN-R wrapper object",
    )
    build_ms.add_argument("controller", type=path_text, help="a .c, .cc or .cpp controller, or a folder of them")
    build_ms.add_argument("--out", type=path_text, required=True, help="the project's folder (new or empty)")
    build_ms.set_defaults(handler=_build_ms)

    from .dump import add_dump_parser

    add_dump_parser(commands)
    return parser


# The same signal again within this is the one stop, sent twice: `timeout` and `kill -- -PGID`
# send it to the process and to its process group.
DUPLICATE_SIGNAL_S = 0.25


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread so that a command stops as after Ctrl-C: a run's
    ``robot_die`` functions run and its run.json says so, a dump's writers abort (temporary
    files removed, locks released) and its workers stop. A KeyboardInterrupt, so that no
    ``except Exception`` (a controller's own) swallows it."""


class _SignalsStopCleanly:
    """While a command runs in the main thread, Ctrl-C raises KeyboardInterrupt and SIGTERM
    ``Terminated``. A command still running ``STOP_GRACE_S`` after the first (a controller that
    catches it and goes on), or a second signal (not the first's duplicate: ``DUPLICATE_SIGNAL_S``),
    ends the process at once with the signal's status."""

    def __init__(self):
        self._deadline: threading.Timer | None = None
        self._previous: dict[int, object] = {}
        self._first = (0, 0.0)  # the first signal's number and time.monotonic()

    @property
    def received(self) -> int:
        """The first signal received (0: none): what ended the command, where a library re-raised
        its exception as a bare KeyboardInterrupt (Ray's ``get`` does)."""
        return self._first[0]

    def __enter__(self) -> _SignalsStopCleanly:
        if threading.current_thread() is threading.main_thread():
            self._previous[signal.SIGTERM] = signal.signal(signal.SIGTERM, self._raise)
            if signal.getsignal(signal.SIGINT) is signal.default_int_handler:  # not where Ctrl-C is ignored
                self._previous[signal.SIGINT] = signal.signal(signal.SIGINT, self._raise)
        return self

    def __exit__(self, *exc_info) -> None:
        if self._deadline is not None:
            self._deadline.cancel()
        for number, handler in self._previous.items():
            signal.signal(number, handler)

    def _raise(self, number, frame):
        terminated = number == signal.SIGTERM
        status, name = (EXIT_TERMINATED, "terminated (SIGTERM)") if terminated else (EXIT_INTERRUPTED, "interrupted")
        if self._deadline is not None:
            if self._first[0] == number and time.monotonic() - self._first[1] < DUPLICATE_SIGNAL_S:
                return  # the first one, sent to the process and to its group
            _stop_now(status, f"{name} again: stopped at once")
        self._first = (number, time.monotonic())
        self._deadline = threading.Timer(
            STOP_GRACE_S, _stop_now, (status, f"{name}, and still running {STOP_GRACE_S:g} s later: stopped at once")
        )
        self._deadline.daemon = True
        self._deadline.start()
        raise Terminated() if terminated else KeyboardInterrupt()


def _stop_now(status: int, why: str) -> None:
    print(f"\naibo-sim: {why} (files being written may be left as they were)", file=sys.stderr, flush=True)
    exit_now(status)


def _reader_gone(stream) -> bool:
    """Whether ``stream`` is a pipe whose reading end is closed (poll reports an error on it)."""
    try:
        poller = select.poll()
        poller.register(stream.fileno(), select.POLLOUT)
        return any(event & select.POLLERR for _, event in poller.poll(0))
    except (OSError, ValueError):  # no file descriptor (a test's StringIO)
        return False


def main(argv: list[str] | None = None) -> int:
    if signal.getsignal(signal.SIGINT) is interrupted_while_loading:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    try:  # the modules a command needs load here: Ctrl-C while they load is an interruption too
        from openr_bridge import OpenRError

        from .cbind import CompileError
        from .mtn import MtnError
        from .render import RenderingUnavailable
        from .robot import DeviceError
        from .runner import ControllerFailed, interrupt_behind
        from .sim import ModelError, SimulationDiverged
        from .viewer import ViewerUnavailable
    except KeyboardInterrupt:
        print("\naibo-sim: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED

    # Exit status: 0 done, else one of exit_status's.
    for stream in (sys.stdout, sys.stderr):  # text a terminal's encoding lacks (a motion's latin-1 name) escaped
        if isinstance(stream, io.TextIOWrapper):
            stream.reconfigure(errors="backslashreplace")
    try:
        args = build_parser().parse_args(argv)
    except KeyboardInterrupt:  # Ctrl-C while the arguments are read
        print("\naibo-sim: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    signals = _SignalsStopCleanly()
    try:
        with signals:
            return args.handler(args)
    except ControllerFailed as exc:
        print(f"aibo-sim: {exc}", file=sys.stderr)
        return EXIT_CONTROLLER
    except SimulationDiverged as exc:
        print(f"aibo-sim: error: {error_line(exc)}", file=sys.stderr)
        return EXIT_DIVERGED
    except BrokenPipeError as exc:
        if _reader_gone(sys.stdout):  # stop quietly, as a process that SIGPIPE ends
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return EXIT_BROKEN_PIPE
        print(f"aibo-sim: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except (
        ModelError,
        MtnError,
        OpenRError,
        DeviceError,
        RenderingUnavailable,
        ViewerUnavailable,
        CompileError,
        OSError,
        ValueError,
    ) as exc:
        if isinstance(exc, OSError) and exc.filename is not None:
            exc = f"{exc.filename}: {exc.strerror or exc}"
        print(f"aibo-sim: error: {error_line(exc)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except SystemError as exc:
        interrupt = interrupt_behind(exc)
        if interrupt is None:
            raise
        return _interrupted(interrupt, args.command, signals.received)
    except KeyboardInterrupt as exc:
        return _interrupted(exc, args.command, signals.received)


def _interrupted(interrupt: KeyboardInterrupt, command: str, received: int) -> int:
    """Say that Ctrl-C (130, as a shell reports a process ended by SIGINT: 128 + 2) or SIGTERM (143)
    ended the command (``received``: the signal, where the exception no longer says); the exit status."""
    hint = " (the dump can continue with --resume)" if command == "dump" else ""
    if isinstance(interrupt, Terminated) or received == signal.SIGTERM:
        print(f"aibo-sim: terminated (SIGTERM){hint}", file=sys.stderr)
        return EXIT_TERMINATED
    print(f"\naibo-sim: interrupted{hint}", file=sys.stderr)
    return EXIT_INTERRUPTED


def program() -> int:
    """The ``aibo-sim`` program: ``main``, then the exit with its status, not waiting for threads
    that still run a controller's code (Python waits for every thread that is not a daemon: one a
    controller started and never ends, or a match's robot stuck in its controller after a signal,
    would hold the command for ever; a run of Webots ends its controllers' processes)."""
    status = main()
    left = [repr(t.name) for t in threading.enumerate() if t is not threading.main_thread() and not t.daemon]
    if not left:
        return status
    print(f"aibo-sim: the run is over; not waiting for threads still running: {', '.join(left)}", file=sys.stderr)
    sys.stdout.flush()
    sys.stderr.flush()
    exit_now(status)


if __name__ == "__main__":
    sys.exit(program())
