"""A match's dump, sharded by robot: ``dump(out, robots=...)`` (``aibo-sim dump CONTROLLER --robots
FILE``, or ``--robot ...``) runs the match (``aibo_sim.match.run_match``: every robot's controller in its
own thread, the world stepped in lockstep) and writes each robot's camera frames, as a dump of one
robot writes them, to ``out/robotN/`` (N: the robot's place in the robots' list, from 1). Those are
the dump's shards (``out/meta.json``'s ``"shards"``, as ``--workers`` writes them): ``load_dump(out)``
reads robot 1's frames, then robot 2's, ...; ``out/coco.json`` lists every robot's.

Each robot's meta.json records its spec (``"parameters"."robot"``: team, number, pose, controller) and
the match (``"robots"``: ``formats.robots_meta``, the observer that robot); the robots' controllers
run in ``out/controller_files/`` (``run --out`` of a match is theirs, so it is here: one folder).
``--resume`` runs the match again from the start (deterministic for a seed) and writes what is missing.
"""

from __future__ import annotations

import contextlib
import os
import time
from dataclasses import replace
from pathlib import Path

from openr_bridge import FRAME_RATE_HZ
from openr_bridge.memory_stick import memory_stick_folder

from ..camera import describe_camera, scene_light
from ..config import DEFAULT_DURATION_S, CameraConfig, WorldConfig, configs
from ..files import make_folder
from ..match import controller_named_as_given, refuse_single_robot_options, robot_folder, run_match
from ..placement import out_path, place_match
from ..render import check_rendering
from ..robot import SimulationEnd
from ..runner import MEMORY_STICK, Progress
from ..sim import Simulation, load_model
from ..team import check_controllers, check_robots
from .coco import coco_bytes
from .formats import DUMP_FORMAT, robots_meta
from .running import _CameraFrames, check_formats, controller_sha256, recorded_parameters, world_parameters
from .writing import COCO, CONTROLLER_FILES, DumpSummary, DumpWriter, check_destination, prepare_folder, write_atomic


class _RobotFrames(_CameraFrames):
    """A match robot's frame listener, in its controller's thread: its camera frames to its writer
    (the robots' at once: what changes the shared model holds the world's render lock). A failure
    stops every robot."""

    def __call__(self, program) -> None:
        try:
            super().__call__(program)
        except SimulationEnd:
            if self.error is not None and program.sim.world.lockstep is not None:
                program.sim.world.lockstep.stop()  # the other robots end at their next step
            raise


def _refuse(env, workers, pose, backend, mtn_mode, memory_stick, policy, engine, ray_address) -> None:
    """ValueError for an option that a match's dump does not take, saying why."""
    if env is not None:
        raise ValueError(
            "--robots and --robot dump a match of controllers, --env an environment (whose robots it makes "
            "itself): give one of them"
        )
    if workers != 1:
        raise ValueError(
            f"--workers {workers} applies to a dump of one robot: a match's robots share one world, stepped "
            "together in one process; its dump is sharded by robot instead (robot1/, robot2/, ...)"
        )
    if engine != "local" or ray_address is not None:
        raise ValueError("--engine and --ray-address apply to --workers shards: a match's dump runs in one process")
    values = {"--pose": pose, "--backend": backend, "--mtn-mode": mtn_mode, "--memory-stick": memory_stick}
    refuse_single_robot_options("dump", values)
    if policy is not None:
        raise ValueError("--policy applies to --env dumps: a controller chooses its own actions")


def _controllers(robots, controller) -> tuple:
    """``robots`` with each one's controller resolved (the dump's ``controller`` where it names none)."""
    check_controllers(robots, controller, "dump")
    return tuple(replace(r, controller=str(Path(r.controller or controller).resolve())) for r in robots)


def _check_places(scene, robots, ball, ball_type: str) -> None:
    """The ball where it can go and the robots apart, before any folder is made (``run_match``
    checks them again, as it does for a run)."""
    sim = Simulation(scene, camera=CameraConfig("ideal"), ball_type=ball_type, robots=robots)
    try:
        place_match(sim, ball)
    finally:
        sim.close()


