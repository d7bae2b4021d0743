"""Frame dumps: every head-camera frame of a headless run, in the formats vision code reads.

Usage::

    aibo-sim dump (CONTROLLER | --env ENV_ID [--policy random|scripted|zero]) --out DIR
                  [--duration S | --steps N] [--backend sim|openr]
                  [--scene FILE] [--pose X Y YAW_DEG] [--ball X Y] [--seed N]
                  [--camera-profile ers7|ideal] [--camera-wb W] [--camera-gain G] [--camera-shutter S]
                  [--formats rgb,yuv444,yuv420,annex,openr,bands,luma,depth,seg,mp4 | all]
                  [--camera-full] [--resume] [--workers N]

A controller dump holds camera frames 0 .. 30 S - 1 (``--steps N``: frames 0 .. N - 1); an
environment dump runs N ``env.step`` calls (``--duration S``: 30 S) and holds the frame of
every observation, each episode's reset frame included. Default formats: rgb, yuv420,
openr, mp4 (a viewable picture, a video tool's YUV, the robot's bytes, a video).

Layout of ``DIR`` (frame files are named by the frame's index in the dump, which for a
controller is the camera frame index, k / 30 s)::

    meta.json            run parameters, the camera (profile, settings, OpenCV intrinsics and
                         distortion), every file's path and layout
    frames.jsonl         one line per complete frame (see ``frame_metadata``)
    rgb/000123.png       8-bit RGB
    yuv444/000123.yuv    I444 planar: Y, then U (Cb), then V (Cr), each w x h
    yuv420/000123.yuv    I420 planar: Y (w x h), U, V (w/2 x h/2): ffmpeg -pix_fmt yuv420p
    annex/000123.yuv     the report's Annex I: bytes Y, U, V per pixel, row-major
    openr/000123.ofbk    the OFbkImageVectorData message, as bytes(message)
    bands/000123_H.raw   each layer's data as Sony's sample writes it: 6 w h bytes for
                         H, M, L (rows of Y, Cr, Cb, Y_LH, Y_HL, Y_HH), w h for C
    luma/000123.png      the 416x320 luma reconstructed from layer H (reconstruct_luma)
    depth/000123.npy     float32 metres along the optical axis, through the same lens
    seg/000123.png       uint8 class ids, names in meta.json (field.SEGMENTATION_CLASSES), same lens
    video.mp4            30 fps, codec mp4v (MPEG-4 part 2: OpenCV's wheels lack H.264)

Colour: the yuv444 and yuv420 files are BT.601 limited range (Y 16-235, Cb/Cr 16-240), what
ffmpeg, ffplay and OpenCV's ``COLOR_YUV2RGB_I420`` assume for raw yuv420p; 4:2:0 chroma is
the mean of each 2x2 block. The Annex I file uses the report's own formulas (Y = 0.299 R +
0.587 G + 0.114 B, U = 0.492 (B - Y) + 128, V = 0.5 (R - Y) + 128, truncated as C casts).
The OPEN-R message and bands hold Sony's YCrCb (Cr before Cb), as ``encode_frame`` makes it.
All are the head camera's frame (``aibo_sim.camera``: the picture exposed at the frame's tick,
the same frames ``aibo-sim run`` shows) and its one OPEN-R message; ``--backend`` only
chooses what the controller (or an environment, as ``camera="openr"``) sees.

Writes are atomic: each file is written under a ``.tmp.`` name and renamed, and a frame's
line goes into frames.jsonl after all its files. A frame is complete when its line is
there; readers see only complete frames. ``--resume`` re-runs the same simulation from the
start (it is deterministic for a seed), drops a partial last line, writes only frames that
are not complete and rebuilds video.mp4 from every frame.

``--workers N`` splits the frames into N shards run in parallel processes, written to
``DIR/shard_k/``; shard k uses seed ``seed + k`` and, in a controller dump without
``--ball``, a ball position drawn from that seed. ``load_dump`` reads a sharded dump as
the shards' frames one after the other.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from multiprocessing import get_context
from pathlib import Path

import cv2
import gymnasium
import mujoco
import numpy as np

import openr_bridge
from openr_bridge import FRAME_RATE_HZ
from openr_bridge.image import BAND_RUNS

from .camera import HEAD_CAMERA_GROUPS, CameraSettings, camera_size, describe_camera, scene_light_temperature
from .ers7 import JOINTS
from .field import SEGMENTATION_CLASSES
from .options import add_world_options, camera_options
from .robot import BACKENDS, SimulationEnd
from .runner import Progress, run_controller
from .sim import Simulation, load_model

FORMATS = ("rgb", "yuv444", "yuv420", "annex", "openr", "bands", "luma", "depth", "seg", "mp4")
DEFAULT_FORMATS = ("rgb", "yuv420", "openr", "mp4")
POLICIES = ("random", "scripted", "zero")
DUMP_FORMAT = "aibo-sim dump 1"

TEMP_PREFIX = ".tmp."
LAYERS = {name: layer for layer, name in enumerate(openr_bridge.LAYER_NAMES)}
# Geoms by name prefix (first match wins); unnamed geoms of the robot's bodies are "robot".
CLASS_PREFIXES = (("field_line", "line"), ("field", "field"), ("wall", "wall"), ("goal", "goal"),
                  ("beacon", "beacon"), ("ball", "ball"))
# Rows: Y, Cb, Cr from RGB / 255 (ITU-R BT.601, limited range), plus the offsets.
BT601_LIMITED = np.array([[65.481, 128.553, 24.966], [-37.797, -74.203, 112.0], [112.0, -93.786, -18.214]])
BT601_OFFSET = np.array([16.0, 128.0, 128.0])
SHARD_BALL_X, SHARD_BALL_Y = (0.3, 1.2), (-0.5, 0.5)  # metres: ahead of the robot's start
SCRIPTED_SWEEP_HZ = 0.25


class DumpError(OSError):
    """The destination cannot be written (or holds another dump); the message names the path."""


# ---------------------------------------------------------------- pixel formats


def rgb_to_yuv_bt601(rgb: np.ndarray) -> np.ndarray:
    """Unrounded (h, w, 3) Y, Cb, Cr of a uint8 RGB frame, BT.601 limited range."""
    return rgb.astype(np.float64) / 255 @ BT601_LIMITED.T + BT601_OFFSET


def _to_bytes(planes) -> bytes:
    return b"".join(np.clip(np.floor(p + 0.5), 0, 255).astype(np.uint8).tobytes() for p in planes)


def yuv444_bytes(rgb: np.ndarray) -> bytes:
    """I444 planar: Y, Cb, Cr planes of w x h bytes each."""
    yuv = rgb_to_yuv_bt601(rgb)
    return _to_bytes(yuv[..., c] for c in range(3))


def yuv420_bytes(rgb: np.ndarray) -> bytes:
    """I420 planar: the Y plane, then Cb and Cr as means of 2x2 blocks (w/2 x h/2 each)."""
    yuv = rgb_to_yuv_bt601(rgb)
    chroma = (yuv[0::2, 0::2, 1:] + yuv[0::2, 1::2, 1:] + yuv[1::2, 0::2, 1:] + yuv[1::2, 1::2, 1:]) / 4
    return _to_bytes([yuv[..., 0], chroma[..., 0], chroma[..., 1]])


def annex_yuv(rgb: np.ndarray) -> np.ndarray:
    """(h, w, 3) uint8 Y, U, V with the report's Annex I formulas and C truncation."""
    r, g, b = (rgb[..., c].astype(np.float64) for c in range(3))
    y = (0.299 * r + 0.587 * g + 0.114 * b).astype(np.uint8)
    u = (0.492 * (b - y) + 128).astype(np.uint8)
    v = (0.5 * (r - y) + 128).astype(np.uint8)
    return np.stack([y, u, v], axis=-1)


