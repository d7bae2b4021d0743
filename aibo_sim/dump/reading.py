"""Reading a dump back: ``load_dump``, ``Dump``, ``DumpFrame``; meta.json and frames.jsonl
parsed with errors that name the file and the line (the writer's resume uses them too)."""

from __future__ import annotations

import io
import json
import os
from pathlib import Path

import cv2
import numpy as np

import openr_bridge
from openr_bridge.image import BAND_RUNS

from ..field import SEGMENTATION_CLASSES
from ..files import SymlinkRefused, decode_image, read_file
from .formats import DUMP_FORMAT, LAYERS, DumpError

META, LINES = "meta.json", "frames.jsonl"


def _read_error(path: Path, exc: OSError) -> DumpError:
    return DumpError(str(exc) if isinstance(exc, SymlinkRefused) else f"cannot read {path}: {exc.strerror or exc}")


def _json_error(path: Path, exc: json.JSONDecodeError, line: int | None = None) -> DumpError:
    where = f"line {line}" if line is not None else f"line {exc.lineno} column {exc.colno}"
    return DumpError(f"{path}: {where}: not valid JSON ({exc.msg}); the file is corrupt")


def read_meta(path: Path) -> dict:
    """A dump's meta.json; DumpError naming the file (and line) when it is not a dump's."""
    try:
        data = read_file(path)
    except FileNotFoundError:
        raise DumpError(f"{path}: not a dump (no {META})") from None
    except OSError as exc:
        raise _read_error(path, exc) from exc
    try:
        meta = json.loads(data)
    except UnicodeDecodeError as exc:
        raise DumpError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start}); the file is corrupt") from None
    except json.JSONDecodeError as exc:
        raise _json_error(path, exc) from None
    if not isinstance(meta, dict) or meta.get("format") != DUMP_FORMAT:
        raise DumpError(f'{path}: not an aibo-sim dump\'s {META} (no "format": {DUMP_FORMAT!r})')
    return meta


def split_lines(data: bytes) -> tuple[bytes, bytes]:
    """frames.jsonl's complete lines and the partial last line (empty when the file ends in a newline)."""
    end = data.rfind(b"\n") + 1
    return data[:end], data[end:]


# A detection in a record's "objects" (``coco.Objects.detect``): its keys and their types.
DETECTION = {"category": str, "object": str, "bbox": list, "area": int, "visibility": (int, float)}


def _detections(objects) -> bool:
    """Whether ``objects`` is a list of detections that coco.json can be made from."""
    return isinstance(objects, list) and all(
        isinstance(o, dict)
        and all(isinstance(o.get(k), t) for k, t in DETECTION.items())
        and o["category"] in SEGMENTATION_CLASSES
        and isinstance(o.get("segmentation", {}), dict)
        for o in objects
    )


def parse_records(path: Path, data: bytes, limit: int) -> list[dict]:
    """frames.jsonl's records, from complete lines only; DumpError naming the line of a bad one
    (an index of ``limit`` or more included: ``frame_limit``)."""
    records = []
    for number, line in enumerate(data.splitlines(), 1):
        try:
            record = json.loads(line)
        except UnicodeDecodeError as exc:
            raise DumpError(f"{path}: line {number}: not UTF-8 text ({exc.reason}); the file is corrupt") from None
        except json.JSONDecodeError as exc:
            raise _json_error(path, exc, number) from None
        index = record.get("index") if isinstance(record, dict) else None
        if isinstance(index, bool) or not isinstance(index, int) or index < 0:
            raise DumpError(f'{path}: line {number}: not a frame record (no "index" >= 0); the file is corrupt')
        if index >= limit:
            raise DumpError(
                f"{path}: line {number}: frame index {index} is past the dump's frames (its indices "
                f"are below {limit}); the file is corrupt"
            )
        if "objects" in record and not _detections(record["objects"]):
            raise DumpError(
                f'{path}: line {number}: "objects" is not a list of detections (each with '
                f"{', '.join(DETECTION)}, a known category); the file is corrupt"
            )
        records.append(record)
    return records


def read_records(path: Path, limit: int) -> list[dict]:
    """The complete frames' records of a frames.jsonl (none when it does not exist)."""
    try:
        data = read_file(path)
    except FileNotFoundError:
        return []
    except OSError as exc:
        raise _read_error(path, exc) from exc
    return parse_records(path, split_lines(data)[0], limit)


