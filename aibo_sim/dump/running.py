"""Running a dump: a controller run or an environment run into a ``DumpWriter``; ``dump``
checks the arguments and hands shards to ``shards.py``."""

from __future__ import annotations

import contextlib
import hashlib
import time
from collections.abc import Iterable
from pathlib import Path

import gymnasium
import mujoco
import numpy as np

import openr_bridge
from openr_bridge import FRAME_RATE_HZ
from openr_bridge.config import find_in_stick
from openr_bridge.memory_stick import load_memory_stick, memory_stick_folder

from ..camera import CameraProfile, CameraSettings, camera_size, describe_camera, scene_light
from ..camera import camera_profile as resolve_profile  # dump's argument of that name shadows it
from ..cbind.build import compile_controller, controller_sources, is_c_controller, own_files
from ..config import DEFAULT_DURATION_S, CameraConfig, ParameterError, WorldConfig, configs
from ..field import DEFAULT_BALL_TYPE
from ..files import make_folder
from ..mtn import MODES as MTN_MODES
from ..placement import check_place, checked_out_path
from ..render import check_rendering
from ..robot import BACKENDS, SimulationEnd, check_memory_stick, whole_ms
from ..runner import MEMORY_STICK, Progress, check_python_controller, refuse_controller_options, run_controller
from ..sim import ModelError, ball_joint, is_seed, load_model
from .formats import DEFAULT_FORMATS, FORMATS, DumpError, is_match, robots_meta
from .shards import dump_sharded, ray_session, shard_balls
from .writing import CONTROLLER_FILES, DumpSummary, DumpWriter

POLICIES = ("random", "scripted", "zero")
# A local worker's memory, with a margin: ~135 MB of its own measured (a controller dump, 208x160,
# default formats; its libraries' pages are shared).
WORKER_MEMORY_MB = 200
ENGINES = ("local", "ray")
RAY_INSTALL = "pip install 'aibo-sim[ray]'"
SCRIPTED_SWEEP_HZ = 0.25


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


def _profile(parameters: dict) -> CameraProfile:
    """The dump's camera profile: its name, and its options where it differs from the preset."""
    return resolve_profile(parameters["camera_profile"], parameters.get("camera_profile_options"))


def _dump_controller(parameters: dict, out: Path, resume: bool, **lock) -> DumpWriter:
    frames, camera_full = parameters["frames"], parameters["camera_full"]
    settings = CameraSettings(**parameters["camera_settings"])
    model, profile = (
        load_model(parameters["scene"], ball_type=parameters.get("ball_type", DEFAULT_BALL_TYPE)),
        _profile(parameters),
    )
    camera = describe_camera(profile, settings, camera_size(camera_full), scene_light(model))
    progress = Progress(frames / FRAME_RATE_HZ, enabled=parameters.get("progress", True))
    with DumpWriter(
        out, parameters["formats"], parameters, resume=resume, camera=camera, model=model, **lock
    ) as writer:
        listener = _CameraFrames(writer, frames, progress)
        workdir = out / CONTROLLER_FILES  # the controller's own files: one folder per shard
        try:
            try:
                make_folder(workdir)
            except NotADirectoryError:
                raise DumpError(
                    f"{workdir}: not a folder (the controller runs in it): move it away, then --resume"
                ) from None
            run_controller(
                parameters["controller"],
                backend=parameters["backend"],
                duration=frames / FRAME_RATE_HZ,
                world=WorldConfig(
                    parameters["scene"],
                    parameters["seed"],
                    parameters["pose"],
                    parameters["ball"],
                    parameters.get("ball_type", DEFAULT_BALL_TYPE),
                ),
                camera=CameraConfig(profile, camera_full, settings),
                mtn_mode=parameters["mtn_mode"],
                memory_stick=parameters["memory_stick"],
                frame_listeners=[listener],
                progress=False,
                workdir=workdir,
            )
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
        env = gymnasium.make(
            parameters["env"],
            camera=camera,
            scene=parameters["scene"],
            camera_profile=_profile(parameters),
            camera_wb=settings["white_balance"],
            camera_gain=settings["gain"],
            camera_shutter=settings["shutter"],
        )
    except gymnasium.error.Error as exc:
        raise ValueError(f"environment {parameters['env']!r}: {exc}") from None
    steps, seed = parameters["frames"], parameters["seed"]
    progress = Progress(steps / FRAME_RATE_HZ, enabled=parameters.get("progress", True))
    try:
        sim = env.unwrapped.sim  # the learner's robot: in a match env, one of several
        specs = sim.world.robot_specs
        with DumpWriter(
            out,
            parameters["formats"],
            parameters,
            resume=resume,
            camera=sim.camera.describe(),
            model=sim.model,
            robots=robots_meta(specs, sim.index + 1) if is_match(specs) else None,
            **lock,
        ) as writer:
            policy = _policy(parameters["policy"], env.action_space, seed)
            env.reset(seed=seed)
            index, episode = 0, 0
            writer.write(sim, index, {"episode": episode, "action": None, "reward": None})
            for step in range(steps):
                action = policy(step)
                _, reward, terminated, truncated, _ = env.step(action)
                index += 1
                writer.write(
                    sim, index, {"episode": episode, "action": np.asarray(action).tolist(), "reward": float(reward)}
                )
                if (terminated or truncated) and step + 1 < steps:
                    env.reset()
                    index, episode = index + 1, episode + 1
                    writer.write(sim, index, {"episode": episode, "action": None, "reward": None})
                progress.update((step + 1) / FRAME_RATE_HZ, index + 1)
    finally:
        progress.close()
        env.close()
    return writer


