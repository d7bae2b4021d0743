"""Files written whole or not at all, never through a symbolic link; folder locks; and the PNG
bytes every writer of pictures uses.

Where aibo-sim writes (a run's, a dump's or a render's folder) it creates, appends to, locks
and reads only its own files: a symbolic link planted in the place of one of them, or of a
folder it writes in, is refused (``SymlinkRefused``, one line naming it), never followed: each
write reaches its folder part by part (``open_folder``), so a link put in a folder's place during
a run is refused too. The folder the user names (``--out``) is resolved once at the start, so it
may itself be a link."""

from __future__ import annotations

import contextlib
import datetime
import errno
import hashlib
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
# A folder on the way is only passed through (O_PATH: no read permission needed, as a path's folders).
_FOLDER_FLAGS = getattr(os, "O_PATH", os.O_RDONLY) | getattr(os, "O_DIRECTORY", 0) | _NO_FOLLOW
HOLDER_COMMAND_CHARS = 300  # a lock holder's command line is cut to this in messages
MAX_NAME_BYTES = 255  # the longest file name Linux's file systems hold (NAME_MAX)


class SymlinkRefused(OSError):
    """A symbolic link where aibo-sim reads or writes a file or folder of its own."""

    @classmethod
    def at(cls, path) -> SymlinkRefused:
        """The error for the symbolic link at ``path``, saying what to do instead."""
        return cls(
            f"{path} is a symbolic link: refusing to follow it (aibo-sim reads and writes only its own "
            "files there); remove it or choose another folder"
        )


def _named(exc: OSError, path) -> OSError:
    """``exc`` naming ``path``: a call relative to a folder's descriptor names only the last part."""
    return type(exc)(exc.errno, exc.strerror, str(path))


def named_file(path) -> Path:
    """The file a user named, its folder resolved once: a link to a folder on its way is the
    user's choice (as ``--out`` is), the file itself is never followed."""
    path = Path(path)
    try:
        return path.absolute().parent.resolve() / path.name
    except RuntimeError:  # Python 3.11's word for a loop of links (an OSError from 3.13)
        raise OSError(errno.ELOOP, os.strerror(errno.ELOOP), str(path.parent)) from None


def _mode(folder_fd: int, name: str) -> int:
    """The kind and permissions of ``name`` in the folder open at ``folder_fd`` (a link's own); 0
    where there is none (or it cannot be looked at)."""
    try:
        return os.stat(name, dir_fd=folder_fd, follow_symlinks=False).st_mode
    except OSError:
        return 0


def _is_link(folder_fd: int, name: str) -> bool:
    return stat.S_ISLNK(_mode(folder_fd, name))


def open_folder(folder, create: bool = False) -> int:
    """A descriptor of ``folder``, reached part by part without following a symbolic link
    (``SymlinkRefused`` names the first part that is one): what is written through it stays in
    the folder aibo-sim made or checked, even where a link takes its place during a run (a
    relative ``folder`` is reached from the working folder). ``create``: missing parts are made."""
    folder = Path(folder)
    fd = os.open(folder.anchor or ".", _FOLDER_FLAGS)
    try:
        for depth in range(len(folder.parts)):
            if depth == 0 and folder.anchor:
                continue
            name, reached = folder.parts[depth], Path(*folder.parts[: depth + 1])
            try:
                inner = _open_folder_in(fd, name, reached)
            except FileNotFoundError:
                if not create:
                    raise
                try:
                    os.mkdir(name, dir_fd=fd)
                except FileExistsError:
                    pass  # made by another process meanwhile
                except OSError as exc:
                    raise _named(exc, reached) from None
                inner = _open_folder_in(fd, name, reached)
            os.close(fd)
            fd = inner
    except BaseException:
        os.close(fd)
        raise
    return fd


def _open_folder_in(folder_fd: int, name: str, path: Path) -> int:
    """The descriptor of the folder ``name`` (at ``path``) in the folder open at ``folder_fd``."""
    try:
        return os.open(name, _FOLDER_FLAGS, dir_fd=folder_fd)
    except OSError as exc:
        raise (SymlinkRefused.at(path) if _is_link(folder_fd, name) else _named(exc, path)) from None


@contextlib.contextmanager
def _folder_of(path: Path):
    """The descriptor of ``path``'s folder (``open_folder``), closed after the block."""
    fd = open_folder(path.parent)
    try:
        yield fd
    finally:
        os.close(fd)


def _open_in(folder_fd: int, path: Path, flags: int, mode: int = 0o666) -> int:
    """``os.open`` of ``path``'s name in the folder open at ``folder_fd``, never following a link."""
    try:
        return os.open(path.name, flags | _NO_FOLLOW, mode, dir_fd=folder_fd)
    except OSError as exc:
        if exc.errno in (errno.ELOOP, errno.EEXIST) and _is_link(folder_fd, path.name):
            raise SymlinkRefused.at(path) from None
        raise _named(exc, path) from None


