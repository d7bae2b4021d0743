"""Runs a controller file headless, as Webots would, on either backend."""

from __future__ import annotations

import contextlib
import json
import math
import os
import re
import runpy
import sys
import threading
import time
import traceback
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

import openr_bridge
from openr_bridge.config import find_in_stick
from openr_bridge.memory_stick import MemoryStick, load_memory_stick, memory_stick_folder

from . import controller
from .cbind import (
    C_SUFFIXES,
    CControllerError,
    compile_controller,
    controller_sources,
    is_c_controller,
    run_c_controller,
    serve,
)
from .config import DEFAULT_DURATION_S, CameraConfig, ParameterError, WorldConfig, configs
from .field import DEFAULT_BALL_TYPE
from .files import (
    FolderLock,
    SymlinkRefused,
    check_atomic_write,
    list_folder,
    make_folder,
    png,
    read_file,
    write_file_atomic,
)
from .openr.host import PICTURE_SIZE, MemoryStickRun, OpenRObjectCrashed
from .placement import make_out_folder, out_path, place
from .render import RenderingUnavailable, check_rendering
from .robot import Robot, SimulationEnd
from .sim import FRAME_MS, Simulation, SimulationDiverged, models_dir


def interrupt_behind(error: Exception) -> KeyboardInterrupt | None:
    """The Ctrl-C or SIGTERM (``cli.Terminated``) that ``error`` stands for: a signal's exception
    raised while a compiled function returns (numba's, a C extension's) reaches the caller as
    the cause of a SystemError ("returned a result with an exception set"), or of a chain of
    them (a compiled function inside another)."""
    while isinstance(error, SystemError):
        error = error.__cause__
    return error if isinstance(error, KeyboardInterrupt) else None


class ControllerFailed(RuntimeError):
    """The controller raised; the message carries the simulated time and the traceback.
    ``exit_status``: the status it passed to ``sys.exit`` when that ended it, else None."""

    def __init__(self, message: str, exit_status=None):
        super().__init__(message)
        self.exit_status = exit_status


@dataclass
class RunSummary:
    """What ``run_controller`` returns and ``run.json`` records of a run that ended normally."""

    controller: str
    backend: str
    simulated_s: float
    wall_s: float
    real_time_factor: float
    camera_frames: int
    robot_pose: tuple[float, float, float]  # at the end, as --pose takes it: x, y in metres, yaw in degrees
    ball_xy: tuple[float, float] | None  # at the end; None in a scene without a ball
    # What the run started from, as given (run.json records these too): the options
    # ``--scene`` (resolved path; None: the RoboCup field), ``--seed``, ``--pose`` (x, y in
    # metres, yaw in degrees; None: the scene's start) and ``--ball`` (None: the scene's).
    scene: str | None = None
    seed: int = 0
    pose: tuple[float, float, float] | None = None
    ball: tuple[float, float] | None = None
    ball_type: str = DEFAULT_BALL_TYPE
    camera: dict = field(default_factory=dict)  # ``HeadCamera.describe()`` at the start: profile, lens, settings


def motion_dirs(controller_path: Path, working_folder: bool = True) -> tuple[Path, ...]:
    """Where ``mtn_new`` looks for relative names: the controller's folder, the working folder
    (``Path(".")``: ``--out``, where the controller's own files land; a memory stick's build
    leaves it out), then the bundled motions."""
    folders = [controller_path.resolve().parent, models_dir() / "motions"]
    if working_folder:
        folders.insert(1, Path("."))
    return tuple(folders)


RUN_FILE = "run.json"
CONSOLE_FILE, SOUND_FILE = "console.log", "speaker.wav"  # a memory stick's console and speaker, in --out
MEMORY_STICK = "memory stick"  # run.json's "backend" of a memory stick's run: its objects are the robot side
LOCK_FILE = ".run.lock"  # flock()ed while a run writes its folder (``files.FolderLock``): one run per folder
FRAME_FILE = re.compile(r"\d{6,}\.png")  # a run's frame, frames/NNNNNN.png
# What a run's frames/ may hold: its frames, their temporary names (".NNNNNN.png.tmp": no
# "*.png" pattern matches them) and the temporary names of earlier versions ("NNNNNN.partial.png").
RUN_FRAME_NAMES = re.compile(rf"{FRAME_FILE.pattern}|\.\d{{6,}}\.png\.tmp|\d{{6,}}\.partial\.png")


