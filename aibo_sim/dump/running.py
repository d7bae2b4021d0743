"""Running a dump: a controller run or an environment run into a ``DumpWriter``, or shards of
it in worker processes that die with their parent."""

from __future__ import annotations

import contextlib
import ctypes
import hashlib
import os
import signal
import sys
import threading
import time
from dataclasses import dataclass
from multiprocessing import connection, get_context
from pathlib import Path

import gymnasium
import numpy as np

from openr_bridge import FRAME_RATE_HZ

from ..camera import CameraSettings, camera_size, describe_camera, scene_light_temperature
from ..robot import BACKENDS, SimulationEnd
from ..runner import Progress, run_controller
from ..sim import load_model
from .formats import DEFAULT_FORMATS, DUMP_FORMAT, FORMATS, PATHS, DumpError
from .writing import DumpWriter, command_line, prepare_folder, remove_temporary_files

POLICIES = ("random", "scripted", "zero")
SHARD_BALL_X, SHARD_BALL_Y = (0.3, 1.2), (-0.5, 0.5)  # metres: ahead of the robot's start
SCRIPTED_SWEEP_HZ = 0.25
PARENT_POLL_S = 0.5  # a worker's check that its parent still lives (where PR_SET_PDEATHSIG is missing)
SHARD_LOCK_WAIT_S = 5.0  # a shard's lock may still be held by a worker of a killed dump, dying
WORKER_STOP_S = 5.0  # SIGTERM, then SIGKILL after this
PR_SET_PDEATHSIG = 1  # <linux/prctl.h>


@dataclass
class DumpSummary:
    out: str
    frames: int  # complete frames in the dump
    new_frames: int  # written by this run
    bytes_written: int
    wall_s: float
    repaired_frames: int = 0  # complete frames whose missing files this run rewrote

    @property
    def frames_per_s(self) -> float:
        return self.new_frames / max(self.wall_s, 1e-9)


class _CameraFrames:
    """Robot frame listener: hands each new camera frame with index < ``frames`` to the writer.

    A failure ends the run (SimulationEnd) and is kept in ``error``: raised inside the
    controller's step, it would otherwise read as the controller's own exception.
    """

    def __init__(self, writer: DumpWriter, frames: int):
        self.writer, self.frames = writer, frames
        self.last_index = -1
        self.error: Exception | None = None

    def __call__(self, robot) -> None:
        index = robot.sim.camera_frame_index()
        if index == self.last_index or index >= self.frames:
            return
        self.last_index = index
        if self.writer.needs_frame(index):
            try:
                self.writer.write(robot.sim, index)
            except Exception as exc:
                self.error = exc
                raise SimulationEnd() from exc


def _dump_controller(parameters: dict, out: Path, resume: bool, **lock) -> DumpWriter:
    frames, camera_full = parameters["frames"], parameters["camera_full"]
    settings = CameraSettings(**parameters["camera_settings"])
    model = load_model(parameters["scene"])
    camera = describe_camera(parameters["camera_profile"], settings, camera_size(camera_full),
                             scene_light_temperature(model))
    with DumpWriter(out, parameters["formats"], parameters, resume=resume, camera=camera, model=model,
                    **lock) as writer:
        listener = _CameraFrames(writer, frames)
        run_controller(parameters["controller"], backend=parameters["backend"], duration=frames / FRAME_RATE_HZ,
                       scene=parameters["scene"], seed=parameters["seed"], pose=parameters["pose"],
                       ball=parameters["ball"], camera_full=camera_full, camera_profile=parameters["camera_profile"],
                       camera_settings=settings, frame_listeners=[listener], progress=parameters.get("progress", True))
        if listener.error is not None:
            raise listener.error
    return writer


def _policy(name: str, action_space, seed: int):
    """The action for step k: uniform random (seeded), zeros, or a sine sweep of every joint."""
    if name == "random":
        action_space.seed(seed)
        return lambda step: action_space.sample()
    if name == "zero":
        return lambda step: np.zeros(action_space.shape, action_space.dtype)
    phases, dtype = np.arange(action_space.shape[0]), action_space.dtype
    return lambda step: (0.8 * np.sin(2 * np.pi * SCRIPTED_SWEEP_HZ * step / FRAME_RATE_HZ + phases)).astype(dtype)