def open_file(path, flags: int, mode: int = 0o666) -> int:
    """``os.open`` that follows no symbolic link, neither at ``path`` nor at a folder on its way
    (``SymlinkRefused``)."""
    path = Path(path)
    with _folder_of(path) as folder_fd:
        return _open_in(folder_fd, path, flags, mode)


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
    """The folder ``path``, made with its parents if missing; ``SymlinkRefused`` when it, or a
    folder above it, is a link, NotADirectoryError naming it when it is a file."""
    os.close(open_folder(path, create=True))
    return Path(path)


def list_folder(folder) -> list[str]:
    """The names in ``folder``, reached as ``open_folder`` reaches it (never through a link)."""
    fd = open_folder(folder)
    try:
        listed = os.open(".", os.O_RDONLY | getattr(os, "O_DIRECTORY", 0) | _NO_FOLLOW, dir_fd=fd)
    except OSError as exc:
        raise _named(exc, folder) from None
    finally:
        os.close(fd)
    try:
        return os.listdir(listed)
    finally:
        os.close(listed)


def remove_in(folder, names) -> None:
    """Remove the regular files ``names`` in ``folder`` (reached as ``open_folder`` reaches it):
    where a link has taken the folder's place, nothing is removed where it points; a link, a
    folder or anything else of such a name is left, as is what cannot be removed."""
    try:
        fd = open_folder(folder)
    except OSError:
        return
    try:
        for name in names:
            _remove_file(fd, name)
    finally:
        os.close(fd)


def _remove_file(folder_fd: int, name: str) -> None:
    """Unlink ``name`` in the folder open at ``folder_fd`` where it is a regular file (a link or a
    folder of that name is not ours); what cannot be removed is left."""
    if stat.S_ISREG(_mode(folder_fd, name)):
        with contextlib.suppress(OSError):
            os.unlink(name, dir_fd=folder_fd)


def rename_in(folder, name: str, new_name: str) -> None:
    """Rename ``name`` to ``new_name`` (replacing it) in ``folder``, reached as ``open_folder``
    reaches it; an OSError names the new path."""
    fd = open_folder(folder)
    try:
        os.replace(name, new_name, src_dir_fd=fd, dst_dir_fd=fd)
    except OSError as exc:
        raise _named(exc, Path(folder, new_name)) from None
    finally:
        os.close(fd)


def create_file(temp: Path, folder_fd: int | None = None) -> int:
    """A new file at ``temp``, opened for writing; a regular file already there (the temporary
    file of a writer that was killed, an earlier run's log) is replaced, never written through
    (a hard link to another file stays as it was), a symbolic link refused. ``folder_fd``: its
    folder's descriptor, when the caller holds one."""
    if folder_fd is None:
        with _folder_of(temp) as folder_fd:
            return create_file(temp, folder_fd)
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL
    try:
        return _open_in(folder_fd, temp, flags)
    except FileExistsError:
        try:
            os.unlink(temp.name, dir_fd=folder_fd)
        except OSError as exc:
            raise _named(exc, temp) from None
        return _open_in(folder_fd, temp, flags)


def temporary_path(path: Path) -> Path:
    """Where ``write_file_atomic`` writes ``path`` first, by default: ``.NAME.tmp`` beside it, or
    ``.HASH.tmp`` for a name too long to take five bytes more (a file system's names hold 255)."""
    name = f".{path.name}.tmp"
    if len(os.fsencode(name)) > MAX_NAME_BYTES:
        name = f".{hashlib.sha256(os.fsencode(path.name)).hexdigest()[:32]}.tmp"
    return path.with_name(name)


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
    fails (a full disk) leaves the earlier set as it was. Each folder is reached once
    (``open_folder``) and written through its descriptor: a link put in its place meanwhile is
    neither followed nor written through."""
    temps = {path: (temps or {}).get(path) or temporary_path(path) for path in files}
    folders: dict[Path, int] = {}

    def folder(path: Path) -> int:
        if path.parent not in folders:
            folders[path.parent] = open_folder(path.parent)
        return folders[path.parent]

    path, created = None, []
    try:
        for path, data in files.items():
            temp = temps[path]
            folder_fd = folder(temp)
            created.append(temp)  # before it exists: a signal right after it is made still finds it
            with open(create_file(temp, folder_fd), "wb") as file:
                file.write(data)
                if durable:
                    file.flush()
                    os.fsync(file.fileno())
        for path in files:  # os.replace would refuse a folder after renaming the others
            if stat.S_ISDIR(_mode(folder(path), path.name)):
                raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(path))
        for path, temp in temps.items():
            try:
                os.replace(temp.name, path.name, src_dir_fd=folder(temp), dst_dir_fd=folder(path))
            except OSError as exc:
                raise _named(exc, path) from None
    except BaseException as exc:
        for temp in created:
            if temp.parent in folders:
                _remove_file(folders[temp.parent], temp.name)
        if not isinstance(exc, OSError) or isinstance(exc, SymlinkRefused):
            raise
        in_the_way = exc.filename not in (None, str(path)) and os.path.lexists(exc.filename)
        where = f"{exc.filename}: " if in_the_way else ""  # the temporary file (a folder there)
        error = type(exc)(f"cannot write {path}: {where}{exc.strerror or exc}")  # FileNotFoundError...
        error.errno = exc.errno
        raise error from exc
    finally:
        for fd in folders.values():
            os.close(fd)


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
