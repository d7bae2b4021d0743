"""Runs a controller file headless, as Webots would, on either backend."""

from __future__ import annotations

import contextlib
import json
import math
import os
import runpy
import sys
import time
import traceback
from dataclasses import asdict, dataclass, field
from pathlib import Path

import cv2
import numpy as np

from . import controller
from .camera import CameraSettings
from .options import place, start_values
from .robot import Robot, SimulationEnd
from .sim import Simulation, SimulationDiverged, models_dir


class ControllerFailed(RuntimeError):
    """The controller raised; the message carries the simulated time and the traceback."""


@dataclass
class RunSummary:
    controller: str
    backend: str
    simulated_s: float
    wall_s: float
    real_time_factor: float
    camera_frames: int
    robot_xy_yaw: tuple[float, float, float]  # at the end: metres, metres, radians
    ball_xy: tuple[float, float] | None  # at the end; None in a scene without a ball
    # What the run started from, as given (run.json records these too): the options
    # ``--scene`` (resolved path; None: the RoboCup field), ``--seed``, ``--pose`` (x, y in
    # metres, yaw in degrees; None: the scene's start) and ``--ball`` (None: the scene's).
    scene: str | None = None
    seed: int = 0
    pose: tuple[float, float, float] | None = None
    ball: tuple[float, float] | None = None
    camera: dict = field(default_factory=dict)  # ``HeadCamera.describe()`` at the start: profile, lens, settings


def motion_dirs(controller_path: Path) -> tuple[Path, ...]:
    """Where ``mtn_new`` looks for relative names: the controller's folder, then the bundled motions."""
    return (controller_path.parent, models_dir() / "motions")


class FrameWriter:
    """Writes each camera frame the controller's camera captured as ``frames/NNNNNN.png``."""

    def __init__(self, directory: Path):
        self.directory = directory / "frames"
        self.directory.mkdir(parents=True, exist_ok=True)
        self.count = 0

    def __call__(self, index: int, rgb: np.ndarray) -> None:
        path = self.directory / f"{index:06d}.png"
        partial = path.with_suffix(".partial.png")
        if not cv2.imwrite(str(partial), np.ascontiguousarray(rgb[:, :, ::-1])):
            raise OSError(f"could not write {partial}")
        os.replace(partial, path)
        self.count += 1


@contextlib.contextmanager
def _controller_context(controller_dir: Path, out: Path | None):
    """Modules beside the controller import; its files land in ``out`` (when given)."""
    previous = Path.cwd()
    sys.path.insert(0, str(controller_dir))
    if out is not None:
        os.chdir(out)
    try:
        yield
    finally:
        os.chdir(previous)
        sys.path.remove(str(controller_dir))


class Progress:
    """A one-line progress bar on a terminal; silent otherwise."""

    def __init__(self, duration_s: float, stream=sys.stderr, enabled: bool = True):
        self.duration_s, self.stream = duration_s, stream
        self.enabled = enabled and stream.isatty()
        self._last = 0.0

    def __call__(self, robot: Robot) -> None:
        """Frame listener form of ``update``."""
        self.update(robot.time_ms / 1000)

    def update(self, simulated_s: float) -> None:
        now = time.monotonic()
        if self.enabled and now - self._last > 0.25:
            self._last = now
            bar = "#" * int(30 * min(1.0, simulated_s / self.duration_s))
            self.stream.write(f"\r[{bar:<30}] {simulated_s:7.2f} / {self.duration_s:.2f} s")
            self.stream.flush()

    def close(self) -> None:
        if self.enabled:
            self.stream.write("\n")


def run_controller(path: str | Path, *, backend: str = "sim", duration: float = 10.0, scene=None, seed: int = 0,
                   out: str | Path | None = None, mtn_mode: str = "openr", memory_stick=None,
                   camera_full: bool = False, camera_profile: str = "ers7",
                   camera_settings: CameraSettings | None = None, pose: tuple[float, float, float] | None = None,
                   ball: tuple[float, float] | None = None, frame_listeners=(), progress: bool = True) -> RunSummary:
    """Run a controller file for ``duration`` simulated seconds; frames, its files and
    ``run.json`` (the summary) go to ``out``.

    The robot starts at ``pose`` (x, y in metres, yaw in degrees; default the scene's start),
    the ball at ``ball``; the head camera is ``camera_profile`` (``ers7`` or ``ideal``) with
    ``camera_settings`` at the start. ``frame_listeners`` are called with the robot after every
    8 ms frame; ``progress=False`` silences the progress bar (worker processes).
    """
    path = Path(path).resolve()
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such controller file")
    if not (math.isfinite(duration) and duration > 0):
        raise ValueError(f"--duration must be positive and finite, not {duration}")
    pose, ball = start_values("--pose", pose, 3), start_values("--ball", ball, 2)
    sim = Simulation(scene, seed=seed, camera_full=camera_full, camera_profile=camera_profile,
                     camera_settings=camera_settings)
    try:
        place(sim, pose, ball)
        camera = sim.camera.describe()
        robot = Robot(sim, backend=backend, mtn_mode=mtn_mode, memory_stick=memory_stick,
                      search_dirs=motion_dirs(path))
    except BaseException:
        sim.close()
        raise
    robot.end_ms = int(round(duration * 1000))
    writer = None
    if out is not None:
        out = Path(out).resolve()
        out.mkdir(parents=True, exist_ok=True)
        writer = FrameWriter(out)
        robot.camera_source.listeners.append(writer)
    robot.frame_listeners.extend(frame_listeners)
    progress_bar = Progress(duration, enabled=progress)
    robot.frame_listeners.append(progress_bar)
    controller.install(robot)
    start = time.perf_counter()
    try:
        with _controller_context(path.parent, out):
            try:
                runpy.run_path(str(path), run_name="__main__")
            except SimulationEnd:
                pass
            except SimulationDiverged:
                raise
            except Exception as exc:
                raise ControllerFailed(
                    f"controller {path.name} raised at simulated t = {robot.time_ms / 1000:.3f} s:\n"
                    + "".join(traceback.format_exception(exc))
                ) from exc
            finally:
                controller.call_die_functions()
    finally:
        progress_bar.close()
        controller.install(None)
        sim.close()
    wall = time.perf_counter() - start
    position, yaw, _ = sim.body_pose()
    ball_end = sim.ball_position()
    summary = RunSummary(str(path), backend, robot.time_ms / 1000, wall, robot.time_ms / 1000 / max(wall, 1e-9),
                         writer.count if writer else 0, (float(position[0]), float(position[1]), yaw),
                         None if ball_end is None else (float(ball_end[0]), float(ball_end[1])),
                         scene=None if scene is None else str(Path(scene).resolve()), seed=seed, pose=pose, ball=ball,
                         camera=camera)
    if out is not None:
        (out / "run.json").write_text(json.dumps(asdict(summary), indent=2) + "\n")
    return summary