def _unfinished_stick(folder: Path) -> str | None:
    """Why a folder with an OPEN-R folder (any case; or its MS with one) is no memory stick: where
    OPEN-R/MW/CONF/OBJECT.CFG is missing, or None."""
    for candidate in (folder, folder / "MS"):
        with contextlib.suppress(OSError):
            if any(entry.name.upper() == "OPEN-R" for entry in candidate.iterdir()):
                try:
                    find_in_stick(candidate, "OBJECT.CFG")
                except openr_bridge.ConfigError as error:
                    return str(error)
    return None


def check_python_controller(path: Path) -> None:
    """A Python controller file that exists and compiles: FileNotFoundError, or ValueError naming
    the file and line of a syntax error (bad input, found before anything is run or written)."""
    if not path.is_file():
        main_files = " or ".join(path.name + suffix for suffix in C_SUFFIXES)
        stick = next(filter(None, map(memory_stick_folder, path.resolve().parents)), None) if path.is_dir() else None
        unfinished = _unfinished_stick(path) if path.is_dir() else None
        what = (
            f"a folder inside the memory stick {stick}: run the stick's folder"
            if stick is not None
            else f"a memory stick without its OBJECT.CFG ({unfinished})"
            if unfinished is not None
            else f"a folder with no {main_files} (a C or C++ controller folder holds its main file under the "
            "folder's name) and no memory stick (MS/OPEN-R/MW/CONF/OBJECT.CFG)"
            if path.is_dir()
            else "not a regular file"
            if path.exists()
            else "no such controller file"
        )
        raise FileNotFoundError(f"{path}: {what}")
    try:
        compile(path.read_bytes(), str(path), "exec")
    except SyntaxError as exc:  # IndentationError too
        code = f" ({exc.text.strip()!r})" if exc.text and exc.text.strip() else ""
        line = "" if exc.lineno is None else f", line {exc.lineno}"  # none for a null byte: not Python text
        raise ValueError(f"{path}{line}: {type(exc).__name__}: {exc.msg}{code}") from None


def earlier_run(out: Path) -> dict | None:
    """``out``'s run.json of an earlier run (of one robot, or a match's: ``"match": true``); None
    when there is none; OSError when it is not an aibo-sim run's (refused, never replaced)."""
    run_json = out / RUN_FILE
    if not (run_json.exists() or run_json.is_symlink()):
        return None
    try:
        previous = json.loads(read_file(run_json))
    except SymlinkRefused:
        raise
    except (OSError, ValueError):
        previous = None
    if isinstance(previous, dict) and (previous.get("match") is True or {"controller", "backend"} <= previous.keys()):
        return previous
    raise OSError(f"{run_json} is not an aibo-sim run's run.json: refusing to replace it; choose another --out")