def geom_classes(model: mujoco.MjModel) -> np.ndarray:
    """Segmentation class id per geom id, plus a last entry (background) that id -1 selects."""
    robot_root = model.body_rootid[model.body("body").id]
    classes = np.zeros(model.ngeom + 1, np.uint8)
    for geom in range(model.ngeom):
        name = model.geom(geom).name
        label = next((label for prefix, label in CLASS_PREFIXES if name.startswith(prefix)), None)
        if label is None and model.body_rootid[model.geom_bodyid[geom]] == robot_root:
            label = "robot"
        classes[geom] = SEGMENTATION_CLASSES.index(label or "background")
    return classes


# ---------------------------------------------------------------- metadata


def ball_in_image(sim: Simulation) -> dict:
    """The ball centre's pixel in the current frame (x right, y down, through the lens; None
    behind the camera), visibility, distance.

    Visible: in front of the camera, projected inside the image, and the line of sight to
    the centre hits the ball first (the head camera's geom groups).
    """
    camera, model, data = sim.camera, sim.model, sim.data
    frame, ball = camera.frame(), sim.ball_position()
    offset = ball - frame.position
    distance = float(np.linalg.norm(offset))
    (u, v), depth = (a[0] for a in camera.project(ball, frame))
    if not depth > 0:
        return {"pixel": None, "visible": False, "distance_m": distance}
    inside = -0.5 <= u <= camera.width - 0.5 and -0.5 <= v <= camera.height - 0.5
    groups = np.array([g in HEAD_CAMERA_GROUPS for g in range(6)], np.uint8)
    hit = np.array([-1], np.int32)
    mujoco.mj_ray(model, data, frame.position, offset, groups, 1, -1, hit)
    return {"pixel": [float(u), float(v)], "visible": bool(inside and hit[0] == model.geom("ball").id),
            "distance_m": distance}


