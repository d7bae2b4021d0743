"""A match: several robots on one field, each run by its own controller in its own thread.

Every robot's controller (a Python file, a C/C++ controller, an OPEN-R memory stick) drives
its own robot (``Simulation`` view of the shared ``World``) as in a run of one robot; the
world advances one 8 ms frame when every robot still running has asked for it (``Lockstep``),
so the controllers run in step whatever their speeds, and the same seed gives the same match.
Each robot's camera frames, console and ``run.json`` go to ``out/robotN/`` (N its place in the
robots' list, from 1), the match's ``run.json`` to ``out``.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import re
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from traceback import walk_tb

from . import controller
from .cbind import CompileError, compile_controller, controller_sources, is_c_controller
from .config import DEFAULT_DURATION_S, CameraConfig, ParameterError, WorldConfig, configs
from .files import check_atomic_write, make_folder, remove_in, write_file_atomic
from .openr.host import PICTURE_SIZE, MemoryStickRun
from .placement import make_out_folder, place_match
from .render import check_rendering
from .robot import Robot, SimulationEnd
from .runner import (
    CONSOLE_FILE,
    LOCK_FILE,
    MEMORY_STICK,
    RUN_FILE,
    SOUND_FILE,
    ControllerFailed,
    FrameWriter,
    Progress,
    _memory_stick,
    _run_controller_program,
    _run_memory_stick,
    check_duration,
    check_listeners,
    check_python_controller,
    earlier_run,
    motion_dirs,
)
from .sim import Simulation, SimulationDiverged
from .team import check_controllers, check_robots

# After Ctrl-C or SIGTERM, how long a match waits for its robots' threads before it writes its
# run.json files: a Python controller stuck in its own code never ends (the command then ends
# without waiting for its thread: cli.program); a C controller is stopped within 2 s.
STOP_WAIT_S = 6.0

# The options of a run of one robot that a match refuses, and why.
SINGLE_ROBOT_OPTIONS = {
    "--pose": "each robot's pose comes from its entry",
    "--backend": "Python and C controllers run on the sim backend, a memory stick on its OPEN-R runtime",
    "--mtn-mode": "motions play as OPEN-R plays them (the openr mode)",
    "--memory-stick": "a robot runs a memory stick when its entry names the stick's folder as its controller",
}


def refuse_single_robot_options(command: str, values: dict) -> None:
    """ValueError, saying why, for the first of ``SINGLE_ROBOT_OPTIONS`` given a value (``command``:
    ``run`` or ``dump``)."""
    for option, value in values.items():
        if value is not None:
            raise ValueError(
                f"{option} applies to a {command} of one robot: in a match, {SINGLE_ROBOT_OPTIONS[option]}"
            )


def robot_folder(index: int) -> str:
    """The folder of robot ``index`` (from 0) in a match's ``--out``: ``robot1``, ``robot2``, ..."""
    return f"robot{index + 1}"


@contextlib.contextmanager
def controller_named_as_given(spec):
    """A missing controller file, a syntax error in it or a C controller that does not compile,
    raised inside, prefixed with where ``spec`` was given (``robots.toml:5: red 2: ...``,
    ``--robot red:2::ctl.py: red 2: ...``)."""
    try:
        yield
    except (FileNotFoundError, ValueError, CompileError) as exc:
        if type(exc) not in (FileNotFoundError, ValueError, CompileError) or not (spec.given and spec.controller):
            raise
        raise type(exc)(f"{spec.given}: {spec.name}: {exc}") from None


