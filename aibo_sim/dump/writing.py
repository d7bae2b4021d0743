"""Writing a dump: the folder's checks and lock, atomic files, ``DumpWriter``, resuming."""

from __future__ import annotations

import contextlib
import errno
import json
import os
import re
from dataclasses import dataclass
from pathlib import Path

import cv2
import mujoco
import numpy as np

import openr_bridge
from openr_bridge import FRAME_RATE_HZ

from .. import files
from ..field import SEGMENTATION_CLASSES
from ..files import (
    HardLinkRefused,
    SymlinkRefused,
    list_folder,
    make_folder,
    open_file,
    png,
    read_file,
    refuse_hard_link,
    remove_in,
    rename_in,
    write_file_atomic,
)
from ..placement import out_path
from ..sim import Simulation
from .coco import Objects, coco_bytes
from .formats import (
    DUMP_FORMAT,
    LAYERS,
    PATHS,
    DumpError,
    annex_yuv,
    file_layouts,
    frame_files,
    frame_metadata,
    geom_classes,
    geom_robots,
    mp4_faststart,
    npy,
    yuv420_bytes,
    yuv444_bytes,
)
from .reading import LINES, META, frame_limit, parse_records, read_meta, split_lines

TEMP_PREFIX = ".tmp."  # a file being written: ".tmp." + its final name, in the same folder
LOCK_NAME = ".dump.lock"  # flock()ed by the writer; holds its pid, command and start time
CONTROLLER_FILES = "controller_files"  # a controller dump's (or shard's) folder: the controller runs there
VIDEO, COCO = PATHS["mp4"], PATHS["coco"]
# What an empty destination may hold: the lock, or the temporary meta.json of a writer killed at once.
OWN_TOP_FILES = frozenset({LOCK_NAME, TEMP_PREFIX + META, TEMP_PREFIX + VIDEO, TEMP_PREFIX + COCO})


# ---------------------------------------------------------------- files


def dump_error(exc: OSError, message: str | None = None) -> DumpError:
    """``exc`` as a DumpError: ``message`` (default, and for a refused link, its own words); a
    full disk's says how to go on."""
    message = str(exc) if message is None or isinstance(exc, (SymlinkRefused, HardLinkRefused)) else message
    if exc.errno == errno.ENOSPC:
        message += "; free some space, then continue the dump with --resume"
    return DumpError(message)


def write_atomic(path: Path, data: bytes) -> None:
    """Write ``path`` whole or not at all (``files.write_file_atomic``, under a ``.tmp.`` name)."""
    try:
        write_file_atomic(path, data, path.with_name(TEMP_PREFIX + path.name))
    except OSError as exc:
        raise dump_error(exc) from exc


def _temporary_name(pattern: str) -> re.Pattern:
    """The temporary names of a layout's file pattern ("rgb/{index:06d}.png" -> .tmp.NNNNNN.png)."""
    parts = re.split(r"(\{index:06d\}|\{layer\})", pattern)
    fields = {"{index:06d}": r"\d{6,}", "{layer}": "[A-Z]+"}
    return re.compile(re.escape(TEMP_PREFIX) + "".join(fields.get(p, re.escape(p)) for p in parts))


def remove_temporary_files(out: Path, layouts: dict) -> None:
    """Remove the dump's own temporary files: its names, in its folders, nothing else."""
    patterns: dict[str, list[re.Pattern]] = {}
    for layout in layouts.values():
        folder, name = os.path.split(layout["path"])
        patterns.setdefault(folder, []).append(_temporary_name(name))
    remove_in(out, OWN_TOP_FILES - {LOCK_NAME})
    for folder, names in patterns.items():
        if folder:
            with contextlib.suppress(OSError):
                remove_in(out / folder, [n for n in list_folder(out / folder) if any(p.fullmatch(n) for p in names)])


# ---------------------------------------------------------------- the lock


class FolderLock(files.FolderLock):
    """The dump's lock, ``.dump.lock`` (``files.FolderLock``): DumpError while another dump holds it."""

    def __init__(self, folder: Path, *, wait_s: float = 0.0, command: str | None = None):
        super().__init__(
            folder,
            LOCK_NAME,
            "dump",
            "wait for it to end or stop it, then --resume",
            wait_s=wait_s,
            command=command,
            error=DumpError,
        )


