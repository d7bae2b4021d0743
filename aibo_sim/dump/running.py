"""Running a dump: a controller run or an environment run into a ``DumpWriter``, or shards of
it in worker processes that die with their parent (``engine="local"``) or in Ray tasks
(``engine="ray"``)."""

from __future__ import annotations

import contextlib
import ctypes
import hashlib
import os
import signal
import socket
import sys
import threading
import time
from dataclasses import dataclass
from multiprocessing import connection, get_context
from pathlib import Path

import gymnasium
import mujoco
import numpy as np

from openr_bridge import FRAME_RATE_HZ

from ..camera import CameraSettings, camera_size, describe_camera, scene_light_temperature
from ..cbind import compile_controller, controller_sources, is_c_controller
from ..robot import BACKENDS, SimulationEnd
from ..runner import Progress, run_controller
from ..sim import load_model
from .coco import coco_bytes
from .formats import DEFAULT_FORMATS, DUMP_FORMAT, FORMATS, PATHS, DumpError
from .reading import LINES
from .writing import COCO, DumpWriter, command_line, prepare_folder, remove_temporary_files, write_atomic

POLICIES = ("random", "scripted", "zero")
ENGINES = ("local", "ray")
RAY_INSTALL = "pip install 'aibo-sim[ray]'"
RAY_MAX_RETRIES = 3  # a shard whose Ray worker is lost runs again (resuming its folder)
RAY_CONNECT_S = 5.0  # an --ray-address that does not answer in this is refused (ray.init would wait minutes)
PROGRESS_POLL_S = 0.5  # a sharded dump counts its shards' frames this often
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

    def __init__(self, writer: DumpWriter, frames: int, progress: Progress):
        self.writer, self.frames, self.progress = writer, frames, progress
        self.last_index = -1
        self.error: Exception | None = None

    def __call__(self, robot) -> None:
        index = robot.sim.camera_frame_index()
        if index == self.last_index or index >= self.frames:
            return
        self.last_index = index
        self.progress.update(robot.time_ms / 1000, index + 1)
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
    progress = Progress(frames / FRAME_RATE_HZ, enabled=parameters.get("progress", True))
    with DumpWriter(out, parameters["formats"], parameters, resume=resume, camera=camera, model=model,
                    **lock) as writer:
        listener = _CameraFrames(writer, frames, progress)
        try:
            run_controller(parameters["controller"], backend=parameters["backend"], duration=frames / FRAME_RATE_HZ,
                           scene=parameters["scene"], seed=parameters["seed"], pose=parameters["pose"],
                           ball=parameters["ball"], camera_full=camera_full,
                           camera_profile=parameters["camera_profile"], camera_settings=settings,
                           frame_listeners=[listener], progress=False)
        finally:
            progress.close()
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
                progress.update((step + 1) / FRAME_RATE_HZ, index + 1)
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


def model_sha256(scene) -> str:
    """The hash of the compiled scene (the robot, the field, their physics and looks): a resume
    refuses a scene or an aibo-sim whose model changed since the dump began."""
    model = load_model(scene)
    saved = np.zeros(mujoco.mj_sizeModel(model), np.uint8)
    mujoco.mj_saveModel(model, None, saved)
    return hashlib.sha256(saved.tobytes()).hexdigest()


def controller_sha256(path: Path) -> str:
    """The hash of a controller: its file's, or for a C or C++ controller folder, that of its
    sources' names and hashes (compiled first, so that a compile error stops the dump at once)."""
    if not is_c_controller(path):
        if not path.is_file():
            raise FileNotFoundError(f"{path}: no such controller file")
        return file_sha256(path)
    compile_controller(path)
    sources = controller_sources(path)[1]
    if sources == [path]:
        return file_sha256(path)
    return hashlib.sha256("".join(f"{s.name}\0{file_sha256(s)}\0" for s in sources).encode()).hexdigest()


