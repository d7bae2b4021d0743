"""Files written whole or not at all, never through a symbolic link; folder locks; and the PNG
bytes every writer of pictures uses.

Where aibo-sim writes (a run's, a dump's or a render's folder) it creates, appends to, locks
and reads only its own files: a symbolic link planted in the place of one of them, or of a
folder it writes in, is refused (``SymlinkRefused``, one line naming it), never followed. The
folder the user names (``--out``) is resolved once at the start, so it may itself be a link."""

from __future__ import annotations

import contextlib
import datetime
import errno
import json
import os
import shlex
import stat
import sys
import time
from pathlib import Path

import cv2
import numpy as np

try:
    import fcntl
except ImportError:  # not POSIX: folders are not locked there
    fcntl = None

_NO_FOLLOW = getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
HOLDER_COMMAND_CHARS = 300  # a lock holder's command line is cut to this in messages


class SymlinkRefused(OSError):
    """A symbolic link where aibo-sim reads or writes a file or folder of its own."""

    @classmethod
    def at(cls, path) -> SymlinkRefused:
        """The error for the symbolic link at ``path``, saying what to do instead."""
        return cls(
            f"{path} is a symbolic link: refusing to follow it (aibo-sim reads and writes only its own "
            "files there); remove it or choose another folder"
        )


def open_file(path, flags: int, mode: int = 0o666) -> int:
    """``os.open`` that never follows a symbolic link at ``path`` (``SymlinkRefused``)."""
    try:
        return os.open(path, flags | _NO_FOLLOW, mode)
    except OSError as exc:
        if exc.errno in (errno.ELOOP, errno.EEXIST) and os.path.islink(path):
            raise SymlinkRefused.at(path) from None
        raise


class HardLinkRefused(OSError):
    """A file aibo-sim would write in place that has another name too: its content is not ours."""


def refuse_hard_link(fd: int, path) -> None:
    """HardLinkRefused, ``fd`` closed, when the file open at ``fd`` has another name too."""
    if os.fstat(fd).st_nlink > 1:
        os.close(fd)
        raise HardLinkRefused(f"{path} is a hard link to another file: refusing to write it; remove it")


def read_file(path) -> bytes:
    """The bytes of the regular file at ``path``: a link is ``SymlinkRefused``; a FIFO, device or
    folder an OSError saying what it is, at once (opened without blocking)."""
    fd = open_file(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    with open(fd, "rb") as file:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise OSError(errno.EINVAL, "not a regular file", str(path))
        return file.read()


def make_folder(path) -> Path:
    """The folder ``path``, made with its parents if missing; ``SymlinkRefused`` when it is a
    link, NotADirectoryError naming it when it is a file."""
    path = Path(path)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        pass
    mode = os.lstat(path).st_mode
    if stat.S_ISLNK(mode):
        raise SymlinkRefused.at(path)
    if not stat.S_ISDIR(mode):
        raise NotADirectoryError(errno.ENOTDIR, "not a folder", str(path))
    return path


def create_file(temp: Path) -> int:
    """A new file at ``temp``, opened for writing; a regular file already there (the temporary
    file of a writer that was killed, an earlier run's log) is replaced, never written through
    (a hard link to another file stays as it was), a symbolic link refused."""
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL
    try:
        return open_file(temp, flags)
    except FileExistsError:
        os.unlink(temp)
        return open_file(temp, flags)


def temporary_path(path: Path) -> Path:
    """Where ``write_file_atomic`` writes ``path`` first, by default: ``.NAME.tmp`` beside it."""
    return path.with_name(f".{path.name}.tmp")


def write_file_atomic(path: Path, data: bytes, temp: Path | None = None, durable: bool = False) -> None:
    """Write ``path`` whole or not at all: as ``temp`` (default ``.NAME.tmp`` in the same folder,
    a name no pattern of a run's files matches), created anew (never through a link), then
    renamed (a link at ``path`` is replaced, not followed). An OSError of the same kind names
    ``path`` (``SymlinkRefused`` the link); no temporary file is left, whatever stops the write (a
    full disk: "cannot write PATH: No space left on device"; Ctrl-C). ``durable``: on the disk
    before the rename (``fsync``: a crash leaves the old file or the new, never an empty one)."""
    write_files_atomic({path: data}, {path: temp} if temp else None, durable)


def check_atomic_write(path: Path) -> None:
    """Raise, before anything is written, the OSError that ``write_file_atomic(path)`` would for
    what lies in its way: a link at its temporary file (``SymlinkRefused``), a folder there or at
    ``path`` (a run checks its folder so, that one refused is left as it was)."""
    temp = temporary_path(path)
    if temp.is_symlink():
        raise SymlinkRefused.at(temp)
    for folder in (temp, path):
        if folder.is_dir():
            where = f"{folder}: " if folder != path else ""
            raise OSError(f"cannot write {path}: {where}{os.strerror(errno.EISDIR)}")


def write_files_atomic(files: dict[Path, bytes], temps: dict[Path, Path] | None = None, durable: bool = False) -> None:
    """Write several files as one set, each as ``write_file_atomic`` writes one: all of them are
    renamed into place once every one is on disk and no target is a folder, so a write that
    fails (a full disk) leaves the earlier set as it was."""
    temps = {path: (temps or {}).get(path) or temporary_path(path) for path in files}
    path, created = None, []
    try:
        for path, data in files.items():
            created.append(temps[path])  # before it exists: a signal right after it is made still finds it
            fd = create_file(temps[path])
            with open(fd, "wb") as file:
                file.write(data)
                if durable:
                    file.flush()
                    os.fsync(file.fileno())
        for path in files:
            if path.is_dir():  # os.replace would refuse it after renaming the others
                raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(path))
        for path, temp in temps.items():
            os.replace(temp, path)
    except BaseException as exc:
        for temp in created:
            with contextlib.suppress(OSError):
                if not temp.is_symlink():  # ours never is: a link refused stays
                    temp.unlink()
        if not isinstance(exc, OSError) or isinstance(exc, SymlinkRefused):
            raise
        in_the_way = exc.filename not in (None, str(path)) and os.path.lexists(exc.filename)
        where = f"{exc.filename}: " if in_the_way else ""  # the temporary file (a folder there)
        error = type(exc)(f"cannot write {path}: {where}{exc.strerror or exc}")  # FileNotFoundError...
        error.errno = exc.errno
        raise error from exc


