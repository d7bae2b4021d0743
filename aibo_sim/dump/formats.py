"""What a dump holds: the pixel formats, each format's files and layout, a frame's metadata."""

from __future__ import annotations

import io
import os
from collections.abc import Sequence

import mujoco
import numpy as np

import openr_bridge
from openr_bridge.image import BAND_RUNS, IMAGE_INFO_SIZE, VECTOR_INFO_SIZE

from ..camera import HEAD_CAMERA_GROUPS
from ..camera.head import BEHIND_CAMERA_GROUP
from ..ers7 import JOINTS
from ..field import LABEL_TEAMS, SEGMENTATION_CLASSES
from ..files import open_file
from ..render import geom_groups
from ..sim import FRAME_MS, Simulation, robot_prefix
from ..team import MAX_ROBOTS, RobotSpec

FORMATS = ("rgb", "yuv444", "yuv420", "annex", "openr", "bands", "luma", "depth", "seg", "robots", "mp4", "coco")
DEFAULT_FORMATS = ("rgb", "yuv420", "openr", "mp4")
DUMP_FORMAT = "aibo-sim dump 1"  # meta.json's "format"

LAYERS = {name: layer for layer, name in enumerate(openr_bridge.LAYER_NAMES)}
# Each format's file, relative to the dump folder ("mp4", "coco": one file for every frame).
PATHS = {
    "rgb": "rgb/{index:06d}.png",
    "yuv444": "yuv444/{index:06d}.yuv",
    "yuv420": "yuv420/{index:06d}.yuv",
    "annex": "annex/{index:06d}.yuv",
    "openr": "openr/{index:06d}.ofbk",
    "bands": "bands/{index:06d}_{layer}.raw",
    "luma": "luma/{index:06d}.png",
    "depth": "depth/{index:06d}.npy",
    "seg": "seg/{index:06d}.png",
    "mp4": "video.mp4",
    "coco": "coco.json",
    "robots": "robots/{index:06d}.png",  # robot instance ids (robot_labels)
}
# Geoms by name prefix (first match wins); the other geoms of every robot's bodies are "robot".
CLASS_PREFIXES = (
    ("field_line", "line"),
    ("field", "field"),
    ("wall", "wall"),
    ("goal", "goal"),
    ("beacon", "beacon"),
    ("ball", "ball"),
)
# Rows: Y, Cb, Cr from RGB / 255 (ITU-R BT.601, limited range), plus the offsets.
BT601_LIMITED = np.array([[65.481, 128.553, 24.966], [-37.797, -74.203, 112.0], [112.0, -93.786, -18.214]])
BT601_OFFSET = np.array([16.0, 128.0, 128.0])


class DumpError(OSError):
    """The destination cannot be written, is not a dump, is locked by another writer or holds
    a corrupt dump; the message names the path (and the line, for a corrupt file)."""


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


def npy(array: np.ndarray) -> bytes:
    """``np.save``'s bytes of an array."""
    buffer = io.BytesIO()
    np.save(buffer, array)
    return buffer.getvalue()


def robot_roots(model: mujoco.MjModel) -> dict[int, int]:
    """Each robot's root body id in ``model`` and its instance id: its place in the world from 1
    (robot 1 the scene's own ERS-7, root body ``body``; robot k's root ``robot{k}/body``, ``sim.robot_prefix``)."""
    roots = {}
    for index in range(MAX_ROBOTS):
        body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, robot_prefix(index) + "body")
        if body >= 0:
            roots[int(model.body_rootid[body])] = index + 1
    return roots


def geom_robots(model: mujoco.MjModel) -> np.ndarray:
    """Robot instance id (``robot_roots``; 0: no robot's) per geom id, uint8, plus a last entry
    (0, background) that id -1 selects."""
    instances = np.zeros(model.ngeom + 1, np.uint8)
    roots = model.body_rootid[model.geom_bodyid]
    for root, instance in robot_roots(model).items():
        instances[:-1][roots == root] = instance
    return instances


def geom_classes(model: mujoco.MjModel) -> np.ndarray:
    """Segmentation class id per geom id, plus a last entry (background) that id -1 selects:
    by name (``CLASS_PREFIXES``), else "robot" for every robot's geoms (``robot_roots``)."""
    robot = geom_robots(model)[:-1] > 0
    classes = np.zeros(model.ngeom + 1, np.uint8)
    for geom in range(model.ngeom):
        name = model.geom(geom).name
        label = next((label for prefix, label in CLASS_PREFIXES if name.startswith(prefix)), None)
        if label is None and robot[geom]:
            label = "robot"
        classes[geom] = SEGMENTATION_CLASSES.index(label or "background")
    return classes