def _dump_env(parameters: dict, out: Path, resume: bool, **lock) -> DumpWriter:
    camera, settings = "openr" if parameters["backend"] == "openr" else "rgb", parameters["camera_settings"]
    try:
        env = gymnasium.make(parameters["env"], camera=camera, scene=parameters["scene"],
                             camera_profile=parameters["camera_profile"], camera_wb=settings["white_balance"],
                             camera_gain=settings["gain"], camera_shutter=settings["shutter"])
    except gymnasium.error.Error as exc:
        raise ValueError(f"environment {parameters['env']!r}: {exc}") from None
    steps, seed = parameters["frames"], parameters["seed"]
    progress = Progress(steps / FRAME_RATE_HZ, enabled=parameters.get("progress", True))
    try:
        sim = env.unwrapped.sim
        with DumpWriter(out, parameters["formats"], parameters, resume=resume, camera=sim.camera.describe(),
                        model=sim.model, **lock) as writer:
            policy = _policy(parameters["policy"], env.action_space, seed)
            env.reset(seed=seed)
            index, episode = 0, 0
            writer.write(sim, index, {"episode": episode, "action": None, "reward": None})
            for step in range(steps):
                action = policy(step)
                _, reward, terminated, truncated, _ = env.step(action)
                index += 1
                writer.write(sim, index, {"episode": episode, "action": np.asarray(action).tolist(),
                                          "reward": float(reward)})
                if (terminated or truncated) and step + 1 < steps:
                    env.reset()
                    index, episode = index + 1, episode + 1
                    writer.write(sim, index, {"episode": episode, "action": None, "reward": None})
                progress.update((step + 1) / FRAME_RATE_HZ)
    finally:
        progress.close()
        env.close()
    return writer


def _dump_one(parameters: dict, out: Path, resume: bool, **lock) -> DumpSummary:
    start = time.perf_counter()
    run = _dump_env if parameters["env"] else _dump_controller
    writer = run(parameters, out, resume, **lock)
    return DumpSummary(str(out), len(writer.complete), writer.new_frames, writer.bytes_written,
                       time.perf_counter() - start, writer.repaired_frames)


def _check_env(env_id: str) -> None:
    """ValueError unless ``env_id`` is an aibo_sim environment (a dump renders its head camera)."""
    from ..envs import ENV_SPECS

    try:
        spec = gymnasium.spec(env_id)
    except gymnasium.error.Error as exc:
        raise ValueError(f"environment {env_id!r}: {exc}") from None
    entry = spec.entry_point if isinstance(spec.entry_point, str) else getattr(spec.entry_point, "__module__", "")
    if not str(entry).startswith("aibo_sim."):
        raise ValueError(f"environment {env_id!r} is not an aibo_sim environment; a dump needs the robot's camera "
                         f"({', '.join(ENV_SPECS)})")