class FrameWriter:
    """Writes each camera frame the controller's camera captured as ``frames/NNNNNN.png``
    in ``run --out``, atomically (see ``write_file_atomic``), and ``run.json``.

    One run per folder: ``out`` may be new, hold no ``frames/`` and no ``run.json`` (the
    controller's files go there too), or hold an earlier aibo-sim run, whose ``frames/``
    files and ``run.json`` are then removed first (the controller's own files are left: it
    rewrites them). Anything else is refused with an OSError (exit status 2), nothing
    changed: a folder another run is writing (``.run.lock``, held as a dump holds its lock,
    until ``lock.release()``), a ``run.json`` that is not aibo-sim's, a non-empty ``frames/``
    beside no ``run.json``, a ``frames/`` holding files that are not a run's frames, a link in
    place of ``frames/`` or ``run.json`` (``files.SymlinkRefused``). ``run.json`` is written at
    the start with ``"status": "incomplete"`` and replaced by the summary at the end
    (``"status": "done"``; ``"failed"`` with the error and the simulated time when the
    controller failed or the physics diverged), so that a killed run's folder is still recognised.

    A write that fails (a full disk) ends the run: the error is kept and ``check`` raises it
    after the run, as the OSError naming the file rather than as the controller's exception;
    ``run.json`` then says ``"failed"`` with that error, where the disk still takes it.
    """

    def __init__(
        self, directory: Path, controller: Path | None = None, backend: str | None = None, prepare: bool = True
    ):
        """``prepare=False``: the folder checked and locked only; ``prepare()`` then clears it
        (a match checks every robot's folder before it changes any)."""
        self.out = make_out_folder(directory)
        self.directory = self.out / "frames"
        self.error: OSError | None = None
        self._written = 0
        self._marker = {"controller": controller and str(controller), "backend": backend, "status": "incomplete"}
        self._check()  # before the lock file is made: a folder refused is left as it was
        self.lock = FolderLock(self.out, LOCK_FILE, "run", "wait for it to end or stop it, or choose another --out")
        if prepare:
            self.prepare()

    def prepare(self) -> None:
        """Remove an earlier run's frames and write run.json saying "incomplete"; the lock is
        released if that fails."""
        try:
            self._prepare(self._marker)
        except BaseException:
            self.lock.release()
            raise

    def _check(self) -> list[Path]:
        """The earlier run's files to remove: its frames, and a memory stick's console and sound,
        which this run may not write; OSError when the folder is not one to reuse."""
        from .dump.writing import LOCK_NAME, META  # a dump's (its package imports this module)

        dump_files = [name for name in (META, LOCK_NAME) if os.path.lexists(self.out / name)]
        if dump_files:  # a dump's folder, or one a dump is writing (its lock is not this run's)
            raise OSError(
                f"{self.out} holds a dump ({dump_files[0]}): a run would mix its frames with the dump's; "
                "choose another --out"
            )
        frames = self.directory
        if frames.is_symlink():
            raise SymlinkRefused.at(frames)
        previous = earlier_run(self.out)
        if previous is not None and previous.get("match") is True:
            raise OSError(
                f"{self.out} holds a match's {RUN_FILE} and robot folders: a run of one robot would leave "
                "them beside its frames; choose another --out"
            )
        try:
            names = os.listdir(frames)
        except FileNotFoundError:
            names = []
        except OSError as exc:
            raise OSError(f"cannot use {frames} for the frames: {exc.strerror or exc}") from exc
        if names and previous is None:
            raise OSError(
                f"{frames} holds files but {self.out} holds no aibo-sim run ({RUN_FILE}): refusing to mix "
                "them with this run's frames; choose another --out"
            )
        foreign = sorted(name for name in names if not RUN_FRAME_NAMES.fullmatch(name))
        if foreign:
            raise OSError(
                f"{frames} holds files that are not a run's frames ({foreign[0]!r}"
                f"{f' and {len(foreign) - 1} more' if len(foreign) > 1 else ''}): refusing to remove them; "
                "choose another --out"
            )
        check_atomic_write(self.out / RUN_FILE)
        own = [self.out / CONSOLE_FILE, self.out / SOUND_FILE] if previous is not None else []
        return [frames / name for name in names] + own

    def _prepare(self, marker: dict) -> None:
        """run.json saying "incomplete" first: a run refused there leaves the earlier one whole."""
        frames = self.directory
        earlier = self._check()  # checked again under the lock
        self.write_run_json(marker)
        for path in earlier:
            try:
                path.unlink()
            except FileNotFoundError:
                pass
            except OSError as exc:
                raise OSError(f"cannot remove the earlier run's {path}: {exc.strerror or exc}") from exc
        try:
            make_folder(frames)
        except SymlinkRefused:
            raise
        except OSError as exc:
            raise OSError(f"cannot create {frames}: {exc.strerror or exc}") from exc

    def write_run_json(self, content: dict) -> None:
        """Replace ``run.json`` in ``--out`` with ``content``, atomically."""
        write_file_atomic(self.out / RUN_FILE, (json.dumps(content, indent=2) + "\n").encode())

    def __call__(self, index: int, rgb: np.ndarray) -> None:
        if self.error is not None:
            raise SimulationEnd()
        path = self.directory / f"{index:06d}.png"
        try:
            write_file_atomic(path, png(np.ascontiguousarray(rgb[:, :, ::-1])))
        except OSError as exc:
            self.error = exc
            raise SimulationEnd() from exc  # raised in the controller's call: ends the run
        self._written += 1

    @property
    def count(self) -> int:
        """The frames written, counted in the folder: a signal (SIGTERM, Ctrl-C) that ends the run
        between a frame's rename and a counter's increment cannot make run.json disagree with it.
        The frames this writer wrote where the folder cannot be reached (a link now in its place)."""
        try:
            return sum(1 for name in list_folder(self.directory) if FRAME_FILE.fullmatch(name))
        except OSError:
            return self._written

    def check(self) -> None:
        """Raise the write error that ended the run, if one did."""
        if self.error is not None:
            raise self.error