def frame_limit(meta: dict) -> int:
    """One more than the highest frame index a (checked) meta.json's dump can hold: a controller
    dump's frame count; an environment dump's steps, each with a reset frame at most, twice that."""
    parameters = meta["parameters"]
    return parameters["frames"] * (2 if parameters.get("env") else 1)


def _whole(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value >= 1


def _inside(path: str) -> bool:
    """Whether a relative ``path`` stays in the folder it is relative to (no .., not absolute)."""
    parts = Path(path).parts
    return bool(parts) and not Path(path).is_absolute() and ".." not in parts


def check_meta(path: Path, meta: dict) -> None:
    """DumpError naming ``path`` and the field when a field that ``load_dump`` reads (in a shard's
    or an unsharded dump's meta.json) is missing or of the wrong type."""

    def bad(field: str, what: str) -> DumpError:
        return DumpError(f"{path}: {field} must be {what}; the file is corrupt")

    for key in ("parameters", "camera", "files"):
        if not isinstance(meta.get(key), dict):
            raise bad(f'"{key}"', "an object")
    if not _whole(meta["parameters"].get("frames")):
        raise bad('"parameters"."frames"', "a whole number >= 1")
    for key in ("width", "height"):
        if not _whole(meta["camera"].get(key)):
            raise bad(f'"camera"."{key}"', "a whole number >= 1")
    for name, layout in meta["files"].items():
        field = f'"files"."{name}"'
        if not isinstance(layout, dict):
            raise bad(field, "an object")
        try:
            inside = _inside(layout["path"].format(index=0, layer="H"))
        except (KeyError, AttributeError, TypeError, ValueError, IndexError):
            inside = False
        if not inside:
            raise bad(field + '."path"', "a file name pattern inside the dump")
        sizes = layout.get("bytes")
        if not (sizes is None or _whole(sizes) or isinstance(sizes, dict) and all(map(_whole, sizes.values()))):
            raise bad(field + '."bytes"', "a whole number >= 1, an object of them or null")
    classes = meta.get("segmentation_classes", SEGMENTATION_CLASSES)
    if not isinstance(classes, (list, tuple)) or not all(isinstance(c, str) for c in classes):
        raise bad('"segmentation_classes"', "a list of names")


class DumpFrame:
    """One frame of a dump; each accessor reads its file when called."""

    def __init__(self, folder: Path, meta: dict, dump_meta: dict):
        self.folder, self.meta, self._dump_meta = folder, meta, dump_meta
        self.width, self.height = dump_meta["camera"]["width"], dump_meta["camera"]["height"]

    @property
    def camera(self) -> dict:
        """The lens of this frame's picture: its dump's (or shard's) ``meta.json`` ``"camera"``."""
        return self._dump_meta["camera"]

    def path(self, name: str, layer: str = "") -> Path:
        """The file of format ``name`` (a layer's, for ``bands``) of this frame.

        :raises FileNotFoundError: the dump has no files of that format.
        """
        files = self._dump_meta["files"]
        if name not in files:
            raise FileNotFoundError(f"{self.folder}: the dump has no {name!r} files (its formats: {', '.join(files)})")
        return self.folder / files[name]["path"].format(index=self.meta["index"], layer=layer)

    def _raw(self, name: str, layer: str = "") -> np.ndarray:
        """A file's bytes (uint8); DumpError naming it when a fixed-size format's has another size."""
        path = self.path(name, layer)
        try:
            data = np.frombuffer(bytearray(read_file(path)), np.uint8)
        except FileNotFoundError:
            raise
        except OSError as exc:
            raise _read_error(path, exc) from exc
        expected = self._dump_meta["files"][name].get("bytes")
        expected = expected.get(layer) if isinstance(expected, dict) else expected
        if expected is not None and data.size != expected:
            raise DumpError(f"{path}: {data.size} bytes, expected {expected}; the file is truncated or corrupt")
        return data

    def _png(self, name: str, flags: int) -> np.ndarray:
        data = self._raw(name)
        image = decode_image(data, flags)
        if image is None:
            raise DumpError(f"{self.path(name)}: not a readable PNG; the file is corrupt")
        return image

    @property
    def rgb(self) -> np.ndarray:
        """The RGB picture, (h, w, 3) uint8."""
        return self._png("rgb", cv2.IMREAD_COLOR)[..., ::-1].copy()

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
        """The frame's ``OFbkImageVectorData``; DumpError if the file is not one."""
        try:
            return openr_bridge.OFbkImageVectorData.from_bytes(self._raw("openr"))
        except openr_bridge.MessageFormatError as exc:
            path = self.path("openr")
            raise DumpError(f"{path}: not an OFbkImageVectorData message ({exc}); the file is corrupt") from None

    def bands(self, layer: str | int) -> dict[int, np.ndarray]:
        """The bands of a layer ("H", "M", "L", "C" or ofbkimageLAYER_*) keyed by ofbkimageBAND_*;
        ValueError naming another."""
        index = LAYERS.get(layer) if isinstance(layer, str) else layer
        if index not in LAYERS.values():
            raise ValueError(f"bands({layer!r}): the layers are {', '.join(LAYERS)} or their numbers 0-3")
        data = self._raw("bands", openr_bridge.LAYER_NAMES[index])
        width, height = openr_bridge.LAYER_SIZE[index]
        info = openr_bridge.OFbkImageInfo(openr_bridge.LAYER_TYPE[index], 0, 0, 0, data.size, width, height)
        return {band: openr_bridge.OFbkImage(info, data, band).array for band in BAND_RUNS[info.type][0]}

    @property
    def luma(self) -> np.ndarray:
        """Layer H's reconstructed full-size luma, (h, w) uint8."""
        return self._png("luma", cv2.IMREAD_GRAYSCALE)

    @property
    def depth(self) -> np.ndarray:
        """Depth in metres along the optical axis, (h, w) float32."""
        try:
            return np.load(io.BytesIO(self._raw("depth")))
        except (ValueError, EOFError):
            raise DumpError(f"{self.path('depth')}: not a NumPy .npy file; the file is corrupt") from None

    @property
    def seg(self) -> np.ndarray:
        """Class ids (h, w) uint8; names in ``Dump.segmentation_classes``."""
        return self._png("seg", cv2.IMREAD_GRAYSCALE)

    @property
    def robots(self) -> np.ndarray:
        """Robot instance ids (h, w) uint8: 0 no robot, k the world's robot k (a match's dump:
        meta.json's ``"robots"``; ``formats.instance_teams`` gives their teams)."""
        return self._png("robots", cv2.IMREAD_GRAYSCALE)


class Dump:
    """A dump's complete frames (a sharded dump's shards one after the other; a shard that
    has not started yet holds none)."""

    def __init__(self, folder: str | Path):
        self.folder = Path(folder).resolve()  # once: it, or a folder above it, may be a link
        meta_path = self.folder / META
        self.meta = read_meta(meta_path)
        shards = self.meta.get("shards", [])
        if not isinstance(shards, list) or not all(isinstance(s, str) and s and Path(s).name == s for s in shards):
            raise DumpError(f'{meta_path}: "shards" must list the shard folders\' names; the file is corrupt')
        if not shards:
            check_meta(meta_path, self.meta)
        for name in shards or {os.path.dirname(layout["path"]) for layout in self.meta["files"].values()} - {""}:
            if (self.folder / name).is_symlink():  # read only files inside the dump
                raise DumpError(str(SymlinkRefused.at(self.folder / name)))
        self.parts = [Dump(self.folder / shard) for shard in shards if (self.folder / shard / META).exists()]
        if shards:
            self.frames = [f for part in self.parts for f in part.frames]
            self.videos = [v for part in self.parts for v in part.videos]
        else:
            records = read_records(self.folder / LINES, frame_limit(self.meta))
            records = {r["index"]: r for r in records}  # one frame per index
            self.frames = [DumpFrame(self.folder, records[i], self.meta) for i in sorted(records)]
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
    """Open a dump folder written by ``aibo-sim dump`` (or ``dump``); DumpError (an OSError)
    when it is not one or its meta.json or frames.jsonl is corrupt (naming the file and line).
    ``folder`` is resolved once, so it (or a folder above it) may be a link; a link inside the
    dump is not followed."""
    return Dump(folder)