class Lockstep:
    """Robots' controllers, each in its own thread, stepping one world together: the world
    advances a frame when every robot still running has asked for it (``step``); a robot whose
    controller ended ``leave``s; ``stop`` ends every robot's next step with SimulationEnd."""

    def __init__(self, world):
        self.world = world
        self._running = {robot.index for robot in world.robots}
        self._waiting: set[int] = set()
        self._generation = 0
        self._failure: BaseException | None = None
        self._stopped = False
        self._condition = threading.Condition()

    def step(self, robot: Simulation, frames: int, before_frame=None) -> None:
        """Advance ``frames`` frames with the other robots (``Simulation.step_frames``)."""
        if not isinstance(frames, int) or frames < 1:
            raise ValueError(f"frames must be a whole number >= 1, not {frames!r}")
        for _ in range(frames):
            if before_frame is not None:
                before_frame()  # the world cannot move before this robot asks for the frame
            with self._condition:
                if self._stopped or self._failure is not None:
                    raise SimulationEnd()
                self._waiting.add(robot.index)
                generation = self._generation
                self._advance_when_all_wait()
                while self._generation == generation and not self._stopped and self._failure is None:
                    self._condition.wait()
                if self._generation == generation:
                    raise SimulationEnd()

    def _advance_when_all_wait(self) -> None:
        if not self._running or not self._waiting >= self._running:
            return
        try:
            self.world.step_frames(1)
        except BaseException as error:  # the physics diverged: every robot stops
            self._failure = error
            self._condition.notify_all()
            raise
        self._waiting.clear()
        self._generation += 1
        self._condition.notify_all()

    def leave(self, robot: Simulation) -> None:
        """``robot``'s controller has ended: the world no longer waits for it."""
        with self._condition:
            self._running.discard(robot.index)
            self._waiting.discard(robot.index)
            if self._waiting:
                try:
                    self._advance_when_all_wait()
                except BaseException:  # kept in _failure: the robots that wait report it
                    pass

    def stop(self) -> None:
        """End every robot's next ``step`` (and those waiting now) with SimulationEnd."""
        with self._condition:
            self._stopped = True
            self._condition.notify_all()

    @property
    def failure(self) -> BaseException | None:
        """The error that stopped the world (its physics diverged), or None."""
        return self._failure


@dataclass
class _Player:
    """One robot of a match: its spec, controller and what runs it."""

    robot: Simulation
    path: Path
    kind: str  # "python", "c" or MEMORY_STICK
    executable: Path | None = None
    stick: object = None
    program: object = None
    writer: FrameWriter | None = None
    error: BaseException | None = None
    # Set when its thread has ended: a join that a signal interrupted may take a live thread for
    # an ended one (CPython 3.11), so the match waits on this rather than on the thread.
    ended: threading.Event = field(default_factory=threading.Event)


def _player(robot: Simulation, controller_path, compiled: dict) -> _Player:
    """The robot's controller, checked (and compiled, once per controller) before the match starts."""
    path = Path(controller_path).resolve()
    stick = _memory_stick(path, None, None, None)
    if stick is not None:
        return _Player(robot, stick.root, MEMORY_STICK, stick=stick)
    if is_c_controller(path):
        if path not in compiled:
            compiled[path] = compile_controller(path)
        return _Player(robot, controller_sources(path)[0], "c", executable=compiled[path])
    check_python_controller(path)
    return _Player(robot, path, "python")