# Where the frames that call a controller, and that its API calls raise from, live.
_SIMULATOR_CODE = (
    *(str(Path(package.__file__).resolve().parent) + os.sep for package in (controller, openr_bridge)),
    runpy.__file__,
    "<frozen runpy>",
    threading.__file__,
)


def controller_traceback(error: BaseException) -> str:
    """``error``'s traceback as the controller's author needs it: their own frames, without the
    simulator's and runpy's around them (an API call's error names what was wrong); chained
    exceptions raised inside the simulator alone are left out."""

    def controllers(exc: traceback.TracebackException) -> list[traceback.FrameSummary]:
        return [frame for frame in exc.stack if not frame.filename.startswith(_SIMULATOR_CODE)]

    def own(exc: traceback.TracebackException) -> traceback.TracebackException:
        exc.stack = traceback.StackSummary.from_list(controllers(exc) or exc.stack)
        for link in ("__cause__", "__context__"):
            chained = getattr(exc, link)
            if chained is not None:
                setattr(exc, link, own(chained) if controllers(chained) else None)
        return exc

    return "".join(own(traceback.TracebackException.from_exception(error)).format())


@contextlib.contextmanager
def _controller_context(controller_dir: Path, workdir: Path | None):
    """Modules beside the controller import; its files land in ``workdir`` (when given)."""
    previous = Path.cwd()
    sys.path.insert(0, str(controller_dir))
    if workdir is not None:
        os.chdir(workdir)
    try:
        yield
    finally:
        os.chdir(previous)
        sys.path.remove(str(controller_dir))


class _ControllerThreads:
    """While a controller runs: the first exception that a thread raises (one the controller
    started) is kept with the thread's name and the simulated time (``error``), for the run to
    end as failed, not printed as threading's hook would; later ones go to that hook. A thread
    that steps past the run's end (SimulationEnd) ends quietly."""

    def __init__(self, robot: Robot, inert: bool = False):
        self._robot, self.error, self._inert = robot, None, inert

    def __enter__(self) -> _ControllerThreads:
        if not self._inert:  # a match's controllers share threading's hook: it stays
            self._previous, threading.excepthook = threading.excepthook, self._hook
        return self

    def __exit__(self, *exc_info) -> None:
        if not self._inert:
            threading.excepthook = self._previous

    def _hook(self, args) -> None:
        if issubclass(args.exc_type, SimulationEnd):
            return
        if self.error is None and args.exc_value is not None:
            self.error = (args.thread.name if args.thread is not None else "?", args.exc_value, self._robot.time_ms)
            return
        self._previous(args)