def dump(out, *, controller: str | Path | None = None, env: str | None = None, policy: str = "random",
         frames: int = 300, backend: str = "sim", scene: str | Path | None = None, seed: int = 0,
         pose: tuple[float, float, float] | None = None, ball: tuple[float, float] | None = None,
         formats=DEFAULT_FORMATS, camera_full: bool = False, camera_profile: str = "ers7",
         camera_settings: CameraSettings | None = None, resume: bool = False, workers: int = 1,
         engine: str = "local", ray_address: str | None = None) -> DumpSummary:
    """Dump a controller run (``frames`` camera frames) or an env run (``frames`` steps) to ``out``;
    ``pose`` (x, y, yaw in degrees) and ``ball`` apply to controller dumps. ``engine="ray"``
    runs the ``workers`` shards as Ray tasks: on the Ray cluster at ``ray_address``, or on a
    local Ray started for the dump; the files are the same, byte for byte."""
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
    if "coco" in formats and "rgb" not in formats:
        raise ValueError("--formats: coco annotates the rgb files; add rgb")
    if not 1 <= workers <= frames:
        raise ValueError(f"--workers must be between 1 and the number of frames ({frames}), not {workers}")
    if engine not in ENGINES:
        raise ValueError(f"--engine must be one of {', '.join(ENGINES)}, not {engine!r}")
    if ray_address is not None and engine != "ray":
        raise ValueError("--ray-address applies to --engine ray")
    if engine == "ray":
        if workers < 2:
            raise ValueError("--engine ray runs the shards of --workers 2 or more as Ray tasks")
        try:
            import ray  # noqa: F401
        except ImportError:
            raise ValueError(f"--engine ray needs Ray, which is not installed: {RAY_INSTALL}") from None
    if env is not None and camera_full:
        raise ValueError("--camera-full applies to controller dumps; environments render their own layer")
    if env is not None and (ball is not None or pose is not None):
        raise ValueError("--ball and --pose apply to controller dumps; environments place the robot and ball themselves")
    if env is not None:
        _check_env(env)
    source_sha256 = None
    if controller is not None:
        controller = Path(controller).resolve()
        source_sha256 = controller_sha256(controller)
    out = Path(out).resolve()
    parameters = {"controller": controller and str(controller), "env": env, "policy": env and policy,
                  "frames": frames, "backend": backend, "scene": scene and str(Path(scene).resolve()), "seed": seed,
                  "pose": pose and list(pose), "ball": ball and list(ball),
                  "formats": [f for f in FORMATS if f in formats], "camera_full": camera_full,
                  "camera_profile": camera_profile, "camera_settings": (camera_settings or CameraSettings()).as_dict()}
    if source_sha256 is not None:
        parameters["controller_sha256"] = source_sha256  # a resume refuses another controller
    parameters["model_sha256"] = model_sha256(scene)
    if workers == 1:
        return _dump_one(parameters, out, resume)
    if engine == "local":
        return _dump_sharded(parameters, out, resume, workers, engine)
    with _ray_session(ray_address):  # before the folder is touched: a Ray that cannot start changes nothing
        return _dump_sharded(parameters, out, resume, workers, engine)


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


class _ShardProgress(Progress):
    """A sharded dump's progress: the frames its shards have listed, counted in what their
    frames.jsonl files gained since the last ``poll``."""

    def __init__(self, folders: list[Path], frames: int):
        super().__init__(frames / FRAME_RATE_HZ)
        self.offsets, self.frames = dict.fromkeys(folders, 0), 0

    def poll(self) -> None:
        if not self.enabled:
            return
        for folder, offset in self.offsets.items():
            with contextlib.suppress(OSError), open(folder / LINES, "rb") as file:
                file.seek(offset)
                data = file.read()
                self.frames += data.count(b"\n")
                self.offsets[folder] = offset + len(data)
        self.update(self.frames / FRAME_RATE_HZ, self.frames)


def _remove_temporary_files(shards: list[tuple[dict, Path]]) -> None:
    """The temporary files of stopped shards."""
    for parameters, folder in shards:
        remove_temporary_files(folder, {f: {"path": PATHS[f]} for f in parameters["formats"]})


def _run_shards(shards: list[tuple[dict, Path]], resume: bool, progress: _ShardProgress) -> list[DumpSummary]:
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
            progress.poll()
            for receive in connection.wait(list(pending), PROGRESS_POLL_S):
                k = pending.pop(receive)
                try:
                    status, value = receive.recv()
                except EOFError:
                    processes[k].join()
                    raise DumpError(f"{shards[k][1]}: its worker process ended without a result "
                                    f"(exit status {processes[k].exitcode}); continue with --resume") from None
                if status == "error":
                    raise _in_shard(value, shards[k][1])
                results[k] = value
        return results
    finally:
        stopped = [p for p in processes if p.is_alive()]
        _stop(processes)
        if stopped:
            _remove_temporary_files(shards)