# ---------------------------------------------------------------- the folder


def check_destination(out: Path, shard_of: Path | None = None) -> None:
    """Before anything is written: ``out`` is missing, empty (but for the dump's own files) or a
    dump; ``shard_of``: the dump whose shard it is (named in the error)."""
    try:
        entries = set(os.listdir(out))
    except FileNotFoundError:
        return
    except OSError as exc:
        raise DumpError(f"cannot create the dump folder {out}: {exc.strerror or exc}") from exc
    if not entries - OWN_TOP_FILES:
        return
    if META in entries:
        read_meta(out / META)  # a clear error when it is not a dump's
        return
    if shard_of is not None:
        raise DumpError(
            f"{out}: this shard of the dump in {shard_of} has no {META}: the shard is damaged; "
            f"remove {out} and --resume to write the shard again"
        )
    raise DumpError(
        f"{out} is not empty and is not a dump (no {META}): refusing to write into it; "
        "choose a new or empty folder for --out"
    )


def _changed_parameters(previous: dict, parameters: dict) -> list[str]:
    return sorted(k for k in set(previous) | set(parameters) if previous.get(k) != parameters.get(k))


def _frames_on_disk(out: Path, layouts: dict, limit: int, truncate: bool) -> tuple[set[int], set[int]]:
    """(frames listed in frames.jsonl, those of them with a file missing or of the wrong size);
    an index of ``limit`` or more is corrupt; a partial last line is cut off when ``truncate``."""
    lines_path = out / LINES
    try:
        data = read_file(lines_path)
    except FileNotFoundError:
        return set(), set()
    except OSError as exc:
        raise dump_error(exc, f"cannot read {lines_path}: {exc.strerror or exc}") from exc
    complete_lines, partial = split_lines(data)
    complete = {record["index"] for record in parse_records(lines_path, complete_lines, limit)}
    if partial and truncate:
        try:
            fd = open_file(lines_path, os.O_WRONLY)
            refuse_hard_link(fd, lines_path)
            try:
                os.ftruncate(fd, len(complete_lines))
            finally:
                os.close(fd)
        except OSError as exc:
            raise dump_error(exc, f"cannot write {lines_path}: {exc.strerror or exc}") from exc
    sizes: dict[str, dict[str, int]] = {}  # a frame's files: regular files (a link is no frame's file)
    for layout in layouts.values():
        folder = os.path.dirname(layout["path"])
        if folder and folder not in sizes:
            sizes[folder] = {}
            with contextlib.suppress(FileNotFoundError), os.scandir(out / folder) as entries:
                sizes[folder] = {
                    e.name: e.stat(follow_symlinks=False).st_size for e in entries if e.is_file(follow_symlinks=False)
                }
    missing = set()
    for index in complete:
        for _, path, expected in frame_files(layouts, index):
            folder, name = os.path.split(path)
            size = sizes.get(folder, {}).get(name)
            if size is None or expected is not None and size != expected:
                missing.add(index)
                break
    return complete, missing


class Prepared:
    """A locked, checked dump folder: the frames already complete, those whose files must be rewritten."""

    def __init__(self, lock: FolderLock, complete: set[int], missing: set[int]):
        self.lock, self.complete, self.missing = lock, complete, missing