class _WaitNotices:
    """While a Python controller runs, a thread that prints the line ``serve.announce_wait``
    prints for a C controller after every ``serve.WAIT_NOTICE_S`` of wall time without an API
    call: a controller that computes for long, or never returns, is not taken for a simulator
    that hangs. None while an API call is under way (the first frames compile the camera's
    passes: the simulator's time, not the controller's). ``name``: the controller's, and in a
    match its robot's."""

    def __init__(self, path: Path, name: str, robot: Robot):
        self._name, self._robot, self._stop = name, robot, threading.Event()
        self._folder, self._controller_thread = str(path.parent) + os.sep, threading.get_ident()
        self._installed = controller.installed()
        self._thread = threading.Thread(target=self._watch, name="aibo-sim wait notices", daemon=True)

    def __enter__(self) -> _WaitNotices:
        self._thread.start()
        return self

    def __exit__(self, *exc_info) -> None:
        self._stop.set()
        self._thread.join()

    def _watch(self) -> None:
        seen, notices = None, 0
        while True:
            if self._installed.last_call_s != seen:
                seen, notices = self._installed.last_call_s, 0
            if self._stop.wait(max(0.0, seen + (notices + 1) * serve.WAIT_NOTICE_S - time.monotonic())):
                return
            if self._installed.last_call_s == seen and not self._in_api_call():
                notices += 1
                serve.announce_wait(self._name, notices * serve.WAIT_NOTICE_S, self._robot.time_ms)

    def _in_api_call(self) -> bool:
        """Whether the controller's thread runs the simulator's code called from the controller's
        (its innermost frame of the simulator's comes before its innermost of the controller's)."""
        frame = sys._current_frames().get(self._controller_thread)
        while frame is not None:
            name = frame.f_code.co_filename
            if name.startswith(_SIMULATOR_CODE[:2]):  # aibo_sim's and openr_bridge's
                return True
            if name.startswith(self._folder):
                return False
            frame = frame.f_back
        return False


class Progress:
    """A one-line progress bar on a terminal: simulated time, frames (when counted), the
    real-time factor and the time left, both from the progress since the first update;
    silent otherwise."""

    def __init__(self, duration_s: float, stream=None, enabled: bool = True):
        """``stream``: standard error (the one at the call, not at import) by default."""
        self.duration_s, self.stream = duration_s, stream or sys.stderr
        self.enabled = enabled and self.stream.isatty()
        self._last, self._origin = 0.0, None

    def __call__(self, robot: Robot) -> None:
        """Frame listener form of ``update``: the run's simulated time and camera frames."""
        self.update(robot.time_ms / 1000, robot.sim.camera_frame_index() + 1)

    def update(self, simulated_s: float, frames: int | None = None) -> None:
        """Redraw the bar (at most every 0.25 s) for ``simulated_s`` seconds and ``frames`` frames."""
        now = time.monotonic()
        if self._origin is None:
            self._origin = now, simulated_s
        if self.enabled and now - self._last > 0.25:
            self._last = now
            bar = "#" * int(30 * min(1.0, simulated_s / self.duration_s))
            factor = (simulated_s - self._origin[1]) / max(now - self._origin[0], 1e-9)
            left = f"{max(0.0, self.duration_s - simulated_s) / factor:.0f} s" if factor > 0 else "?"
            counted = f"{frames} frames, " if frames is not None else ""
            self.stream.write(
                f"\r[{bar:<30}] {counted}{simulated_s:.2f} / {self.duration_s:.2f} s, "
                f"{factor:.1f}x real time, {left} left\x1b[K"
            )  # erase the longer line before
            self.stream.flush()

    def close(self) -> None:
        """End the bar's line."""
        if self.enabled:
            self.stream.write("\n")