def command_line() -> str:
    """This process's command line, as a shell would take it."""
    try:
        arguments = Path("/proc/self/cmdline").read_bytes().rstrip(b"\0").split(b"\0")
        return shlex.join(a.decode(errors="replace") for a in arguments)
    except OSError:
        return shlex.join([sys.executable, *sys.argv])


class FolderLock:
    """An exclusive ``flock`` on ``folder/name`` for the life of a writer (the kernel drops it
    when the process dies, however it dies); the file names the holder. Held by another
    process: ``error`` (an OSError class) saying "FOLDER is being written by another WHAT
    (its pid, start time and command): ADVICE; nothing was changed"."""

    def __init__(
        self,
        folder: Path,
        name: str,
        what: str,
        advice: str,
        *,
        wait_s: float = 0.0,
        command: str | None = None,
        error: type[OSError] = OSError,
    ):
        self.path, self._fd = folder / name, None
        if fcntl is None:
            return
        try:
            fd = open_file(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        except SymlinkRefused as exc:
            raise error(str(exc)) from None
        except OSError as exc:
            raise error(f"cannot lock {self.path}: {exc.strerror or exc}") from exc
        try:
            refuse_hard_link(fd, self.path)
        except OSError as exc:
            raise error(str(exc)) from None
        deadline = time.monotonic() + wait_s
        while True:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                if time.monotonic() < deadline:
                    time.sleep(0.05)
                    continue
                holder = self._holder(fd)
                os.close(fd)
                raise error(
                    f"{folder} is being written by another {what} ({holder}): {advice}; nothing was changed"
                ) from None
            except OSError as exc:
                os.close(fd)
                raise error(f"cannot lock {self.path}: {exc.strerror or exc}") from exc
        started = datetime.datetime.now().astimezone().isoformat(timespec="seconds")
        info = {"pid": os.getpid(), "command": command or command_line(), "started": started}
        with contextlib.suppress(OSError):  # the lock holds without its description
            os.ftruncate(fd, 0)
            os.pwrite(fd, (json.dumps(info) + "\n").encode(), 0)
        self._fd = fd

    @staticmethod
    def _holder(fd: int) -> str:
        try:
            info = json.loads(os.pread(fd, 65536, 0))
            command = str(info["command"])
            if len(command) > HOLDER_COMMAND_CHARS:
                command = command[:HOLDER_COMMAND_CHARS] + "..."
            return f"pid {info['pid']}, started {info['started']}, command: {command}"
        except (OSError, ValueError, KeyError, TypeError):
            return "a process that has just started"

    def release(self) -> None:
        """Unlock the folder and clear the lock file's holder description; a second call does nothing."""
        if self._fd is not None:
            with contextlib.suppress(OSError):
                os.ftruncate(self._fd, 0)
            os.close(self._fd)  # drops the flock
            self._fd = None


PNG_END = b"\0\0\0\0IEND\xaeB`\x82"  # a PNG's last chunk: IEND, empty, and its CRC


def decode_image(data, flags: int) -> np.ndarray | None:
    """``cv2.imdecode`` of ``data`` (bytes or uint8), None when it holds no picture; a PNG cut
    short (no IEND chunk) is None without being decoded, where libpng and OpenCV would print a
    line of their own on stderr: the caller names the file."""
    data = np.frombuffer(data, np.uint8)
    if not data.size or (data[:8].tobytes() == b"\x89PNG\r\n\x1a\n" and PNG_END not in data.tobytes()):
        return None
    return cv2.imdecode(data, flags)


def png(image: np.ndarray) -> bytes:
    """PNG bytes of an 8-bit image (BGR when it has three channels, as OpenCV writes)."""
    ok, encoded = cv2.imencode(".png", image)
    if not ok:
        raise ValueError(f"PNG encoding of a {image.shape} {image.dtype} image failed")
    return encoded.tobytes()