def prepare_folder(
    out: Path, meta: dict, resume: bool, *, lock_wait_s: float = 0.0, command: str | None = None
) -> Prepared:
    """Check, create and lock the folder, check a dump being resumed, write meta.json.

    Refused (DumpError, nothing changed): a non-empty folder that is not a dump, a dump
    without ``resume``, a dump made with other parameters (or another controller file), a
    dump another process is writing. Frames listed in frames.jsonl whose files are missing or
    of the wrong size (a fixed-size format's) are rewritten (``Prepared.missing``); the
    simulation is deterministic.
    """
    check_destination(out)
    try:
        make_folder(out)
    except OSError as exc:
        raise dump_error(exc, f"cannot create the dump folder {out}: {exc.strerror or exc}") from exc
    lock = FolderLock(out, wait_s=lock_wait_s, command=command)
    try:
        meta_path, layouts = out / META, meta.get("files", {})
        complete: set[int] = set()
        missing: set[int] = set()
        if meta_path.exists():
            if not resume:
                raise DumpError(f"{out} already holds a dump: pass --resume to continue it, or choose another --out")
            previous = read_meta(meta_path).get("parameters")
            previous = previous if isinstance(previous, dict) else {}
            parameters = meta["parameters"]
            if (
                "controller_sha256" in parameters
                and "controller_sha256" in previous  # a match's dump records each robot's elsewhere
                and parameters.get("controller") == previous.get("controller")
                and previous["controller_sha256"] != parameters["controller_sha256"]
            ):
                raise DumpError(
                    f"{meta_path}: cannot resume, the controller file {parameters['controller']} changed "
                    "since the dump began (another SHA-256); dump to another --out"
                )
            changed = _changed_parameters(previous, parameters)
            if changed:
                raise DumpError(
                    f"{meta_path}: cannot resume, the dump was made with other parameters ({', '.join(changed)})"
                )
            complete, missing = _frames_on_disk(out, layouts, frame_limit(meta), truncate=True)
        remove_temporary_files(out, layouts)
        write_atomic(meta_path, (json.dumps(meta, indent=2) + "\n").encode())
    except BaseException:
        lock.release()
        raise
    return Prepared(lock, complete, missing)


# ---------------------------------------------------------------- the writer


@dataclass
class DumpSummary:
    """What ``dump`` returns: the dump's folder, its frames and what this run wrote."""

    out: str
    frames: int  # complete frames in the dump
    new_frames: int  # written by this run
    bytes_written: int
    wall_s: float
    repaired_frames: int = 0  # complete frames whose missing or wrong-sized files this run rewrote

    @property
    def frames_per_s(self) -> float:
        """Frames this run wrote per second of wall time."""
        return self.new_frames / max(self.wall_s, 1e-9)