def run_controller(
    path: str | Path,
    *,
    world: WorldConfig | None = None,
    camera: CameraConfig | None = None,
    backend: str | None = None,
    duration: float = DEFAULT_DURATION_S,
    out: str | Path | None = None,
    mtn_mode: str | None = None,
    memory_stick=None,
    frame_listeners=(),
    progress: bool = True,
    workdir: str | Path | None = None,
) -> RunSummary:
    """Run a controller for ``duration`` simulated seconds; frames, its files and ``run.json``
    (the summary) go to ``out``. The controller is a Python file, a C or C++ file or folder
    (``aibo_sim.cbind``: compiled first, a CompileError when it does not compile), or a memory
    stick: a folder with ``OPEN-R/MW/CONF/OBJECT.CFG``, whose OPEN-R objects run on the host
    OPEN-R runtime (``aibo_sim.openr``: ``backend``, ``mtn_mode`` and ``memory_stick``, the
    Webots API's, do not apply; its console goes to ``out/console.log``, its sound to
    ``out/speaker.wav``).

    The run starts in ``world`` (``WorldConfig``: scene, seed, the robot's pose, the ball; default
    the RoboCup field as the scene has it) with the head camera ``camera`` (``CameraConfig``;
    default the ``ers7`` profile); run.json records both (``WorldConfig.from_dict`` and
    ``CameraConfig.from_dict`` read them back). ``frame_listeners`` are called with the
    robot (or the memory stick's run) after every 8 ms frame; ``progress=False`` silences the
    progress bar (worker processes). The controller runs in ``workdir`` (default ``out``; with
    neither, the current folder): its files land there.
    """
    path = Path(path).resolve()
    stick = _memory_stick(path, backend, mtn_mode, memory_stick)
    executable = None
    if stick is not None:
        path, backend = stick.root, MEMORY_STICK
    else:
        backend, mtn_mode = backend or "sim", mtn_mode or "openr"
        if is_c_controller(path):
            executable = compile_controller(path)
            path = controller_sources(path)[0]  # the main file: its folder holds the controller's motions
        else:
            check_python_controller(path)
    check_duration(duration)
    check_listeners(frame_listeners, "frame_listeners")
    world, camera = configs(world, camera)
    scene = world.scene
    sim = Simulation(scene, seed=world.seed, camera=camera, ball_type=world.ball_type)
    writer = None
    try:
        place(sim, world.pose, world.ball)
        check_rendering(sim.model)
        out = None if out is None else out_path(out)
        folder = Path(workdir).resolve() if workdir is not None else out
        if stick is None:
            program = Robot(
                sim, backend=backend, mtn_mode=mtn_mode, memory_stick=memory_stick, search_dirs=motion_dirs(path)
            )
            camera_listeners = program.camera_source.listeners
            # what it serves (the openr backend: layer H), and whether the sensor's full frame was asked for
            size = (program.camera_source.width, program.camera_source.height)
            described = {**sim.camera.describe(size), "full": camera.full}
        else:
            program = MemoryStickRun(
                sim,
                stick,
                folder or Path.cwd(),
                log_path=out and out / CONSOLE_FILE,
                sound_path=out and out / SOUND_FILE,
            )
            camera_listeners = program.camera_listeners
            described = {**sim.camera.describe(PICTURE_SIZE), "full": camera.full}
        if out is not None:
            writer = FrameWriter(out, controller=path, backend=backend)
    except BaseException:
        sim.close()
        if writer is not None:
            writer.lock.release()
        raise
    program.end_ms = int(round(duration * 1000))
    if writer is not None:
        camera_listeners.append(writer)
    program.frame_listeners.extend(frame_listeners)
    progress_bar = Progress(duration, enabled=progress)
    program.frame_listeners.append(progress_bar)
    start = time.perf_counter()

    def record_end(status: str, error: BaseException) -> None:
        """run.json of a run that did not reach its end: how it ended, the time and frames so far."""
        writer.write_run_json(
            {
                "controller": str(path),
                "backend": backend,
                "status": status,
                **({"error": str(error)} if status == "failed" else {}),
                "simulated_s": program.time_ms / 1000,
                "camera_frames": writer.count,
                "camera": described,
            }
        )

    try:
        if stick is None:
            _run_controller_program(path, executable, program, folder)
        else:
            _run_memory_stick(path, program)
        wall = time.perf_counter() - start
        if writer is not None and writer.error is not None:  # a frame that could not be written ended the run
            try:
                record_end("failed", writer.error)
            except OSError:
                pass  # the full disk refused this too: run.json still says "incomplete"
            writer.check()
        position, yaw, _ = sim.body_pose()
        ball_end = sim.ball_position()
        summary = RunSummary(
            str(path),
            backend,
            program.time_ms / 1000,
            wall,
            program.time_ms / 1000 / max(wall, 1e-9),
            writer.count if writer else 0,
            (float(position[0]), float(position[1]), math.degrees(yaw)),
            None if ball_end is None else (float(ball_end[0]), float(ball_end[1])),
            scene=None if scene is None else str(Path(scene).resolve()),
            seed=world.seed,
            pose=world.pose,
            ball=world.ball,
            ball_type=world.ball_type,
            camera=described,
        )
        if writer is not None:
            done = asdict(summary)
            writer.write_run_json(
                {"controller": done.pop("controller"), "backend": done.pop("backend"), "status": "done", **done}
            )
    except (
        ControllerFailed,
        SimulationDiverged,
        RenderingUnavailable,
        KeyboardInterrupt,
        OSError,
        openr_bridge.ConfigError,  # a connection the objects' services refuse, found as they start
    ) as failure:
        if writer is not None:  # the frames so far stay, and run.json says how the run ended
            with contextlib.suppress(OSError):  # a full disk may refuse this too: run.json says "incomplete"
                record_end("interrupted" if isinstance(failure, KeyboardInterrupt) else "failed", failure)
        raise
    finally:
        progress_bar.close()
        sim.close()
        if writer is not None:
            writer.lock.release()
    return summary