PARAMETER_ORDER = (  # meta.json's "parameters", in this order: a dump's file reads the same run after run
    "controller",
    "robots",
    "env",
    "policy",
    "frames",
    "backend",
    "scene",
    "seed",
    "pose",
    "ball",
    "mtn_mode",
    "memory_stick",
    "robot",
    "formats",
    "camera_full",
    "camera_profile",
    "camera_settings",
    "ball_type",
    "camera_profile_options",
    "controller_sha256",
    "model_sha256",
)


def world_parameters(frames: int, world: WorldConfig, camera: CameraConfig, formats, model) -> dict:
    """What every dump records of its world and camera (a single robot's, each robot's of a match):
    frames, scene, seed, ball, its type (not the default's), formats, camera (its profile's
    options where it has any) and the model's hash."""
    recorded = {
        "frames": frames,
        "scene": world.scene and str(Path(world.scene).resolve()),
        "seed": world.seed,
        "ball": world.ball and list(world.ball),
        "formats": [f for f in FORMATS if f in formats],
        "camera_full": camera.full,
        "camera_profile": camera.profile.name,
        "camera_settings": camera.settings.as_dict(),
        "model_sha256": model_sha256(model),
    }
    if world.ball_type != DEFAULT_BALL_TYPE:  # only then: a dump resumes one made before the pink ball existed
        recorded["ball_type"] = world.ball_type
    if camera.profile.options():  # only then: a dump of a preset resumes one made before options were recorded
        recorded["camera_profile_options"] = camera.profile.options()
    return recorded


def recorded_parameters(*parts: dict) -> dict:
    """``parts`` merged in ``PARAMETER_ORDER`` (the world's, the run's: meta.json's "parameters")."""
    merged = {key: value for part in parts for key, value in part.items()}
    if unknown := merged.keys() - set(PARAMETER_ORDER):
        raise KeyError(f"parameters without a place in PARAMETER_ORDER: {sorted(unknown)}")
    return {key: merged[key] for key in PARAMETER_ORDER if key in merged}