class DumpWriter:
    """Writes the chosen formats of each camera frame into a dump folder, atomically; holds
    the folder's lock until ``finish`` or ``abort``."""

    def __init__(
        self,
        out: Path,
        formats,
        parameters: dict,
        *,
        resume: bool,
        camera: dict,
        model: mujoco.MjModel,
        lock_wait_s: float = 0.0,
        command: str | None = None,
        robots: dict | None = None,
    ):
        """``robots``: meta.json's "robots" (``formats.robots_meta``) in a match's dump; None for a lone
        robot, whose meta.json has none. ``out`` is resolved once (``placement.out_path``): a link on
        its way is the user's; one put under it later is not followed."""
        self.out, self.formats = out_path(out), tuple(formats)
        width, height = camera["width"], camera["height"]
        self.layouts = file_layouts(self.formats, width, height)
        meta = {
            "format": DUMP_FORMAT,
            "parameters": parameters,
            "camera": camera,
            "files": self.layouts,
            "segmentation_classes": list(SEGMENTATION_CLASSES),
            **({"robots": robots} if robots is not None else {}),
        }
        prepared = prepare_folder(out, meta, resume, lock_wait_s=lock_wait_s, command=command)
        self._lock, self.complete, self.missing = prepared.lock, prepared.complete, prepared.missing
        self.new_frames = self.repaired_frames = self.bytes_written = 0
        self._lines = self._video = self._video_path = None
        self._video_frames = 0
        try:
            self._classes = geom_classes(model) if "seg" in self.formats else None
            self._instances = geom_robots(model) if "robots" in self.formats else None  # formats.robot_labels
            self._objects = Objects(model) if "coco" in self.formats else None
            for name in self.formats:
                path = out / self.layouts[name]["path"]
                try:
                    make_folder(path.parent)
                except OSError as exc:
                    raise dump_error(exc, f"cannot create {path.parent}: {exc.strerror or exc}") from exc
            self._lines = open(self._open(out / LINES, os.O_APPEND), "ab")
            if "mp4" in self.formats:
                self._video_path = out / (TEMP_PREFIX + VIDEO)
                os.close(self._open(self._video_path, os.O_EXCL))  # ours, not a link, when OpenCV opens it
                self._video = cv2.VideoWriter(
                    str(self._video_path), cv2.VideoWriter_fourcc(*"mp4v"), FRAME_RATE_HZ, (width, height)
                )
                if not self._video.isOpened():
                    raise DumpError(f"cannot write {self._video_path}: OpenCV's mp4v video writer did not open")
        except BaseException:
            self.abort()
            raise

    @staticmethod
    def _open(path: Path, flags: int) -> int:
        """``path`` created (or opened) for writing with ``flags``, never through a link; DumpError."""
        try:
            fd = open_file(path, os.O_WRONLY | os.O_CREAT | flags)
            refuse_hard_link(fd, path)
            return fd
        except OSError as exc:
            raise dump_error(exc, f"cannot write {path}: {exc.strerror or exc}") from exc

    def needs_frame(self, index: int) -> bool:
        """Whether frame ``index`` must be rendered: not complete yet, a file of it missing (or
        of the wrong size), or wanted by the video."""
        return index not in self.complete or index in self.missing or self._video is not None

    def write(self, sim: Simulation, index: int, extra: dict | None = None) -> None:
        """Dump the current camera frame as frame ``index``; ``extra`` joins its metadata."""
        rgb = sim.camera.frame().rgb
        if self._video is not None:
            self._video.write(np.ascontiguousarray(rgb[..., ::-1]))
            self._video_frames += 1
        if index in self.complete and index not in self.missing:
            return
        # The frame's geom ids, rendered once for the seg and robots files and for coco's goals and beacons.
        ids = sim.camera.segmentation() if {"seg", "robots", "coco"} & set(self.formats) else None
        for path, data in self._encode(sim, rgb, index, ids):
            write_atomic(path, data)
            self.bytes_written += len(data)
        if index in self.missing:  # its line is there already
            self.missing.discard(index)
            self.repaired_frames += 1
            return
        objects = {"objects": self._objects.detect(sim, ids)} if self._objects is not None else {}
        line = json.dumps({**frame_metadata(sim, index), **objects, **(extra or {})}) + "\n"
        try:
            self._lines.write(line.encode())
            self._lines.flush()
        except OSError as exc:
            raise dump_error(exc, f"cannot write {self.out / LINES}: {exc.strerror or exc}") from exc
        self.complete.add(index)
        self.new_frames += 1

    def _encode(self, sim: Simulation, rgb: np.ndarray, index: int, ids: np.ndarray | None):
        """(path, bytes) of each file of a frame (``ids``: its geom ids, for seg and robots)."""
        wants = set(self.formats)

        def path(name: str, layer: str = "") -> Path:
            return self.out / self.layouts[name]["path"].format(index=index, layer=layer)

        if "rgb" in wants:
            yield path("rgb"), png(rgb[..., ::-1])
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
                yield path("luma"), png(openr_bridge.reconstruct_luma(message))
        if "depth" in wants:
            yield path("depth"), npy(sim.camera.depth())
        if wants & {"seg", "robots"}:
            if "seg" in wants:
                yield path("seg"), png(self._classes[ids])
            if "robots" in wants:
                yield path("robots"), png(self._instances[ids])

    def __enter__(self) -> DumpWriter:
        return self

    def __exit__(self, kind, error, traceback) -> None:
        if kind is None:
            self.finish()
        else:
            self.abort()

    def finish(self) -> None:
        """Close the files; the video takes its final name only now (none without a frame: a
        container without a stream, which players refuse), coco.json is written now."""
        try:
            self._close()
            if self._video_path is not None and not self._video_frames:
                remove_in(self.out, [self._video_path.name])
            elif self._video_path is not None:
                final = self.out / VIDEO
                try:
                    mp4_faststart(self._video_path)  # its index ahead of the frames (or left as written)
                    rename_in(self.out, self._video_path.name, VIDEO)
                except OSError as exc:
                    remove_temporary_files(self.out, self.layouts)
                    raise dump_error(exc, f"cannot write {final}: {exc.strerror or exc}") from exc
                self.bytes_written += final.stat().st_size
            if self._objects is not None:
                coco = coco_bytes(self.out, [self.out])
                write_atomic(self.out / COCO, coco)
                self.bytes_written += len(coco)
        finally:
            self._lock.release()

    def abort(self) -> None:
        """Stop after a failure: complete frames stay, the dump's temporary files go."""
        try:
            self._close()
            remove_temporary_files(self.out, self.layouts)
        finally:
            self._lock.release()

    def _close(self) -> None:
        if self._lines is not None:
            self._lines.close()
        if self._video is not None:
            self._video.release()