def robots_meta(robots: Sequence[RobotSpec], observer: int) -> dict:
    """meta.json's ``"robots"`` of a dump of the camera of robot ``observer`` (its instance id, from
    1) of a world of ``robots`` (``sim.world.robot_specs``), written for a match only (``is_match``:
    a lone robot's meta.json stays as it was): ``observer``; ``instances``, each robot by
    instance id (``robot_roots``) with its team (None: no uniform), player number and name;
    ``teams``, the team ids of ``robot_labels`` (``field.LABEL_TEAMS``: 0 none)."""
    return {
        "observer": observer,
        "instances": [
            {"id": index + 1, "team": robot.team, "number": robot.number, "name": robot.name}
            for index, robot in enumerate(robots)
        ],
        "teams": list(LABEL_TEAMS),
    }


def is_match(robots: Sequence[RobotSpec]) -> bool:
    """Whether a world of ``robots`` is a match (several robots, or one in a uniform): its dumps
    record ``robots_meta`` and may hold ``robot_labels``."""
    return len(robots) > 1 or any(robot.team is not None for robot in robots)


def instance_teams(robots: dict) -> np.ndarray:
    """The team id (``field.LABEL_TEAMS``) of each robot instance id, uint8, from ``robots_meta``
    (index 0: no robot): ``instance_teams(meta["robots"])[instances]`` is a dump's team image."""
    teams = np.zeros(MAX_ROBOTS + 1, np.uint8)
    for robot in robots["instances"]:
        teams[robot["id"]] = LABEL_TEAMS.index(robot["team"])
    return teams