def dump_match(
    out,
    robots,
    *,
    controller=None,
    frames: int = round(DEFAULT_DURATION_S * FRAME_RATE_HZ),
    world: WorldConfig | None = None,
    camera: CameraConfig | None = None,
    formats=(),
    resume: bool = False,
    env=None,
    workers: int = 1,
    backend=None,
    mtn_mode=None,
    memory_stick=None,
    policy=None,
    engine: str = "local",
    ray_address=None,
) -> DumpSummary:
    """``dump(out, robots=...)``: the match of ``robots`` (``team.RobotSpec``s; each runs its own
    controller, or ``controller``) for ``frames`` camera frames, one dump per robot in
    ``out/robotN``. Everything is checked before a folder is made: the options a match does not take
    (ValueError saying why), the robots (TeamError), the controllers (compiled), the places."""
    world, camera = configs(world, camera)
    scene, ball, ball_type = world.scene, world.ball, world.ball_type
    _refuse(env, workers, world.pose, backend, mtn_mode, memory_stick, policy, engine, ray_address)
    robots = check_robots(robots, "--robots")
    robots = _controllers(robots, controller)
    check_formats(formats)
    model = load_model(scene, ball_type=ball_type, robots=robots)
    check_rendering(model)
    _check_places(scene, robots, ball, ball_type)
    hashes = {}
    for robot in robots:
        if robot.controller not in hashes:
            with controller_named_as_given(robot):
                hashes[robot.controller] = controller_sha256(Path(robot.controller))
    out = out_path(out)
    recorded = world_parameters(frames, world, camera, formats, model)
    match = {"controller": controller and str(Path(controller).resolve()), "robots": [r.as_dict() for r in robots]}
    shards = [robot_folder(k) for k in range(len(robots))]
    meta = {"format": DUMP_FORMAT, "parameters": recorded_parameters(recorded, match), "shards": shards}
    described = describe_camera(camera.profile, camera.settings, camera.size, scene_light(model))
    start = time.perf_counter()
    prepared = prepare_folder(out, meta, resume)
    writers: list[DumpWriter] = []
    try:
        for shard in shards:
            check_destination(out / shard, shard_of=out)
        for k, robot in enumerate(robots):
            stick = memory_stick_folder(robot.controller) is not None
            run = {
                "controller": robot.controller,
                "env": None,
                "policy": None,
                "backend": MEMORY_STICK if stick else "sim",
                "pose": list(robot.pose),
                "mtn_mode": None if stick else "openr",
                "memory_stick": None,
                "robot": robot.as_dict(),
                "controller_sha256": hashes[robot.controller],
            }
            parameters = recorded_parameters(recorded, run)
            writers.append(
                DumpWriter(
                    out / shards[k],
                    parameters["formats"],
                    parameters,
                    resume=resume,
                    camera=described,
                    model=model,
                    robots=robots_meta(robots, k + 1),
                )
            )
        _run(out, robots, writers, frames, replace(world, scene=recorded["scene"]), camera)
        coco = coco_bytes(out, [out / shard for shard in shards]) if "coco" in recorded["formats"] else b""
        if coco:
            write_atomic(out / COCO, coco)
    except BaseException:
        for writer in writers:
            with contextlib.suppress(Exception):
                writer.abort()  # complete frames stay, temporary files go
        raise
    finally:
        prepared.lock.release()
    return DumpSummary(
        str(out),
        sum(len(w.complete) for w in writers),
        sum(w.new_frames for w in writers),
        sum(w.bytes_written for w in writers) + len(coco),
        time.perf_counter() - start,
        sum(w.repaired_frames for w in writers),
    )


def _run(out: Path, robots, writers, frames: int, world: WorldConfig, camera: CameraConfig) -> None:
    """The match, each robot's frames into its writer, then the writers finished (their videos and
    coco.json). The controllers run in ``out/controller_files`` (``world``'s scene: a whole path)."""
    workdir = out / CONTROLLER_FILES
    try:
        make_folder(workdir)
    except NotADirectoryError:
        raise ValueError(f"{workdir}: not a folder (the controllers run in it): move it away, then --resume") from None
    progress = Progress(frames / FRAME_RATE_HZ)
    listeners: list[_RobotFrames] = []

    def robot_listeners(robot: Simulation) -> list:
        shown = progress if robot.index == 0 else Progress(frames / FRAME_RATE_HZ, enabled=False)
        listeners.append(_RobotFrames(writers[robot.index], frames, shown))
        return [listeners[-1]]

    previous = Path.cwd()
    os.chdir(workdir)  # the controllers' own files land there
    try:
        try:
            run_match(
                robots,
                duration=frames / FRAME_RATE_HZ,
                world=world,
                camera=camera,
                robot_listeners=robot_listeners,
                progress=False,
            )
        except BaseException:
            failed = next((listener.error for listener in listeners if listener.error is not None), None)
            if failed is not None:  # a write failed: that is why the match stopped
                raise failed from None
            raise
        failed = next((listener.error for listener in listeners if listener.error is not None), None)
        if failed is not None:
            raise failed
    finally:
        os.chdir(previous)
        progress.close()
    for writer in writers:
        writer.finish()