def run_match(
    robots,
    *,
    controller_path=None,
    duration: float = DEFAULT_DURATION_S,
    world: WorldConfig | None = None,
    camera: CameraConfig | None = None,
    out=None,
    frame_listeners=(),
    robot_listeners=None,
    progress: bool = True,
) -> dict:
    """Run a match of ``robots`` (``team.RobotSpec``s, up to ``team.MAX_ROBOTS``) for ``duration``
    simulated seconds, in ``world`` (its scene, seed and ball; each robot's pose is its spec's),
    each robot's head camera set up as ``camera``; each robot runs its spec's controller, or
    ``controller_path`` when it names none. Returns the match's summary (what ``out/run.json``
    holds).

    ``frame_listeners`` are called after every 8 ms frame with robot 1's program (its ``Robot``
    or ``MemoryStickRun``); ``robot_listeners(robot)``, when given, returns for each robot (its
    ``Simulation``) the listeners called so with its own program, in its controller's thread.

    Raises:
        TeamError, ValueError: bad robots (one line naming them), or a robot without controller.
        ControllerFailed: one or more controllers failed (the others ran to the end).
        SimulationDiverged: the physics diverged (every robot stopped there).
    """
    robots = check_robots(robots, "--robots")
    world, camera = configs(world, camera)
    check_listeners(frame_listeners, "frame_listeners")
    if robot_listeners is not None and not callable(robot_listeners):
        raise TypeError(f"robot_listeners must be a callable (or None), not {robot_listeners!r}")
    if world.pose is not None:
        raise ParameterError.at(
            "pose", " ".join(map(str, world.pose)), "applies to a run of one robot: each robot's pose is its spec's"
        )
    scene, seed, ball, ball_type = world.scene, world.seed, world.ball, world.ball_type
    check_duration(duration)
    check_controllers(robots, controller_path, "run")
    sim = Simulation(scene, seed=seed, camera=camera, ball_type=ball_type, robots=robots)
    world, compiled = sim.world, {}
    players: list[_Player] = []
    made: list[Path] = []  # the robots' folders this match made: removed again if it is refused
    try:
        place_match(sim, ball)
        check_rendering(sim.model)
        for robot in world.robots:
            with controller_named_as_given(robot.spec):
                players.append(_player(robot, robot.spec.controller or controller_path, compiled))
        _check_module_names(players)
        out = None if out is None else make_out_folder(out)
        if out:
            _check_match_folder(out, len(players))
        for player in players:
            folder = out / robot_folder(player.robot.index) if out else None
            if player.kind == MEMORY_STICK:
                player.program = MemoryStickRun(
                    player.robot,
                    player.stick,
                    folder or Path.cwd(),
                    log_path=folder and folder / CONSOLE_FILE,
                    sound_path=folder and folder / SOUND_FILE,
                )
                listeners = player.program.camera_listeners
            else:
                player.program = Robot(player.robot, search_dirs=motion_dirs(player.path))
                listeners = player.program.camera_source.listeners
            if folder is not None:
                if not os.path.lexists(folder):
                    made.append(folder)
                make_folder(folder)
                player.writer = FrameWriter(folder, controller=player.path, backend=player.kind, prepare=False)
                listeners.append(player.writer)
            player.program.end_ms = int(round(duration * 1000))
        if out:  # the match "incomplete" first, then every robot's folder (each checked and locked) cleared
            match_json = {"match": True, "status": "incomplete", "robots": [p.robot.spec.as_dict() for p in players]}
            write_file_atomic(out / RUN_FILE, (json.dumps(match_json, indent=2) + "\n").encode())
        for player in players:
            if player.writer is not None:
                player.writer.prepare()
    except BaseException:
        for player in players:
            if player.writer is not None:
                player.writer.lock.release()
        for folder in made:  # a refused match leaves --out as it was
            remove_in(folder, [LOCK_FILE])
            with contextlib.suppress(OSError):  # a link now in its place is not removed
                os.rmdir(folder)
        sim.close()
        raise
    players[0].program.frame_listeners.extend(frame_listeners)
    if robot_listeners is not None:
        for player in players:
            player.program.frame_listeners.extend(robot_listeners(player.robot))
    progress_bar = Progress(duration, enabled=progress)
    players[0].program.frame_listeners.append(progress_bar)
    world.lockstep = Lockstep(world)
    start = time.perf_counter()
    threads = [
        threading.Thread(target=_play, args=(player, world.lockstep), name=f"robot {player.robot.spec.name}")
        for player in players
    ]
    added = [str(p.path.parent) for p in players if str(p.path.parent) not in sys.path]
    added = list(dict.fromkeys(added))
    sys.path[:0] = added  # modules beside each controller import
    previous = Path.cwd()
    interrupted, started = False, []
    thread_errors: list[tuple[str, list[_Player]]] = []  # threads the controllers started raised (_play keeps its own)

    def thread_failed(args) -> None:
        if not issubclass(args.exc_type, SimulationEnd):
            name = args.thread.name if args.thread is not None else "?"
            error = f"its thread {name!r} raised {args.exc_type.__name__}: {args.exc_value}"
            thread_errors.append((error, _code_owners(players, args.exc_traceback)))

    previous_hook, threading.excepthook = threading.excepthook, thread_failed
    try:
        if out is not None:
            os.chdir(out)  # the controllers' own files land in --out
        for player, thread in zip(players, threads):
            thread.start()
            started.append(player)
        for player in started:
            while not player.ended.wait(0.1):  # wakes for Ctrl-C and SIGTERM
                pass
    except BaseException:  # Ctrl-C, SIGTERM: every robot stops at its next step
        interrupted = True
        world.lockstep.stop()
        deadline = time.monotonic() + STOP_WAIT_S
        for player in started:
            player.ended.wait(max(0.0, deadline - time.monotonic()))
        raise
    finally:
        threading.excepthook = previous_hook
        os.chdir(previous)
        for path in added:
            sys.path.remove(path)
        progress_bar.close()
        _blame_thread_errors(thread_errors)
        summary = _summary(sim, players, seed, scene, ball, ball_type, time.perf_counter() - start, interrupted)
        unwritten = [  # a frame, or a memory stick's console.log or sound, that could not be written
            p.error
            for p in players
            if isinstance(p.error, OSError) and (p.kind == MEMORY_STICK or p.error is getattr(p.writer, "error", None))
        ]
        try:
            if out is not None:
                _write_summaries(out, players, summary)
        except OSError:
            if not unwritten:
                raise  # else the full disk refused run.json too: the frame's error is reported below
        finally:
            for player in players:
                if player.writer is not None:
                    player.writer.lock.release()
            sim.close()
    if world.lockstep.failure is not None:
        raise world.lockstep.failure
    if unwritten:
        raise unwritten[0]  # "cannot write ...": the disk's fault, not a controller's
    failed = [p for p in players if p.error is not None]
    if failed:
        raise ControllerFailed("; ".join(f"{p.robot.spec.name}: {p.error}" for p in failed))
    return summary