def check_listeners(listeners, what: str) -> None:
    """A TypeError naming ``what`` unless ``listeners`` is a sequence of callables (a listener
    that is none failed the run at its first call, as the controller's error)."""
    if isinstance(listeners, (str, bytes)) or not all(callable(listener) for listener in listeners):
        raise TypeError(f"{what} must be a sequence of callables, not {listeners!r}")


def check_duration(duration) -> None:
    """ValueError unless ``duration`` is a positive, finite number of seconds holding at least one
    8 ms joint frame (a run's, a match's, a dump's)."""
    if isinstance(duration, (str, bytes, bool)) or not isinstance(duration, (int, float, np.integer, np.floating)):
        raise ParameterError.at("duration", repr(duration), "must be a number of seconds")
    if not (math.isfinite(duration) and duration > 0):
        raise ParameterError.at("duration", duration, "must be positive and finite")
    if round(duration * 1000) < FRAME_MS:
        raise ParameterError.at(
            "duration", f"{duration} s", f"shorter than one {FRAME_MS} ms joint frame: nothing would run"
        )


def refuse_controller_options(folder: Path, backend: str | None, mtn_mode: str | None, memory_stick) -> None:
    """ValueError for a controller's option given with the memory stick ``folder``."""
    for option, value in (("--backend", backend), ("--mtn-mode", mtn_mode), ("--memory-stick", memory_stick)):
        if value not in (None, MEMORY_STICK if option == "--backend" else None):
            raise ValueError(
                f"{option} applies to controllers: {folder} is a memory stick, whose OPEN-R objects run as on the robot"
            )


def _memory_stick(path: Path, backend: str | None, mtn_mode: str | None, memory_stick) -> MemoryStick | None:
    """The memory stick ``path`` names (``memory_stick_folder``), loaded and its objects read (a
    ConfigError naming the file and line of a problem), or None for a controller; ValueError for
    a controller's option given with a stick."""
    folder = memory_stick_folder(path)
    if folder is None:
        return None
    refuse_controller_options(folder, backend, mtn_mode, memory_stick)
    stick = load_memory_stick(folder)
    stick.check_objects()
    return stick


def _run_memory_stick(path: Path, run: MemoryStickRun) -> None:
    """Run a memory stick's objects; an object that crashed or called OPENR::Fatal is
    ControllerFailed. A frame that could not be written, or a match stopped, ends the run
    (SimulationEnd) as its end does."""
    try:
        run.run()
    except SimulationEnd:
        pass  # the writer's error, or the match's interruption, is reported by the caller
    except OpenRObjectCrashed as error:
        raise ControllerFailed(f"memory stick {path.name}: {error}") from error
    failure = run.controller_error or run.fatal_error  # the wrapper's controller failed, or OPENR::Fatal
    if failure is not None:
        raise ControllerFailed(f"memory stick {path.name}: {failure}")