def _in_shard(error: BaseException, folder: Path) -> BaseException:
    """``error`` of a shard, its message led by the shard's folder name (same type and
    attributes: the exit status stays); as it is when its type cannot be made from a message."""
    if str(error).startswith(str(folder)):
        return error
    try:
        named = type(error)(f"{folder.name}: {error}")
    except Exception:
        return error
    named.__dict__.update(error.__dict__)
    return named.with_traceback(error.__traceback__)


def _ray_shard(parameters: dict, folder: Path, command: str) -> DumpSummary:
    """A Ray task's body: one shard, resumed (a retried task finds its lost attempt's frames)."""
    return _dump_one(parameters, folder, True, lock_wait_s=SHARD_LOCK_WAIT_S, command=command)


@contextlib.contextmanager
def _ray_session(address: str | None):
    """Ray for a dump: the cluster at ``address`` or a local Ray, stopped after the dump, unless
    this process is connected to one already."""
    import ray

    host, _, port = (address or "").removeprefix("ray://").rpartition(":")
    if host and port.isdigit():
        try:
            socket.create_connection((host, int(port)), RAY_CONNECT_S).close()
        except OSError as exc:
            raise ValueError(f"--ray-address {address}: no Ray cluster answers there ({exc.strerror or exc})") from None
    started = not ray.is_initialized()
    if started:
        try:
            ray.init(address=address, include_dashboard=False, logging_level="warning")
        except Exception as exc:  # Ray's own exception types, by version
            where = f"--ray-address {address}" if address else "--engine ray"
            raise ValueError(f"{where}: cannot start or reach Ray ({str(exc).splitlines()[0]})") from None
    try:
        yield
    finally:
        if started:
            ray.shutdown()


def _run_ray_shards(shards: list[tuple[dict, Path]], progress: _ShardProgress) -> list[DumpSummary]:
    """Each shard as a Ray task (retried when its worker is lost); the first failure cancels
    the others and is raised."""
    import ray

    task = ray.remote(num_cpus=1, max_retries=RAY_MAX_RETRIES)(_ray_shard)
    command = command_line()
    pending = {task.remote(parameters, folder, f"{command} (Ray task: {folder.name})"): k
               for k, (parameters, folder) in enumerate(shards)}
    results = [None] * len(shards)
    try:
        while pending:
            progress.poll()
            for ref in ray.wait(list(pending), timeout=PROGRESS_POLL_S)[0]:
                k = pending.pop(ref)
                folder = shards[k][1]
                try:
                    results[k] = ray.get(ref)
                except ray.exceptions.RayTaskError as exc:  # the shard's own error, as the local engine raises it
                    raise _in_shard(exc.cause, folder) if exc.cause is not None else DumpError(f"{folder}: {exc}") from None
                except ray.exceptions.RayError as exc:
                    raise DumpError(f"{folder}: its Ray task was lost ({type(exc).__name__}) {RAY_MAX_RETRIES + 1} "
                                    "times; continue with --resume") from None
        return results
    finally:
        for ref in pending:
            ray.cancel(ref, force=True)
        if pending:
            ray.wait(list(pending), num_returns=len(pending), timeout=WORKER_STOP_S)
            _remove_temporary_files(shards)


def _dump_sharded(parameters: dict, out: Path, resume: bool, workers: int, engine: str) -> DumpSummary:
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
        progress = _ShardProgress([folder for _, folder in shards], parameters["frames"])
        try:
            results = _run_ray_shards(shards, progress) if engine == "ray" else _run_shards(shards, resume, progress)
        finally:
            progress.close()
        if "coco" in parameters["formats"]:
            write_atomic(out / COCO, coco_bytes(out, [folder for _, folder in shards]))
    finally:
        prepared.lock.release()
    return DumpSummary(str(out), sum(r.frames for r in results), sum(r.new_frames for r in results),
                       sum(r.bytes_written for r in results), time.perf_counter() - start,
                       sum(r.repaired_frames for r in results))