def file_sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as file:
        for block in iter(lambda: file.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def dump(out, *, controller: str | Path | None = None, env: str | None = None, policy: str = "random",
         frames: int = 300, backend: str = "sim", scene: str | Path | None = None, seed: int = 0,
         pose: tuple[float, float, float] | None = None, ball: tuple[float, float] | None = None,
         formats=DEFAULT_FORMATS, camera_full: bool = False, camera_profile: str = "ers7",
         camera_settings: CameraSettings | None = None, resume: bool = False, workers: int = 1) -> DumpSummary:
    """Dump a controller run (``frames`` camera frames) or an env run (``frames`` steps) to ``out``;
    ``pose`` (x, y, yaw in degrees) and ``ball`` apply to controller dumps."""
    if (controller is None) == (env is None):
        raise ValueError("dump a controller file or an environment (--env), not both or neither")
    unknown = sorted(set(formats) - set(FORMATS))
    if unknown or not formats:
        raise ValueError(f"unknown formats {unknown or '(none given)'}; known: {', '.join(FORMATS)}")
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, not {backend!r}")
    if policy not in POLICIES:
        raise ValueError(f"policy must be one of {POLICIES}, not {policy!r}")
    if frames < 1:
        raise ValueError(f"the number of frames (or steps) must be positive, not {frames}")
    if not 1 <= workers <= frames:
        raise ValueError(f"--workers must be between 1 and the number of frames ({frames}), not {workers}")
    if env is not None and camera_full:
        raise ValueError("--camera-full applies to controller dumps; environments render their own layer")
    if env is not None and (ball is not None or pose is not None):
        raise ValueError("--ball and --pose apply to controller dumps; environments place the robot and ball themselves")
    if env is not None:
        _check_env(env)
    controller_sha256 = None
    if controller is not None:
        controller = Path(controller).resolve()
        if not controller.is_file():
            raise FileNotFoundError(f"{controller}: no such controller file")
        controller_sha256 = file_sha256(controller)
    out = Path(out).resolve()
    parameters = {"controller": controller and str(controller), "env": env, "policy": env and policy,
                  "frames": frames, "backend": backend, "scene": scene and str(Path(scene).resolve()), "seed": seed,
                  "pose": pose and list(pose), "ball": ball and list(ball),
                  "formats": [f for f in FORMATS if f in formats], "camera_full": camera_full,
                  "camera_profile": camera_profile, "camera_settings": (camera_settings or CameraSettings()).as_dict()}
    if controller_sha256 is not None:
        parameters["controller_sha256"] = controller_sha256  # a resume refuses another controller file
    if workers == 1:
        return _dump_one(parameters, out, resume)
    return _dump_sharded(parameters, out, resume, workers)


# ---------------------------------------------------------------- shards in worker processes


def die_with_parent(parent_pid: int) -> None:
    """Make this worker process end when ``parent_pid`` does, however it ends (SIGKILL too).

    Linux: ``prctl(PR_SET_PDEATHSIG, SIGKILL)``; everywhere: a thread that ends the process
    once its parent is gone (it has been re-parented), checked every ``PARENT_POLL_S``.
    """
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
    if os.getppid() != parent_pid:  # the parent died before the line above
        os._exit(1)

    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(PARENT_POLL_S)
        os._exit(1)

    threading.Thread(target=watch, name="aibo-sim parent watchdog", daemon=True).start()


def _shard_worker(results, parent_pid: int, parameters: dict, out: Path, resume: bool, command: str) -> None:
    """A worker process's body: one shard, its summary or exception sent back on ``results``."""
    die_with_parent(parent_pid)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C reaches the whole group: the parent stops us
    try:
        result = ("ok", _dump_one(parameters, out, resume, lock_wait_s=SHARD_LOCK_WAIT_S, command=command))
    except BaseException as exc:  # noqa: BLE001 - the parent reports it
        result = ("error", exc)
    try:
        results.send(result)
    except Exception:  # an exception that does not pickle
        results.send(("error", DumpError(f"{out}: {type(result[1]).__name__}: {result[1]}")))


def _stop(processes) -> None:
    for process in processes:
        if process.is_alive():
            process.terminate()
    deadline = time.monotonic() + WORKER_STOP_S
    for process in processes:
        process.join(max(0.0, deadline - time.monotonic()))
        if process.is_alive():
            process.kill()
            process.join()


def _run_shards(shards: list[tuple[dict, Path]], resume: bool) -> list[DumpSummary]:
    """Each shard in its own spawned process; the first failure stops the others and is raised.
    However this returns (an exception, a signal turned into one), no worker outlives it."""
    context, parent, command = get_context("spawn"), os.getpid(), command_line()
    processes, pending, results = [], {}, [None] * len(shards)
    try:
        for k, (parameters, folder) in enumerate(shards):
            receive, send = context.Pipe(duplex=False)
            process = context.Process(target=_shard_worker, name=f"aibo-sim dump {folder.name}", daemon=True,
                                      args=(send, parent, parameters, folder, resume,
                                            f"{command} (worker of pid {parent}: {folder.name})"))
            process.start()
            send.close()
            processes.append(process)
            pending[receive] = k
        while pending:
            for receive in connection.wait(list(pending)):
                k = pending.pop(receive)
                try:
                    status, value = receive.recv()
                except EOFError:
                    processes[k].join()
                    raise DumpError(f"{shards[k][1]}: its worker process ended without a result "
                                    f"(exit status {processes[k].exitcode}); continue with --resume") from None
                if status == "error":
                    raise value
                results[k] = value
        return results
    finally:
        stopped = [p for p in processes if p.is_alive()]
        _stop(processes)
        if stopped:
            for parameters, folder in shards:
                remove_temporary_files(folder, {f: {"path": PATHS[f]} for f in parameters["formats"]})


def _dump_sharded(parameters: dict, out: Path, resume: bool, workers: int) -> DumpSummary:
    start = time.perf_counter()
    meta = {"format": DUMP_FORMAT, "parameters": {**parameters, "workers": workers},
            "shards": [f"shard_{k}" for k in range(workers)]}
    prepared = prepare_folder(out, meta, resume)
    try:
        shards = []
        for k in range(workers):
            seed = parameters["seed"] + k
            ball = parameters["ball"]
            if parameters["controller"] and ball is None:
                rng = np.random.default_rng(seed)
                ball = [float(rng.uniform(*SHARD_BALL_X)), float(rng.uniform(*SHARD_BALL_Y))]
            frames = parameters["frames"] // workers + (k < parameters["frames"] % workers)
            shard = {**parameters, "seed": seed, "ball": ball, "frames": frames, "progress": False}
            shards.append((shard, out / f"shard_{k}"))
        results = _run_shards(shards, resume)
    finally:
        prepared.lock.release()
    return DumpSummary(str(out), sum(r.frames for r in results), sum(r.new_frames for r in results),
                       sum(r.bytes_written for r in results), time.perf_counter() - start,
                       sum(r.repaired_frames for r in results))