def _run_as_main(path: Path) -> None:
    """Run a Python file as ``__main__`` in a namespace of its own, leaving ``sys.modules`` and
    ``sys.argv`` alone (``runpy`` swaps them for the run: the threads of a match would leave the
    process with a controller as its ``__main__``)."""
    code = compile(path.read_bytes(), str(path), "exec")
    exec(code, {"__name__": "__main__", "__file__": str(path), "__builtins__": __builtins__})


def _run_controller_program(
    path: Path, executable: Path | None, robot: Robot, workdir: Path | None, match: str | None = None
) -> None:
    """Run a Python or C controller on ``robot`` until its end; ControllerFailed (or the
    simulator's SimulationDiverged, RenderingUnavailable) for a run that did not end well.

    How a controller ends: its run is over (SimulationEnd) or it calls sys.exit(0) or
    sys.exit(): a normal end. It raises (in its own thread or in one it started), or calls
    sys.exit with another status: ControllerFailed quoting its traceback or its status (never
    read as a divergence). The physics diverges: SimulationDiverged. Its robot_die functions
    run in every case (Ctrl-C too); one that raises is reported after the controller's own error.

    ``match``: the robot's name (``red 2``) where it is one of a match's controllers, in its
    robot's thread (``match.run_match`` installs the robot and sets the folders up once for all).
    """
    if match is None:
        controller.install(robot)
    try:
        with contextlib.ExitStack() as stack:
            threads = stack.enter_context(_ControllerThreads(robot, match is not None))
            if match is None:
                stack.enter_context(_controller_context(path.parent, workdir))
            name = path.name if match is None else f"{path.name} of {match}"
            error: BaseException | None = None
            try:
                if executable is None:
                    with _WaitNotices(path, name, robot):
                        if match is None:
                            runpy.run_path(str(path), run_name="__main__")
                        else:
                            _run_as_main(path)
                else:
                    run_c_controller(executable, name)
            except SimulationEnd:
                pass
            except SystemExit as exc:
                error = None if exc.code in (None, 0) else exc
            except KeyboardInterrupt:
                raise
            except BaseException as exc:  # an Exception, or another BaseException it raised (GeneratorExit)
                interrupt = interrupt_behind(exc)
                if interrupt is not None:
                    raise interrupt from None
                error = exc
            finally:
                ended_ms = robot.time_ms
                die_failures = controller.call_die_functions()
            where = f"at simulated t = {ended_ms / 1000:.3f} s"
            if error is None and threads.error is not None:
                thread, error, raised_ms = threads.error
                where = f"in thread {thread!r} at simulated t = {raised_ms / 1000:.3f} s"
            die_report = "".join(
                f"\n{'then ' if error is not None or k else ''}its robot_die function "
                f"{getattr(fn, '__qualname__', repr(fn))} raised:\n" + controller_traceback(exc).rstrip()
                for k, (fn, exc) in enumerate(die_failures)
            )
            if isinstance(error, (SimulationDiverged, RenderingUnavailable)):  # the simulator's, not the controller's
                if die_report:
                    raise type(error)(f"{error}{die_report}") from error
                raise error
            if isinstance(error, SystemExit):
                status = error.code if isinstance(error.code, int) else repr(error.code)
                call = "sys.exit" if executable is None else "exit"
                raise ControllerFailed(
                    f"controller {path.name} exited with {call}({status}) {where}{die_report}", exit_status=error.code
                ) from error
            if isinstance(error, CControllerError):
                if error.time_ms is not None:  # its robot_die functions may have stepped since
                    where = f"at simulated t = {error.time_ms / 1000:.3f} s"
                raise ControllerFailed(f"controller {path.name} {where}: {error}") from error
            if error is not None:
                raise ControllerFailed(
                    f"controller {path.name} raised {where}:\n" + controller_traceback(error) + die_report
                ) from error
            if die_report:
                raise ControllerFailed(f"controller {path.name} ended {where};{die_report}")
    finally:
        if match is None:
            controller.install(None)
