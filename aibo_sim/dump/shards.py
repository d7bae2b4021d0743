"""A dump in shards: worker processes that die with their parent (``engine="local"``) or Ray
tasks (``engine="ray"``), each shard a dump of its own folder, merged at the end. A shard is
dumped by the function ``dump_sharded`` is given (``running.dump_one``)."""

from __future__ import annotations

import contextlib
import math
import os
import signal
import socket
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from multiprocessing import connection, get_context
from pathlib import Path

import numpy as np

from openr_bridge import FRAME_RATE_HZ

from ..cbind.child import die_with_parent_thread
from ..config import CameraConfig, ParameterError, WorldConfig
from ..files import command_line, open_file
from ..placement import place
from ..runner import Progress
from ..sim import Simulation
from .coco import coco_bytes
from .formats import DUMP_FORMAT, PATHS, DumpError
from .reading import LINES
from .writing import COCO, DumpSummary, check_destination, prepare_folder, remove_temporary_files, write_atomic

DumpShard = Callable[..., DumpSummary]  # (parameters, folder, resume, lock_wait_s=, command=): one shard

RAY_MAX_RETRIES = 3  # a shard whose Ray worker is lost runs again (resuming its folder)
RAY_CONNECT_S = 5.0  # an --ray-address that does not answer in this is refused (ray.init would wait minutes)
PROGRESS_POLL_S = 0.5  # a sharded dump counts its shards' frames this often
SHARD_BALL_X, SHARD_BALL_Y = (0.3, 1.2), (-0.5, 0.5)  # metres: ahead of the robot's start
SHARD_BALL_DRAWS = 20  # draws of a shard's ball, each checked: one the scene cannot place is drawn again
PARENT_POLL_S = 0.5  # a worker's check that its parent still lives (where PR_SET_PDEATHSIG is missing)
SHARD_LOCK_WAIT_S = 5.0  # a shard's lock may still be held by a worker of a killed dump, dying
WORKER_STOP_S = 5.0  # SIGTERM, then SIGKILL after this


def die_with_parent(parent_pid: int) -> None:
    """Make this worker process end when ``parent_pid`` does, however it ends (SIGKILL too).

    Linux: ``child.die_with_parent_thread`` (``PR_SET_PDEATHSIG``: the parent's thread that
    started the worker is the one that waits for it); everywhere: a thread that ends the
    process once its parent is gone (it has been re-parented), checked every ``PARENT_POLL_S``.
    """
    die_with_parent_thread()
    if os.getppid() != parent_pid:  # the parent died before the line above
        os._exit(1)

    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(PARENT_POLL_S)
        os._exit(1)

    threading.Thread(target=watch, name="aibo-sim parent watchdog", daemon=True).start()


def _shard_worker(
    results, parent_pid: int, dump_shard: DumpShard, parameters: dict, out: Path, resume: bool, command: str
) -> None:
    """A worker process's body: one shard, its summary or exception sent back on ``results``."""
    die_with_parent(parent_pid)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C reaches the whole group: the parent stops us
    try:
        result = ("ok", dump_shard(parameters, out, resume, lock_wait_s=SHARD_LOCK_WAIT_S, command=command))
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
            with contextlib.suppress(OSError), open(open_file(folder / LINES, os.O_RDONLY), "rb") as file:
                file.seek(offset)
                data = file.read()
                self.frames += data.count(b"\n")
                self.offsets[folder] = offset + len(data)
        self.update(self.frames / FRAME_RATE_HZ, self.frames)


def _listed_frames(folder: Path) -> int:
    """How many frames the shard's frames.jsonl lists (0 before it has one)."""
    try:
        with open(open_file(folder / LINES, os.O_RDONLY), "rb") as file:
            return file.read().count(b"\n")
    except FileNotFoundError:
        return 0


def _remove_temporary_files(shards: list[tuple[dict, Path]]) -> None:
    """The temporary files of stopped shards."""
    for parameters, folder in shards:
        remove_temporary_files(folder, {f: {"path": PATHS[f]} for f in parameters["formats"]})