def _play(player: _Player, lockstep: Lockstep) -> None:
    """A robot's thread: its controller from start to end, its error kept."""
    try:
        if player.kind == MEMORY_STICK:
            _run_memory_stick(player.path, player.program)
        else:
            controller.install(player.program, match=True)
            try:
                _run_controller_program(
                    player.path, player.executable, player.program, None, match=player.robot.spec.name
                )
            finally:
                controller.install(None, match=True)
    except SimulationDiverged:
        pass  # the lockstep keeps it: the match reports it once
    except BaseException as error:
        player.error = error
    finally:
        if player.writer is not None and player.writer.error is not None:
            player.error = player.writer.error  # a frame it could not write ended its run
        try:
            lockstep.leave(player.robot)
            player.robot.camera.close()  # its OpenGL context is current in this thread only
        finally:
            player.ended.set()


def _code_owners(players: list[_Player], traceback) -> list[_Player]:
    """The Python controllers whose code a thread's traceback runs through: those whose main file
    it is, else those whose folder holds it (the first frame that has any); every Python
    controller where none."""
    python = [player for player in players if player.kind == "python"]
    for frame, _ in walk_tb(traceback):
        file = Path(frame.f_code.co_filename)
        owners = [p for p in python if p.path == file] or [p for p in python if p.path.parent == file.parent]
        if owners:
            return owners
    return python


def _blame_thread_errors(thread_errors: list[tuple[str, list[_Player]]]) -> None:
    """A thread a Python controller started raised: that controller failed, as in a run of one
    robot (the thread's first error; of several controllers its code could be, each, saying so)."""
    if thread_errors:
        error, owners = thread_errors[0]
        suspects = "" if len(owners) == 1 else f" (a thread of one of {len(owners)} Python controllers)"
        for player in owners:
            player.error = player.error or ControllerFailed(error + suspects)


