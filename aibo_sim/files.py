"""Files written whole or not at all, and the PNG bytes every writer of pictures uses."""

from __future__ import annotations

import contextlib
import errno
import os
from pathlib import Path

import cv2
import numpy as np


def write_file_atomic(path: Path, data: bytes, temp: Path | None = None) -> None:
    """Write ``path`` whole or not at all: as ``temp`` (default ``.NAME.tmp`` in the same folder,
    a name no pattern of a run's files matches), then renamed. An OSError names ``path``; no
    temporary file is left, whatever stops the write (a full disk: "cannot write PATH: No space
    left on device"; Ctrl-C)."""
    write_files_atomic({path: data}, {path: temp} if temp else None)


def write_files_atomic(files: dict[Path, bytes], temps: dict[Path, Path] | None = None) -> None:
    """Write several files as one set, each as ``write_file_atomic`` writes one: all of them are
    renamed into place once every one is on disk and no target is a folder, so a write that
    fails (a full disk) leaves the earlier set as it was."""
    temps = {path: (temps or {}).get(path) or path.with_name(f".{path.name}.tmp") for path in files}
    path = None
    try:
        for path, data in files.items():
            with open(temps[path], "wb") as file:
                file.write(data)
        for path in files:
            if path.is_dir():  # os.replace would refuse it after renaming the others
                raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(path))
        for path, temp in temps.items():
            os.replace(temp, path)
    except BaseException as exc:
        for temp in temps.values():
            with contextlib.suppress(OSError):
                temp.unlink()
        if not isinstance(exc, OSError):
            raise
        error = OSError(f"cannot write {path}: {exc.strerror or exc}")
        error.errno = exc.errno
        raise error from exc


def png(image: np.ndarray) -> bytes:
    """PNG bytes of an 8-bit image (BGR when it has three channels, as OpenCV writes)."""
    ok, encoded = cv2.imencode(".png", image)
    if not ok:
        raise ValueError(f"PNG encoding of a {image.shape} {image.dtype} image failed")
    return encoded.tobytes()