def _run_shards(
    dump_shard: DumpShard, shards: list[tuple[dict, Path]], resume: bool, progress: _ShardProgress
) -> list[DumpSummary]:
    """Each shard in its own spawned process; the first failure stops the others and is raised.
    However this returns (an exception, a signal turned into one), no worker outlives it."""
    context, parent, command = get_context("spawn"), os.getpid(), command_line()
    processes, pending, results = [], {}, [None] * len(shards)
    try:
        for k, (parameters, folder) in enumerate(shards):
            receive, send = context.Pipe(duplex=False)
            process = context.Process(
                target=_shard_worker,
                name=f"aibo-sim dump {folder.name}",
                daemon=True,
                args=(
                    send,
                    parent,
                    dump_shard,
                    parameters,
                    folder,
                    resume,
                    f"{command} (worker of pid {parent}: {folder.name})",
                ),
            )
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
                    raise DumpError(
                        f"{shards[k][1]}: its worker process ended without a result "
                        f"(exit status {processes[k].exitcode}); continue with --resume"
                    ) from None
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


def end_with_process(pid: int) -> None:
    """End this process (``os._exit(1)``) once process ``pid`` of this machine has ended, however
    it ended (SIGKILL too), checked every ``PARENT_POLL_S``."""

    def watch() -> None:
        while True:
            try:
                os.kill(pid, 0)
            except ProcessLookupError:
                os._exit(1)
            except PermissionError:  # alive, another user's
                pass
            time.sleep(PARENT_POLL_S)

    threading.Thread(target=watch, name="aibo-sim dump watchdog", daemon=True).start()


def _ray_shard(
    dump_shard: DumpShard, parameters: dict, folder: Path, command: str, dumper: tuple[str, int]
) -> DumpSummary:
    """A Ray task's body: one shard, resumed (a retried task finds its lost attempt's frames). On
    the machine of the dump's command (``dumper``: host name, process id), its worker ends with
    that command, as a local worker does: a killed dump's task wrote on into its folder."""
    if dumper[0] == socket.gethostname():
        end_with_process(dumper[1])
    return dump_shard(parameters, folder, True, lock_wait_s=SHARD_LOCK_WAIT_S, command=command)