def dump_one(parameters: dict, out: Path, resume: bool, **lock) -> DumpSummary:
    """Dump one folder (a whole dump, or one shard) as ``parameters`` say; returns its summary.

    :param resume: keep the frames already complete in ``out`` and write the rest.
    :param lock: ``lock_wait_s`` and ``command``, for ``DumpWriter``'s lock on ``out``.
    """
    start = time.perf_counter()
    run = _dump_env if parameters["env"] else _dump_controller
    writer = run(parameters, out, resume, **lock)
    return DumpSummary(
        str(out),
        len(writer.complete),
        writer.new_frames,
        writer.bytes_written,
        time.perf_counter() - start,
        writer.repaired_frames,
    )


def available_memory_mb() -> float | None:
    """The memory new processes can take, in MiB: Linux's MemAvailable, within this process's
    cgroup limit (a container's); None where neither can be read."""
    values = []
    with contextlib.suppress(OSError, ValueError, IndexError):
        meminfo = Path("/proc/meminfo").read_text()
        values.append(int(meminfo.split("MemAvailable:")[1].split()[0]) / 1024)
    with contextlib.suppress(OSError, ValueError, IndexError):
        group = Path("/sys/fs/cgroup") / Path("/proc/self/cgroup").read_text().split("0::/")[1].split("\n")[0]
        limit = (group / "memory.max").read_text().strip()
        if limit != "max":
            values.append((int(limit) - int((group / "memory.current").read_text())) / 2**20)
    return min(values) if values else None


def _check_env(env_id: str) -> None:
    """ValueError unless ``env_id`` is an aibo_sim environment (a dump renders its head camera)."""
    from ..envs import ENV_SPECS

    try:
        spec = gymnasium.spec(env_id)
    except gymnasium.error.Error as exc:
        raise ValueError(f"environment {env_id!r}: {exc}") from None
    entry = spec.entry_point if isinstance(spec.entry_point, str) else getattr(spec.entry_point, "__module__", "")
    if not str(entry).startswith("aibo_sim."):
        raise ValueError(
            f"environment {env_id!r} is not an aibo_sim environment; a dump needs the robot's camera "
            f"({', '.join(ENV_SPECS)})"
        )