def robot_labels(sim: Simulation, ids: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Per-pixel robot instance and team of ``sim``'s camera frame: two (h, w) uint8 images, the
    instance id (``robot_roots``: the robot's place in the world from 1, ``robots_meta``; 0 no
    robot) and the team id (``field.LABEL_TEAMS``: 1 red, 2 blue; 0 no robot or none). ``ids``: the
    frame's ``camera.segmentation()`` (geom ids), rendered when not given. The pixels are those of
    the segmentation's class "robot": every robot the camera draws, the observing robot's own
    body only where the camera can see it (its paws; never the geoms it leaves out, ``own_geoms``)."""
    if ids is None:
        ids = sim.camera.segmentation()
    instances = geom_robots(sim.model)[ids]
    return instances, instance_teams(robots_meta(sim.world.robot_specs, sim.index + 1))[instances]


# ---------------------------------------------------------------- layouts


def file_layouts(formats, width: int, height: int) -> dict:
    """meta.json's "files": each format's path pattern, layout and size in bytes (None: it varies)."""
    size, full = f"{width}x{height}", f"{openr_bridge.FULL_WIDTH}x{openr_bridge.FULL_HEIGHT}"
    bands = {
        name: BAND_RUNS[layer_type][1] * w * h
        for name, (w, h), layer_type in zip(
            openr_bridge.LAYER_NAMES, openr_bridge.LAYER_SIZE, openr_bridge.LAYER_TYPE, strict=True
        )
    }
    layouts = {
        "rgb": (f"PNG, 8-bit RGB, {size}", None),
        "yuv444": (f"I444 planar, {size}, Y then U (Cb) then V (Cr), BT.601 limited range", 3 * width * height),
        "yuv420": (
            f"I420 planar (ffmpeg yuv420p), {size}, Y then U (Cb) then V (Cr) at "
            f"{width // 2}x{height // 2}, BT.601 limited range",
            width * height * 3 // 2,
        ),
        "annex": (f"Annex I: Y, U, V bytes per pixel, row-major, {size}", 3 * width * height),
        "openr": (
            "OFbkImageVectorData message bytes",  # the header, the layers' infos, the layers back to back
            VECTOR_INFO_SIZE + IMAGE_INFO_SIZE * len(bands) + sum(bands.values()),
        ),
        "bands": (
            "a layer's GetData bytes: H, M, L rows of Y, Cr, Cb, Y_LH, Y_HL, Y_HH (6 w h bytes), C the CDT "
            "band (w h bytes)",
            bands,
        ),
        "luma": (f"PNG, 8-bit grey, {full}, reconstruct_luma of layer H", None),
        "depth": (
            f"NumPy float32 {size}, metres along the optical axis",
            len(npy(np.zeros((height, width), np.float32))),
        ),
        "seg": (f"PNG, 8-bit class ids (segmentation_classes), {size}", None),
        "robots": (
            f"PNG, 8-bit robot instance ids, {size}: 0 no robot, k the world's robot k (in a match, "
            "meta.json's \"robots\"; 1 a lone robot's own body)",
            None,
        ),
        "mp4": (f"MP4 (mp4v), 30 fps, {size}", None),
        "coco": (
            "COCO detection annotations (ball, goal, beacon, robot boxes and masks with visibility) "
            'of the rgb files, written at the end from frames.jsonl\'s "objects"',
            None,
        ),
    }
    return {f: dict(zip(("path", "layout", "bytes"), (PATHS[f], *layouts[f]))) for f in formats}


def frame_files(layouts: dict, index: int):
    """(format, relative path, expected size or None) of each file of frame ``index`` (not the video)."""
    for name, layout in layouts.items():
        if "{index" not in layout["path"]:
            continue
        if "{layer}" in layout["path"]:
            sizes = layout["bytes"] or {}
            for layer in openr_bridge.LAYER_NAMES:
                yield name, layout["path"].format(index=index, layer=layer), sizes.get(layer)
        else:
            yield name, layout["path"].format(index=index), layout["bytes"]


# ---------------------------------------------------------------- metadata


def ball_in_image(sim: Simulation) -> dict | None:
    """The ball centre's pixel in the current frame (x right, y down, through the lens; None
    behind the camera), visibility, distance, in the state the frame was exposed in; None in a
    scene without a ball.

    Visible: in front of the camera, projected inside the image, and the line of sight to
    the centre hits the ball first (the geoms the head camera draws: its geom groups, and in a
    match the other robots whole, ``camera.own_geoms``).
    """
    camera, model, data = sim.camera, sim.model, sim.camera.exposure_data()
    frame, ball = camera.frame(), sim.ball_position(data)
    if ball is None:
        return None
    offset = ball - frame.position
    distance = float(np.linalg.norm(offset))
    (u, v), depth = (a[0] for a in camera.project(ball, frame))
    if not depth > 0:
        return {"pixel": None, "visible": False, "distance_m": distance}
    inside = -0.5 <= u <= camera.width - 0.5 and -0.5 <= v <= camera.height - 0.5
    hit = np.array([-1], np.int32)
    if len(sim.world.robots) == 1:
        groups = np.array([g in HEAD_CAMERA_GROUPS for g in range(6)], np.uint8)
        mujoco.mj_ray(model, data, frame.position, offset, groups, 1, -1, hit)
    else:  # the other robots' group-1 geoms (heads, tails) hide the ball too; this robot's never drawn
        shown = (*HEAD_CAMERA_GROUPS, BEHIND_CAMERA_GROUP)
        hidden = next(g for g in range(mujoco.mjNGROUP) if g not in shown)
        groups = np.array([g in shown for g in range(6)], np.uint8)
        # under the render lock: the robots' renders change the groups too
        with geom_groups(model, camera.own_geoms(), hidden, sim.world.render_lock):
            mujoco.mj_ray(model, data, frame.position, offset, groups, 1, -1, hit)
    return {
        "pixel": [float(u), float(v)],
        "visible": bool(inside and hit[0] == model.geom("ball").id),
        "distance_m": distance,
    }


def frame_metadata(sim: Simulation, index: int) -> dict:
    """A frames.jsonl record: time, OPEN-R counters, camera pose and settings, joints (rad), the
    ball, each as the frame was exposed (``frame_number``'s 8 ms tick: its ``time_s``)."""
    frame = sim.camera.frame()
    return {
        "index": index,
        "time_s": frame.frame_number * FRAME_MS / 1000,
        "frame_number": frame.frame_number,  # 8 ms ticks, the message's frameNumber
        "field_counter": frame.index,
        "camera": {
            "position": frame.position.tolist(),
            "xmat": frame.xmat.reshape(-1).tolist(),
            **frame.settings.as_dict(),
        },
        "joints": dict(zip((j.name for j in JOINTS), sim.joint_positions(sim.camera.exposure_data()).tolist())),
        "ball": ball_in_image(sim),
    }


_MP4_CONTAINERS = {b"moov", b"trak", b"mdia", b"minf", b"stbl"}  # the boxes on the way to the chunk offsets
_MOVE_BLOCK = 1 << 20  # faststart moves the frames in blocks of this many bytes


def _box_header(data: bytes | memoryview, start: int, end: int) -> tuple[bytes, int, int]:
    """(type, size, header length) of the box at ``data[start:]`` (ISO/IEC 14496-12, 4.2: a
    32-bit size, or 1 and a 64-bit size after the type, or 0: up to ``end``)."""
    size, kind, header = int.from_bytes(data[start : start + 4], "big"), bytes(data[start + 4 : start + 8]), 8
    if size == 1:
        size, header = int.from_bytes(data[start + 8 : start + 16], "big"), 16
    elif size == 0:
        size = end - start
    return kind, size, header


def mp4_boxes(data: bytes | memoryview, start: int, end: int):
    """(type, start, end, header length) of each box in ``data[start:end]``; ValueError for a box
    that runs past its parent."""
    while start + 8 <= end:
        kind, size, header = _box_header(data, start, end)
        if size < header or start + size > end:
            raise ValueError(f"MP4 box {kind!r} at byte {start} runs past its parent")
        yield kind, start, start + size, header
        start += size


def _shift_chunk_offsets(moov: bytearray, start: int, end: int, moved: range, shift: int) -> None:
    """Add ``shift`` to the chunk offsets (stco, co64) inside ``moov[start:end]`` that lie in
    ``moved``; ValueError where one no longer fits its 32 bits or its box."""
    for kind, box_start, box_end, header in mp4_boxes(moov, start, end):
        if kind in _MP4_CONTAINERS:
            _shift_chunk_offsets(moov, box_start + header, box_end, moved, shift)
        elif kind in (b"stco", b"co64"):
            width, entries = (4 if kind == b"stco" else 8), box_start + header + 8  # after version, flags, count
            count = int.from_bytes(moov[entries - 4 : entries], "big")
            if entries + count * width > box_end:
                raise ValueError(f"{kind!r} lists more offsets than it holds")
            for at in range(entries, entries + count * width, width):
                offset = int.from_bytes(moov[at : at + width], "big")
                if offset in moved:
                    if offset + shift >= 1 << (8 * width):
                        raise ValueError("a chunk offset no longer fits its stco box")
                    moov[at : at + width] = (offset + shift).to_bytes(width, "big")


def mp4_faststart(path) -> bool:
    """Move an MP4's ``moov`` box (its index, which OpenCV's writer puts last) ahead of ``mdat``,
    in place and at the same size, as ``ffmpeg -movflags +faststart`` does: a player can then
    start before the whole file is read. The frames move in blocks, so memory stays small.
    False, the file untouched, where the index already leads or cannot be moved (a chunk
    offset that would outgrow 32 bits, boxes it cannot read)."""
    with open(open_file(path, os.O_RDWR), "r+b") as file:
        size = file.seek(0, os.SEEK_END)
        boxes, start = {}, 0  # the first box of each type at the top level: (start, end)
        while start + 8 <= size:
            file.seek(start)
            kind, length, header = _box_header(file.read(16), 0, size - start)
            if length < header or start + length > size:
                return False
            boxes.setdefault(kind, (start, start + length))
            start += length
        if b"moov" not in boxes or b"mdat" not in boxes or boxes[b"moov"][0] < boxes[b"mdat"][0] or start != size:
            return False
        (mdat_start, _), (moov_start, moov_end) = boxes[b"mdat"], boxes[b"moov"]
        file.seek(moov_start)
        moov = bytearray(file.read(moov_end - moov_start))
        try:
            _shift_chunk_offsets(
                moov, _box_header(moov, 0, len(moov))[2], len(moov), range(mdat_start, moov_start), len(moov)
            )
        except ValueError:
            return False
        # Everything from mdat to moov moves up by moov's length, last block first (they overlap).
        end = moov_start
        while end > mdat_start:
            block = max(mdat_start, end - _MOVE_BLOCK)
            file.seek(block)
            data = file.read(end - block)
            file.seek(block + len(moov))
            file.write(data)
            end = block
        file.seek(mdat_start)
        file.write(moov)
    return True