@contextlib.contextmanager
def _stderr_kept_unless_failed():
    """What the code inside writes to file descriptor 2 (C++ code too), written there afterwards
    unless it raised: its error then says it in one line."""
    with tempfile.TemporaryFile() as kept:
        sys.stderr.flush()
        saved = os.dup(2)
        os.dup2(kept.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
        kept.seek(0)
        os.write(2, kept.read())


@contextlib.contextmanager
def ray_session(address: str | None):
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
        handlers = {number: signal.getsignal(number) for number in (signal.SIGTERM, signal.SIGINT)}

        def put_back_handlers():
            """This command's handlers, where Ray put its own (its SIGTERM exits at once) or, in
            ``ray.shutdown``, set SIGTERM's action to the default under Python's table of handlers."""
            if threading.current_thread() is threading.main_thread():
                for number, handler in handlers.items():
                    signal.signal(number, signal.SIG_DFL if handler is None else handler)

        try:
            with _stderr_kept_unless_failed():  # a refused connection: Ray's C++ client logs each retry
                ray.init(address=address, include_dashboard=False, logging_level="warning")
            put_back_handlers()
        except SystemExit as exc:  # Ray's SIGTERM handler, its first act in ray.init: sys.exit(SIGTERM)
            ray.shutdown()
            put_back_handlers()
            if exc.code == signal.SIGTERM:
                signal.raise_signal(signal.SIGTERM)  # to this command's handler: it stops as after any SIGTERM
            raise
        except Exception as exc:  # Ray's own exception types, by version
            where = f"--ray-address {address}" if address else "--engine ray"
            hint = (
                "; a cluster that authenticates with a token (`ray start`'s default since Ray 2.59) needs "
                "RAY_AUTH_MODE=token and its token here too"
                if address and os.environ.get("RAY_AUTH_MODE", "") != "token"
                else ""
            )
            raise ValueError(f"{where}: cannot start or reach Ray ({str(exc).splitlines()[0]}){hint}") from None
    try:
        yield
    finally:
        if started:
            ray.shutdown()
            put_back_handlers()


def _run_ray_shards(
    dump_shard: DumpShard, shards: list[tuple[dict, Path]], progress: _ShardProgress
) -> list[DumpSummary]:
    """Each shard as a Ray task (retried when its worker is lost); the first failure cancels
    the others and is raised."""
    import ray

    task = ray.remote(num_cpus=1, max_retries=RAY_MAX_RETRIES)(_ray_shard)
    command = command_line()
    dumper = socket.gethostname(), os.getpid()
    listed = [_listed_frames(folder) for _, folder in shards]  # a retried task counts only its own frames
    pending = {
        task.remote(dump_shard, parameters, folder, f"{command} (Ray task: {folder.name})", dumper): k
        for k, (parameters, folder) in enumerate(shards)
    }
    results = [None] * len(shards)
    try:
        while pending:
            progress.poll()
            for ref in ray.wait(list(pending), timeout=PROGRESS_POLL_S)[0]:
                k = pending.pop(ref)
                folder = shards[k][1]
                try:
                    result = ray.get(ref)
                    result.new_frames = max(result.new_frames, result.frames - listed[k])  # its lost attempts' too
                    results[k] = result
                except ray.exceptions.RayTaskError as exc:  # the shard's own error, as the local engine raises it
                    raise (
                        _in_shard(exc.cause, folder) if exc.cause is not None else DumpError(f"{folder}: {exc}")
                    ) from None
                except ray.exceptions.RayError as exc:
                    raise DumpError(
                        f"{folder}: its Ray task was lost ({type(exc).__name__}) {RAY_MAX_RETRIES + 1} "
                        "times; continue with --resume"
                    ) from None
        return results
    finally:
        for ref in pending:
            ray.cancel(ref, force=True)
        if pending:
            ray.wait(list(pending), num_returns=len(pending), timeout=WORKER_STOP_S)
            _remove_temporary_files(shards)


def shard_balls(world: WorldConfig, workers: int) -> list[list[float]]:
    """Each shard's ball, for a controller dump without one (``world.ball`` None) in a scene whose
    ball can be placed: drawn from the shard's seed (shard k: ``world.seed + k``) in
    ``SHARD_BALL_X/Y`` ahead of the robot (of ``world.pose``; without one, of the origin, the
    default field's start), again where it cannot be placed there (a wall, the robot, off the
    field), checked before the dump writes anything. A ValueError naming the shard where none of
    ``SHARD_BALL_DRAWS`` draws can be placed."""
    x, y, yaw = world.pose or (0.0, 0.0, 0.0)
    cos, sin = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    sim = Simulation(world.scene, camera=CameraConfig("ideal"), ball_type=world.ball_type)
    try:
        balls = []
        for k in range(workers):
            rng = np.random.default_rng(world.seed + k)
            for _ in range(SHARD_BALL_DRAWS):
                ahead, side = float(rng.uniform(*SHARD_BALL_X)), float(rng.uniform(*SHARD_BALL_Y))
                ball = [x + ahead * cos - side * sin, y + ahead * sin + side * cos]  # (ahead, side) at yaw 0
                try:
                    place(sim, world.pose, ball)
                    break
                except ParameterError:
                    continue
            else:
                raise ValueError(
                    f"shard_{k}: none of {SHARD_BALL_DRAWS} balls drawn from its seed {world.seed + k} ahead of the "
                    "robot can be placed in the scene: give --ball"
                )
            balls.append(ball)
        return balls
    finally:
        sim.close()


def dump_sharded(
    dump_shard: DumpShard, parameters: dict, out: Path, resume: bool, workers: int, engine: str, balls: list
) -> DumpSummary:
    """The dump as ``workers`` shards, each dumped by ``dump_shard``, shard k with ``balls[k]``
    (``shard_balls``, or the dump's ball)."""
    start = time.perf_counter()
    meta = {
        "format": DUMP_FORMAT,
        "parameters": {**parameters, "workers": workers},
        "shards": [f"shard_{k}" for k in range(workers)],
    }
    prepared = prepare_folder(out, meta, resume)
    try:
        shards = []
        for k in range(workers):
            seed = parameters["seed"] + k
            frames = parameters["frames"] // workers + (k < parameters["frames"] % workers)
            shard = {**parameters, "seed": seed, "ball": balls[k], "frames": frames, "progress": False}
            shards.append((shard, out / f"shard_{k}"))
            check_destination(out / f"shard_{k}", shard_of=out)
        progress = _ShardProgress([folder for _, folder in shards], parameters["frames"])
        try:
            results = (
                _run_ray_shards(dump_shard, shards, progress)
                if engine == "ray"
                else _run_shards(dump_shard, shards, resume, progress)
            )
        finally:
            progress.close()
        coco = coco_bytes(out, [folder for _, folder in shards]) if "coco" in parameters["formats"] else b""
        if coco:
            write_atomic(out / COCO, coco)
    finally:
        prepared.lock.release()
    return DumpSummary(
        str(out),
        sum(r.frames for r in results),
        sum(r.new_frames for r in results),
        sum(r.bytes_written for r in results) + len(coco),
        time.perf_counter() - start,
        sum(r.repaired_frames for r in results),
    )