def file_sha256(path: Path) -> str:
    """The SHA-256 of the file at ``path``, in hex."""
    digest = hashlib.sha256()
    with open(path, "rb") as file:
        for block in iter(lambda: file.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def model_sha256(model: mujoco.MjModel) -> str:
    """The hash of the compiled scene (the robot, the field, their physics and looks): a resume
    refuses a scene or an aibo-sim whose model changed since the dump began."""
    saved = np.zeros(mujoco.mj_sizeModel(model), np.uint8)
    mujoco.mj_saveModel(model, None, saved)
    return hashlib.sha256(saved.tobytes()).hexdigest()


def controller_sha256(path: Path) -> str:
    """The hash of a controller: its file's, or for a C or C++ controller with several sources or
    headers of its own (``cbind.build.own_files``), that of their names and hashes (compiled first: a
    syntax or compile error stops the dump at once); for a memory stick, that of its configuration
    files and objects (each read and checked first)."""
    if memory_stick_folder(path) is not None:
        stick = load_memory_stick(memory_stick_folder(path))
        files = [stick.object_cfg, *(o.file for o in stick.objects)]
        stick.check_objects()
        for name in ("CONNECT.CFG", "DESIGNDB.CFG"):
            with contextlib.suppress(openr_bridge.ConfigError):
                files.append(find_in_stick(stick.root, name))
        return hashlib.sha256(
            "".join(f"{f.relative_to(stick.root)}\0{file_sha256(f)}\0" for f in files).encode()
        ).hexdigest()
    if not is_c_controller(path):
        check_python_controller(path)
        return file_sha256(path)
    compile_controller(path)
    main, sources = controller_sources(path)
    files = own_files(main, sources)
    if sources == [path] and len(files) == 1:
        return file_sha256(path)
    return hashlib.sha256("".join(f"{name}\0{file_sha256(f)}\0" for name, f in files).encode()).hexdigest()


def check_formats(formats) -> None:
    """ValueError for no formats, an unknown one, or coco without the rgb files it annotates."""
    if isinstance(formats, (str, bytes)) or not isinstance(formats, Iterable):
        raise ParameterError.at("formats", repr(formats), f"a sequence of format names; known: {', '.join(FORMATS)}")
    unknown = sorted(set(formats) - set(FORMATS))
    if unknown or not formats:
        raise ParameterError.at(
            "formats",
            ",".join(map(str, formats)) or "''",
            f"unknown {unknown or '(none given)'}; known: {', '.join(FORMATS)}",
        )
    if "coco" in formats and "rgb" not in formats:
        raise ParameterError.at("formats", ",".join(formats), "coco annotates the rgb files; add rgb")


def dump(
    out,
    *,
    controller: str | Path | None = None,
    env: str | None = None,
    policy: str | None = None,
    frames: int = round(DEFAULT_DURATION_S * FRAME_RATE_HZ),
    backend: str | None = None,
    world: WorldConfig | None = None,
    camera: CameraConfig | None = None,
    formats=DEFAULT_FORMATS,
    resume: bool = False,
    workers: int = 1,
    engine: str = "local",
    ray_address: str | None = None,
    mtn_mode: str | None = None,
    memory_stick: str | Path | None = None,
    robots=None,
) -> DumpSummary:
    """Dump a controller run (``frames`` camera frames) or an env run (``frames`` steps of
    ``policy``, default random) to ``out``, in ``world`` (scene, seed: shard k of ``workers``
    takes seed + k, the robot's pose, the ball) with the head camera ``camera``;
    ``world.pose`` (x, y, yaw in degrees), ``world.ball``, ``mtn_mode`` (default openr) and ``memory_stick``
    apply to controller dumps, as to ``run_controller`` (a memory stick takes none of ``backend``,
    ``mtn_mode`` and ``memory_stick``); the controller runs in
    ``out/controller_files`` (a shard's own). ``engine="ray"``
    runs the ``workers`` shards as Ray tasks: on the Ray cluster at ``ray_address``, or on a
    local Ray started for the dump; the files are the same, byte for byte.

    ``robots`` (``team.RobotSpec``s): a match, each robot running its spec's controller or
    ``controller``, dumped one robot a shard (``out/robot1``, ...: ``match.dump_match``)."""
    world, camera = configs(world, camera)
    count, shards = whole_ms(frames), whole_ms(workers)  # whole numbers (not bools, nor 2.5), else None
    if count is None or count < 1:
        raise ValueError(f"the number of frames (or steps) must be a whole number of at least 1, not {frames!r}")
    if shards is None or not 1 <= shards <= count:
        raise ParameterError.at(
            "workers", repr(workers), f"must be a whole number from 1 to the number of frames ({count})"
        )
    frames, workers = count, shards
    if robots is not None:
        from .match import dump_match  # it imports this module

        return dump_match(
            out,
            robots,
            controller=controller,
            frames=frames,
            world=world,
            camera=camera,
            formats=formats,
            resume=resume,
            env=env,
            workers=workers,
            backend=backend,
            mtn_mode=mtn_mode,
            memory_stick=memory_stick,
            policy=policy,
            engine=engine,
            ray_address=ray_address,
        )
    scene, seed, pose, ball, ball_type = world.scene, world.seed, world.pose, world.ball, world.ball_type
    if (controller is None) == (env is None):
        raise ValueError("dump a controller file or an environment (--env), not both or neither")
    check_formats(formats)
    if controller is not None and memory_stick_folder(controller) is not None:
        refuse_controller_options(controller, backend, mtn_mode, memory_stick)
        backend = MEMORY_STICK
    backend = backend or "sim"
    if backend not in (*BACKENDS, MEMORY_STICK):
        raise ValueError(f"backend must be one of {BACKENDS}, not {backend!r}")
    if policy is not None and controller is not None:
        raise ValueError("--policy applies to --env dumps: a controller chooses its own actions")
    policy = policy or "random"
    if policy not in POLICIES:
        raise ValueError(f"policy must be one of {POLICIES}, not {policy!r}")
    available = available_memory_mb() if engine == "local" and workers > 1 else None
    if available is not None and workers * WORKER_MEMORY_MB > available:
        raise ValueError(
            f"--workers {workers}: this machine has memory for {int(available // WORKER_MEMORY_MB)} "
            f"workers ({available / 1024:.1f} GB available, about {WORKER_MEMORY_MB} MB a worker)"
        )
    if not is_seed(seed, workers):
        shards = f" with {workers} workers (shard k uses seed + k)" if workers > 1 else ""
        raise ParameterError.at("seed", repr(seed), f"must be a whole number from 0 to 2**64 - {workers}{shards}")
    if engine not in ENGINES:
        raise ParameterError.at("engine", repr(engine), f"must be one of {', '.join(ENGINES)}")
    if ray_address is not None and engine != "ray":
        raise ValueError("--ray-address applies to --engine ray")
    if engine == "ray":
        if workers < 2:
            raise ValueError("--engine ray runs the shards of --workers 2 or more as Ray tasks")
        try:
            import ray  # noqa: F401
        except ImportError:
            raise ValueError(f"--engine ray needs Ray, which is not installed: {RAY_INSTALL}") from None
    if env is not None and camera.full:
        raise ValueError("--camera-full applies to controller dumps; environments render their own layer")
    if env is not None and (ball is not None or pose is not None or ball_type != DEFAULT_BALL_TYPE):
        raise ValueError(
            "--ball, --ball-type and --pose apply to controller dumps; environments place the robot and "
            "their own ball themselves"
        )
    if env is not None and (mtn_mode is not None or memory_stick is not None):
        raise ValueError("--mtn-mode and --memory-stick apply to controller dumps, not to --env")
    if mtn_mode is not None and mtn_mode not in MTN_MODES:
        raise ParameterError.at("mtn_mode", repr(mtn_mode), f"must be one of {', '.join(MTN_MODES)}")
    check_memory_stick(backend, memory_stick)
    if memory_stick is not None:
        memory_stick = Path(memory_stick).resolve()
        openr_bridge.OpenRSystem.from_memory_stick(memory_stick)  # a ConfigError naming it, before the folder is made
    if env is not None:
        _check_env(env)
    model = load_model(scene, ball_type=ball_type)
    check_rendering(model)
    try:
        ball_joint(model)
        placeable_ball = True
    except ModelError as exc:
        if env is not None:  # the environments place the ball at each reset
            raise ModelError(f"--scene {scene}: environment {env} places the ball, but {exc}") from None
        placeable_ball = False
    if controller is not None:
        check_place(
            scene, pose, ball, ball_type
        )  # the scene's ModelError, or a start's ValueError, before the folder is made
    source_sha256 = None
    if controller is not None:
        controller = Path(controller).resolve()
        source_sha256 = controller_sha256(controller)
    out = checked_out_path(out)
    run = {
        "controller": controller and str(controller),
        "env": env,
        "policy": env and policy,
        "backend": backend,
        "pose": pose and list(pose),
        "mtn_mode": controller and backend != MEMORY_STICK and (mtn_mode or "openr") or None,
        "memory_stick": memory_stick and str(memory_stick),
    }
    if source_sha256 is not None:
        run["controller_sha256"] = source_sha256  # a resume refuses another controller
    parameters = recorded_parameters(world_parameters(frames, world, camera, formats, model), run)
    if workers == 1:
        return dump_one(parameters, out, resume)
    drawn = controller is not None and ball is None and placeable_ball  # each shard's ball drawn, checked now
    balls = shard_balls(world, workers) if drawn else [parameters["ball"]] * workers
    if engine == "local":
        return dump_sharded(dump_one, parameters, out, resume, workers, engine, balls)
    with ray_session(ray_address):  # before the folder is touched: a Ray that cannot start changes nothing
        return dump_sharded(dump_one, parameters, out, resume, workers, engine, balls)