def frame_metadata(sim: Simulation, index: int) -> dict:
    """A frames.jsonl record: time, OPEN-R counters, camera pose and settings, joints (rad), the ball."""
    frame = sim.camera.frame()
    return {
        "index": index,
        "time_s": sim.time_ms / 1000,
        "frame_number": frame.frame_number,  # 8 ms ticks, the message's frameNumber
        "field_counter": frame.index,
        "camera": {"position": frame.position.tolist(), "xmat": frame.xmat.reshape(-1).tolist(),
                   **frame.settings.as_dict()},
        "joints": dict(zip((j.name for j in JOINTS), sim.joint_positions().tolist())),
        "ball": ball_in_image(sim),
    }


def file_layouts(formats, width: int, height: int) -> dict:
    """meta.json's "files": each format's path pattern, layout and size in bytes."""
    size, full = f"{width}x{height}", f"{openr_bridge.FULL_WIDTH}x{openr_bridge.FULL_HEIGHT}"
    layouts = {
        "rgb": ("rgb/{index:06d}.png", f"PNG, 8-bit RGB, {size}", None),
        "yuv444": ("yuv444/{index:06d}.yuv", f"I444 planar, {size}, Y then U (Cb) then V (Cr), BT.601 limited range",
                   3 * width * height),
        "yuv420": ("yuv420/{index:06d}.yuv", f"I420 planar (ffmpeg yuv420p), {size}, Y then U (Cb) then V (Cr) at "
                   f"{width // 2}x{height // 2}, BT.601 limited range", width * height * 3 // 2),
        "annex": ("annex/{index:06d}.yuv", f"Annex I: Y, U, V bytes per pixel, row-major, {size}", 3 * width * height),
        "openr": ("openr/{index:06d}.ofbk", "OFbkImageVectorData message bytes", None),
        "bands": ("bands/{index:06d}_{layer}.raw", "a layer's GetData bytes: H, M, L rows of Y, Cr, Cb, Y_LH, "
                  "Y_HL, Y_HH (6 w h bytes), C the CDT band (w h bytes)",
                  {name: BAND_RUNS[layer_type][1] * w * h for name, (w, h), layer_type
                   in zip(openr_bridge.LAYER_NAMES, openr_bridge.LAYER_SIZE, openr_bridge.LAYER_TYPE, strict=True)}),
        "luma": ("luma/{index:06d}.png", f"PNG, 8-bit grey, {full}, reconstruct_luma of layer H", None),
        "depth": ("depth/{index:06d}.npy", f"NumPy float32 {size}, metres along the optical axis", None),
        "seg": ("seg/{index:06d}.png", f"PNG, 8-bit class ids (segmentation_classes), {size}", None),
        "mp4": ("video.mp4", f"MP4 (mp4v), 30 fps, {size}", None),
    }
    return {f: dict(zip(("path", "layout", "bytes"), layouts[f])) for f in formats}


# ---------------------------------------------------------------- writing


def write_atomic(path: Path, data: bytes) -> None:
    """Write ``path`` whole or not at all (temporary name in the same folder, then rename)."""
    temp = path.with_name(TEMP_PREFIX + path.name)
    try:
        with open(temp, "wb") as file:
            file.write(data)
        os.replace(temp, path)
    except OSError as exc:
        with contextlib.suppress(OSError):
            temp.unlink()
        raise DumpError(f"cannot write {path}: {exc.strerror or exc}") from exc


def _png(image: np.ndarray) -> bytes:
    ok, encoded = cv2.imencode(".png", image)
    if not ok:
        raise ValueError(f"PNG encoding of a {image.shape} {image.dtype} image failed")
    return encoded.tobytes()


class DumpWriter:
    """Writes the chosen formats of each camera frame into a dump folder, atomically."""

    def __init__(self, out: Path, formats, parameters: dict, *, resume: bool, camera: dict, model: mujoco.MjModel):
        self.out, self.formats = out, tuple(formats)
        width, height = camera["width"], camera["height"]
        self.layouts = file_layouts(self.formats, width, height)
        meta = {"format": DUMP_FORMAT, "parameters": parameters, "camera": camera, "files": self.layouts,
                "segmentation_classes": list(SEGMENTATION_CLASSES)}
        self.complete = _prepare_folder(out, meta, resume)
        self.new_frames = self.bytes_written = 0
        self._classes = geom_classes(model) if "seg" in self.formats else None
        for name in self.formats:
            (out / self.layouts[name]["path"]).parent.mkdir(exist_ok=True)
        self._lines = _open_for_append(out / "frames.jsonl")
        self._video = self._video_path = None
        if "mp4" in self.formats:
            self._video_path = out / (TEMP_PREFIX + "video.mp4")
            self._video = cv2.VideoWriter(str(self._video_path), cv2.VideoWriter_fourcc(*"mp4v"), FRAME_RATE_HZ,
                                          (width, height))
            if not self._video.isOpened():
                raise DumpError(f"cannot write {self._video_path}: OpenCV's mp4v video writer did not open")

    def needs_frame(self, index: int) -> bool:
        """Whether frame ``index`` must be rendered: not complete yet, or wanted by the video."""
        return index not in self.complete or self._video is not None

    def write(self, sim: Simulation, index: int, extra: dict | None = None) -> None:
        """Dump the current camera frame as frame ``index``; ``extra`` joins its metadata."""
        rgb = sim.camera.frame().rgb
        if self._video is not None:
            self._video.write(np.ascontiguousarray(rgb[..., ::-1]))
        if index in self.complete:
            return
        for path, data in self._encode(sim, rgb, index):
            write_atomic(path, data)
            self.bytes_written += len(data)
        line = json.dumps({**frame_metadata(sim, index), **(extra or {})}) + "\n"
        try:
            self._lines.write(line.encode())
            self._lines.flush()
        except OSError as exc:
            raise DumpError(f"cannot write {self.out / 'frames.jsonl'}: {exc.strerror or exc}") from exc
        self.complete.add(index)
        self.new_frames += 1

    def _encode(self, sim: Simulation, rgb: np.ndarray, index: int):
        """(path, bytes) of each file of a frame."""
        wants = set(self.formats)

        def path(name: str, layer: str = "") -> Path:
            return self.out / self.layouts[name]["path"].format(index=index, layer=layer)

        if "rgb" in wants:
            yield path("rgb"), _png(rgb[..., ::-1])
        if "yuv444" in wants:
            yield path("yuv444"), yuv444_bytes(rgb)
        if "yuv420" in wants:
            yield path("yuv420"), yuv420_bytes(rgb)
        if "annex" in wants:
            yield path("annex"), annex_yuv(rgb).tobytes()
        if wants & {"openr", "bands", "luma"}:
            message = sim.camera.frame().message
            if "openr" in wants:
                yield path("openr"), bytes(message)
            if "bands" in wants:
                for name, layer in LAYERS.items():
                    yield path("bands", name), message.GetData(layer).tobytes()
            if "luma" in wants:
                yield path("luma"), _png(openr_bridge.reconstruct_luma(message))
        if "depth" in wants:
            buffer = io.BytesIO()
            np.save(buffer, sim.camera.depth())
            yield path("depth"), buffer.getvalue()
        if "seg" in wants:
            yield path("seg"), _png(self._classes[sim.camera.segmentation()])

    def __enter__(self) -> "DumpWriter":
        return self

    def __exit__(self, kind, error, traceback) -> None:
        if kind is None:
            self.finish()
        else:
            self.abort()

    def finish(self) -> None:
        """Close the files; the video takes its final name only now."""
        self._close()
        if self._video_path is not None:
            final = self.out / "video.mp4"
            try:
                os.replace(self._video_path, final)
            except OSError as exc:
                _remove_temporary_files(self.out)
                raise DumpError(f"cannot write {final}: {exc.strerror or exc}") from exc

    def abort(self) -> None:
        """Stop after a failure: complete frames stay, temporary files go."""
        self._close()
        _remove_temporary_files(self.out)

    def _close(self) -> None:
        self._lines.close()
        if self._video is not None:
            self._video.release()


def _prepare_folder(out: Path, meta: dict, resume: bool) -> set[int]:
    """Create or check the folder and write meta.json; returns the indices already complete."""
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise DumpError(f"cannot create the dump folder {out}: {exc.strerror or exc}") from exc
    meta_path, lines_path = out / "meta.json", out / "frames.jsonl"
    complete: set[int] = set()
    if meta_path.exists():
        if not resume:
            raise DumpError(f"{out} already holds a dump: pass --resume to continue it, or choose another --out")
        parameters, previous = meta["parameters"], json.loads(meta_path.read_text()).get("parameters") or {}
        if previous != parameters:
            changed = ", ".join(sorted(k for k in parameters if previous.get(k) != parameters[k]))
            raise DumpError(f"{meta_path}: cannot resume, the dump was made with other parameters ({changed})")
        complete = _complete_frames(lines_path)
    _remove_temporary_files(out)
    write_atomic(meta_path, (json.dumps(meta, indent=2) + "\n").encode())
    return complete


def _complete_frames(lines_path: Path) -> set[int]:
    """Indices listed in frames.jsonl, after cutting off a partial last line."""
    if not lines_path.exists():
        return set()
    data = lines_path.read_bytes()
    end = data.rfind(b"\n") + 1
    if end < len(data):
        with open(lines_path, "r+b") as file:
            file.truncate(end)
    return {json.loads(line)["index"] for line in data[:end].splitlines()}


def _open_for_append(path: Path):
    try:
        return open(path, "ab")
    except OSError as exc:
        raise DumpError(f"cannot write {path}: {exc.strerror or exc}") from exc


def _remove_temporary_files(out: Path) -> None:
    for temp in out.rglob(TEMP_PREFIX + "*"):
        with contextlib.suppress(OSError):
            temp.unlink()


# ---------------------------------------------------------------- running


@dataclass
class DumpSummary:
    out: str
    frames: int  # complete frames in the dump
    new_frames: int  # written by this run
    bytes_written: int
    wall_s: float

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


def _dump_controller(parameters: dict, out: Path, resume: bool) -> DumpWriter:
    frames, camera_full = parameters["frames"], parameters["camera_full"]
    settings = CameraSettings(**parameters["camera_settings"])
    model = load_model(parameters["scene"])
    camera = describe_camera(parameters["camera_profile"], settings, camera_size(camera_full),
                             scene_light_temperature(model))
    with DumpWriter(out, parameters["formats"], parameters, resume=resume, camera=camera, model=model) as writer:
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


def _dump_env(parameters: dict, out: Path, resume: bool) -> DumpWriter:
    camera, settings = "openr" if parameters["backend"] == "openr" else "rgb", parameters["camera_settings"]
    try:
        env = gymnasium.make(parameters["env"], camera=camera, scene=parameters["scene"],
                             camera_profile=parameters["camera_profile"], camera_wb=settings["white_balance"],
                             camera_gain=settings["gain"], camera_shutter=settings["shutter"])
    except gymnasium.error.Error as exc:
        raise ValueError(f"environment {parameters['env']!r}: {exc}") from None
    steps, seed = parameters["frames"], parameters["seed"]
    progress = Progress(steps / FRAME_RATE_HZ)
    try:
        sim = env.unwrapped.sim
        with DumpWriter(out, parameters["formats"], parameters, resume=resume, camera=sim.camera.describe(),
                        model=sim.model) as writer:
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


def _dump_one(parameters: dict, out: Path, resume: bool) -> DumpSummary:
    start = time.perf_counter()
    run = _dump_env if parameters["env"] else _dump_controller
    writer = run(parameters, out, resume)
    return DumpSummary(str(out), len(writer.complete), writer.new_frames, writer.bytes_written,
                       time.perf_counter() - start)


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
    if controller is not None:
        controller = Path(controller).resolve()
        if not controller.is_file():
            raise FileNotFoundError(f"{controller}: no such controller file")
    out = Path(out).resolve()
    parameters = {"controller": controller and str(controller), "env": env, "policy": env and policy,
                  "frames": frames, "backend": backend, "scene": scene and str(Path(scene).resolve()), "seed": seed,
                  "pose": pose and list(pose), "ball": ball and list(ball),
                  "formats": [f for f in FORMATS if f in formats], "camera_full": camera_full,
                  "camera_profile": camera_profile, "camera_settings": (camera_settings or CameraSettings()).as_dict()}
    if workers == 1:
        return _dump_one(parameters, out, resume)
    return _dump_sharded(parameters, out, resume, workers)


def _dump_sharded(parameters: dict, out: Path, resume: bool, workers: int) -> DumpSummary:
    start = time.perf_counter()
    meta = {"format": DUMP_FORMAT, "parameters": {**parameters, "workers": workers},
            "shards": [f"shard_{k}" for k in range(workers)]}
    _prepare_folder(out, meta, resume)
    shards = []
    for k in range(workers):
        seed = parameters["seed"] + k
        ball = parameters["ball"]
        if parameters["controller"] and ball is None:
            rng = np.random.default_rng(seed)
            ball = [float(rng.uniform(*SHARD_BALL_X)), float(rng.uniform(*SHARD_BALL_Y))]
        frames = parameters["frames"] // workers + (k < parameters["frames"] % workers)
        shard = {**parameters, "seed": seed, "ball": ball, "frames": frames, "progress": False}
        shards.append((shard, out / f"shard_{k}", resume))
    with ProcessPoolExecutor(workers, mp_context=get_context("spawn")) as pool:
        results = list(pool.map(_dump_one, *zip(*shards)))
    return DumpSummary(str(out), sum(r.frames for r in results), sum(r.new_frames for r in results),
                       sum(r.bytes_written for r in results), time.perf_counter() - start)


# ---------------------------------------------------------------- reading


class DumpFrame:
    """One frame of a dump; each accessor reads its file when called."""

    def __init__(self, folder: Path, meta: dict, dump_meta: dict):
        self.folder, self.meta, self._dump_meta = folder, meta, dump_meta
        self.width, self.height = dump_meta["camera"]["width"], dump_meta["camera"]["height"]

    def path(self, name: str, layer: str = "") -> Path:
        files = self._dump_meta["files"]
        if name not in files:
            raise FileNotFoundError(f"{self.folder}: the dump has no {name!r} files (its formats: {', '.join(files)})")
        return self.folder / files[name]["path"].format(index=self.meta["index"], layer=layer)

    def _raw(self, name: str) -> np.ndarray:
        return np.fromfile(self.path(name), np.uint8)

    @property
    def rgb(self) -> np.ndarray:
        return cv2.imread(str(self.path("rgb")), cv2.IMREAD_COLOR)[..., ::-1].copy()

    @property
    def yuv444(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(Y, U, V) planes, each (h, w)."""
        return tuple(self._raw("yuv444").reshape(3, self.height, self.width))

    @property
    def yuv420(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(Y, U, V) planes: (h, w), (h/2, w/2), (h/2, w/2)."""
        data, luma = self._raw("yuv420"), self.width * self.height
        chroma = data[luma:].reshape(2, self.height // 2, self.width // 2)
        return data[:luma].reshape(self.height, self.width), chroma[0], chroma[1]

    @property
    def annex(self) -> np.ndarray:
        """(h, w, 3): Y, U, V per pixel."""
        return self._raw("annex").reshape(self.height, self.width, 3)

    @property
    def message(self) -> openr_bridge.OFbkImageVectorData:
        return openr_bridge.OFbkImageVectorData.from_bytes(self.path("openr").read_bytes())

    def bands(self, layer: str | int) -> dict[int, np.ndarray]:
        """The bands of a layer ("H", "M", "L", "C" or ofbkimageLAYER_*) keyed by ofbkimageBAND_*."""
        index = LAYERS[layer] if isinstance(layer, str) else layer
        data = np.fromfile(self.path("bands", openr_bridge.LAYER_NAMES[index]), np.uint8)
        width, height = openr_bridge.LAYER_SIZE[index]
        info = openr_bridge.OFbkImageInfo(openr_bridge.LAYER_TYPE[index], 0, 0, 0, data.size, width, height)
        return {band: openr_bridge.OFbkImage(info, data, band).array for band in BAND_RUNS[info.type][0]}

    @property
    def luma(self) -> np.ndarray:
        return cv2.imread(str(self.path("luma")), cv2.IMREAD_GRAYSCALE)

    @property
    def depth(self) -> np.ndarray:
        return np.load(self.path("depth"))

    @property
    def seg(self) -> np.ndarray:
        """Class ids (h, w) uint8; names in ``Dump.segmentation_classes``."""
        return cv2.imread(str(self.path("seg")), cv2.IMREAD_GRAYSCALE)


class Dump:
    """A dump's complete frames (a sharded dump's shards one after the other)."""

    def __init__(self, folder: str | Path):
        self.folder = Path(folder)
        meta_path = self.folder / "meta.json"
        if not meta_path.is_file():
            raise FileNotFoundError(f"{meta_path}: not a dump (no meta.json)")
        self.meta = json.loads(meta_path.read_text())
        self.parts = [Dump(self.folder / shard) for shard in self.meta.get("shards", ())]
        if self.parts:
            self.frames = [f for part in self.parts for f in part.frames]
            self.videos = [v for part in self.parts for v in part.videos]
        else:
            lines = self.folder / "frames.jsonl"
            text = lines.read_text() if lines.exists() else ""
            records = [json.loads(line) for line in text.splitlines(keepends=True) if line.endswith("\n")]
            self.frames = [DumpFrame(self.folder, r, self.meta) for r in sorted(records, key=lambda r: r["index"])]
            video = self.folder / "video.mp4"
            self.videos = [video] if video.is_file() else []
        self.segmentation_classes = tuple(self.meta.get("segmentation_classes", SEGMENTATION_CLASSES))

    def __len__(self) -> int:
        return len(self.frames)

    def __getitem__(self, i: int) -> DumpFrame:
        return self.frames[i]

    def __iter__(self):
        return iter(self.frames)


def load_dump(folder: str | Path) -> Dump:
    """Open a dump folder written by ``aibo-sim dump`` (or ``dump``)."""
    return Dump(folder)


# ---------------------------------------------------------------- command line


def _dump_command(args) -> int:
    formats = FORMATS if args.formats == "all" else tuple(f.strip() for f in args.formats.split(",") if f.strip())
    if args.steps is not None and args.steps <= 0 or args.duration is not None and args.duration <= 0:
        raise ValueError("--steps and --duration must be positive")
    frames = args.steps if args.steps is not None else round((args.duration or 10.0) * FRAME_RATE_HZ)
    summary = dump(args.out, controller=args.controller, env=args.env, policy=args.policy, frames=frames,
                   backend=args.backend, scene=args.scene, seed=args.seed, pose=args.pose and tuple(args.pose),
                   ball=args.ball and tuple(args.ball), formats=formats, resume=args.resume, workers=args.workers,
                   **camera_options(args))
    print(f"dumped {summary.frames} frames to {summary.out} ({summary.new_frames} written now) in "
          f"{summary.wall_s:.1f} s: {summary.frames_per_s:.1f} frames/s, "
          f"{summary.bytes_written / 1e6 / max(summary.wall_s, 1e-9):.2f} MB/s")
    return 0


def add_dump_parser(subcommands) -> argparse.ArgumentParser:
    """Add the ``dump`` subcommand to the ``aibo-sim`` subparsers."""
    parser = subcommands.add_parser("dump", help="write every camera frame of a headless run (images, YUV, OPEN-R)",
                                    description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("controller", nargs="?", help="controller file (or use --env)")
    parser.add_argument("--env", help="gymnasium environment id, e.g. aibo_sim/HeadTrackBall-v0")
    parser.add_argument("--policy", choices=POLICIES, default="random", help="environment policy (default random)")
    parser.add_argument("--out", required=True, help="dump folder")
    length = parser.add_mutually_exclusive_group()
    length.add_argument("--duration", type=float, help="simulated seconds, 30 frames each (default 10)")
    length.add_argument("--steps", type=int, help="camera frames (controller) or environment steps")
    parser.add_argument("--backend", choices=BACKENDS, default="sim", help="what the controller sees")
    add_world_options(parser)  # --scene, --pose, --ball, --seed (shard k of --workers: seed + k), camera
    parser.add_argument("--formats", default=",".join(DEFAULT_FORMATS),
                        help=f"comma-separated from {','.join(FORMATS)}, or all (default {','.join(DEFAULT_FORMATS)})")
    parser.add_argument("--resume", action="store_true", help="continue an interrupted dump in --out")
    parser.add_argument("--workers", type=int, default=1, help="processes; the frames are split into shards")
    parser.set_defaults(handler=_dump_command)
    return parser