def _check_module_names(players: list[_Player]) -> None:
    """ValueError where the folders of two Python controllers hold a module of one name (``NAME.py``
    or a package ``NAME/``, not a controller's own main file): a match's Python controllers share
    one interpreter, where both would import the one found first."""
    mains = {player.path for player in players}
    seen: dict[str, tuple[str, Path]] = {}
    for player in players:
        if player.kind != "python":
            continue
        for entry in sorted(player.path.parent.iterdir()):
            if entry.suffix == ".py" and entry.is_file() and entry not in mains:
                name = entry.stem
            elif (entry / "__init__.py").is_file():
                name = entry.name
            else:
                continue
            robot, first = seen.setdefault(name, (player.robot.spec.name, entry))
            if first != entry:
                raise ValueError(
                    f"{robot}'s {first} and {player.robot.spec.name}'s {entry} are both the module {name!r}: the "
                    "Python controllers of a match share one interpreter, where both would import the first: "
                    "rename one"
                )


def _check_match_folder(out: Path, robots: int) -> None:
    """OSError when ``out`` holds what would lie mixed with this match's files: a run of one robot
    (its frames), or an earlier match's robot folders beyond this match's ``robots``."""
    check_atomic_write(out / RUN_FILE)
    previous = earlier_run(out)
    if previous is not None and previous.get("match") is not True:
        raise OSError(
            f"{out} holds a run of one robot ({RUN_FILE} and its frames): a match would leave them beside "
            "its robots' folders; choose another --out"
        )
    extra = sorted(
        number
        for name in os.listdir(out)
        if re.fullmatch(r"robot[1-9][0-9]*", name) and (number := int(name[5:])) > robots
    )
    if extra:
        more = f" and {len(extra) - 1} more" if len(extra) > 1 else ""
        has = f"{robots} robot{'s' * (robots > 1)}"
        raise OSError(
            f"{out} holds an earlier match's {robot_folder(extra[0] - 1)}{more} (this match has {has}): its "
            "files would lie beside this match's; remove it or choose another --out"
        )


def _summary(sim, players, seed, scene, ball, ball_type, wall: float, interrupted: bool) -> dict:
    """The match's run.json: how it ended, the world's settings and each robot's entry."""
    simulated = sim.time_ms / 1000
    entries = []
    for player in players:
        position, yaw, _ = player.robot.body_pose()
        entries.append(
            {
                **player.robot.spec.as_dict(),
                "folder": robot_folder(player.robot.index),
                "controller": str(player.path),
                "backend": player.kind,
                "status": "failed" if player.error is not None else "interrupted" if interrupted else "done",
                **({"error": str(player.error)} if player.error is not None else {}),
                "camera_frames": player.writer.count if player.writer else 0,
                "robot_pose": [float(position[0]), float(position[1]), math.degrees(yaw)],
                "camera": player.robot.camera.describe(PICTURE_SIZE if player.kind == MEMORY_STICK else None),
            }
        )
    ball_end = sim.ball_position()
    return {
        "status": "interrupted"
        if interrupted
        else "failed"
        if any(p.error is not None for p in players) or sim.world.lockstep.failure
        else "done",
        "simulated_s": simulated,
        "wall_s": wall,
        "real_time_factor": simulated / max(wall, 1e-9),
        "seed": seed,
        "scene": None if scene is None else str(Path(scene).resolve()),
        "ball": list(ball) if ball is not None else None,
        "ball_type": ball_type,
        "ball_xy": None if ball_end is None else [float(ball_end[0]), float(ball_end[1])],
        "robots": entries,
    }


def _write_summaries(out: Path, players, summary: dict) -> None:
    """``out/run.json`` (the match) and each robot's ``run.json`` (its entry); one that cannot be
    written (its folder now a link) stops no other, its error raised after them."""
    errors = []
    for player, entry in zip(players, summary.get("robots", [])):
        if player.writer is not None:
            try:
                player.writer.write_run_json(entry)
            except OSError as error:
                errors.append(error)
    write_file_atomic(out / RUN_FILE, (json.dumps({"match": True, **summary}, indent=2) + "\n").encode())
    if errors:
        raise errors[0]
