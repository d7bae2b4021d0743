"""A memory stick folder as the ERS-7 reads it: ``OPEN-R/MW/CONF/OBJECT.CFG``, ``CONNECT.CFG``,
``DESIGNDB.CFG`` and the files they name.

- OBJECT.CFG: one object a line, a ``/MS/...`` path to its ``.BIN`` (the gzipped object
  ``make install`` writes); ``#`` comments; ``[ERS-7]`` sections (``config.design_lines``).
- CONNECT.CFG (optional): subject-observer lines (``config.parse_connect_cfg``).
- DESIGNDB.CFG (optional): ``KEYWORD /MS/path`` lines, what ``OPENR::FindDesignData`` finds.

``/MS/...`` paths name files of the folder: each name is found ignoring case, as on the stick's
FAT (``stick_path``); a path that is not on the stick or climbs out of it is a ``ConfigError``.
Every problem names the file and line.
"""

import gzip
import struct
import zlib
from dataclasses import dataclass
from pathlib import Path

from .config import ConfigError, Connection, _quote, design_lines, find_in_stick, parse_connect_cfg, read_config

GZIP_MAGIC = b"\x1f\x8b"


def _elf_kind(header: bytes) -> bytes:
    """An ELF file's magic, class (32 or 64 bits), byte order and machine (e_machine)."""
    return header[:6] + header[18:20]


@dataclass(frozen=True)
class StickObject:
    """An OBJECT.CFG line: the ``/MS`` path as written, its file, the line."""

    ms_path: str
    file: Path
    line: int

    @property
    def name(self) -> str:
        """The file's name without its suffix (``HELLO`` for HELLO.BIN)."""
        return Path(self.ms_path).stem.upper()


@dataclass(frozen=True)
class MemoryStick:
    """A memory stick's OBJECT.CFG objects, CONNECT.CFG connections and DESIGNDB.CFG entries."""

    root: Path
    objects: tuple[StickObject, ...]
    connections: tuple[Connection, ...]
    design_data: dict  # keyword -> /MS path

    @property
    def object_cfg(self) -> Path:
        """The stick's ``OPEN-R/MW/CONF/OBJECT.CFG`` (any letter case)."""
        return find_in_stick(self.root, "OBJECT.CFG")

    def check_objects(self) -> None:
        """Read every object (``read_object``): a ConfigError naming the OBJECT.CFG line of one
        that is missing or not built for this machine, before a run writes anything."""
        for stick_object in self.objects:
            read_object(stick_object, self.object_cfg)


def is_memory_stick(folder) -> bool:
    """Whether ``folder`` holds ``OPEN-R/MW/CONF/OBJECT.CFG`` (any case)."""
    try:
        find_in_stick(folder, "OBJECT.CFG")
    except ConfigError:
        return False
    return True


def memory_stick_folder(path) -> Path | None:
    """The memory stick ``path`` names: the folder itself, or its ``MS`` (a program's folder, as
    Sony's samples and ``aibo-sim build-ms`` lay them out); None when neither is one."""
    path = Path(path)
    if not path.is_dir():
        return None
    for folder in (path, path / "MS"):
        if is_memory_stick(folder):
            return folder
    return None


# What a memory stick's names may hold besides the dot (Sony's Programmer's Guide, A.1).
NAME_CHARACTERS = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789$&#{}~%'()-@^`!_")


def is_8_3(name: str) -> bool:
    """Whether the robot's memory stick takes ``name`` (Sony's Programmer's Guide, A.1): up to 8
    characters, then up to 3 after one dot, each a letter, a digit or one of ``$&#{}~%'()-@^`!_``."""
    base, _, extension = name.partition(".")
    return 0 < len(base) <= 8 and len(extension) <= 3 and set(base + extension) <= NAME_CHARACTERS


def stick_path(root: Path, ms_path: str, config: Path, line: int) -> Path:
    """The file of the folder ``root`` that ``/MS/...`` names (names matched ignoring case; a
    missing one kept as written), or ConfigError naming ``config`` and ``line``; every name 8.3,
    as the robot requires (Sony's Programmer's Guide, A.1)."""
    if ms_path[:4].upper() != "/MS/":
        raise ConfigError(f"{_quote(ms_path)} is not on the memory stick (a path must begin with /MS/)", config, line)
    found = root
    for part in ms_path[4:].split("/"):
        if part in ("", "."):
            continue
        if part == "..":
            raise ConfigError(f"{_quote(ms_path)} climbs out of the memory stick", config, line)
        if not is_8_3(part):
            raise ConfigError(
                f"{_quote(ms_path)}: {_quote(part)} is not an 8.3 name of letters, digits and $&#{{}}~%'()-@^`!_ "
                "(the robot's memory stick has no other names)",
                config,
                line,
            )
        matches = [entry for entry in found.iterdir() if entry.name.upper() == part.upper()] if found.is_dir() else []
        found = matches[0] if len(matches) == 1 else found / part
    return found


def load_memory_stick(folder) -> MemoryStick:
    """The memory stick in ``folder``; ConfigError naming the file and line of a problem."""
    root = Path(folder)
    object_cfg = find_in_stick(root, "OBJECT.CFG")
    objects = []
    for number, text in design_lines(read_config(object_cfg), str(object_cfg)):
        fields = text.split()
        if len(fields) != 1:
            raise ConfigError(f"expected one /MS/... path to an object, got {_quote(text.strip())}", object_cfg, number)
        objects.append(StickObject(fields[0], stick_path(root, fields[0], object_cfg, number), number))
    if not objects:
        raise ConfigError("lists no object (one /MS/OPEN-R/MW/OBJS/NAME.BIN a line)", object_cfg)
    connections: list[Connection] = []
    design_data: dict[str, str] = {}
    for name in ("CONNECT.CFG", "DESIGNDB.CFG"):
        try:
            path = find_in_stick(root, name)
        except ConfigError:
            continue
        if name == "CONNECT.CFG":
            connections = parse_connect_cfg(read_config(path), str(path))
            continue
        for number, text in design_lines(read_config(path), str(path)):
            fields = text.split()
            if len(fields) != 2:
                raise ConfigError(f"expected 'KEYWORD /MS/path', got {_quote(text.strip())}", path, number)
            stick_path(root, fields[1], path, number)
            design_data[fields[0]] = fields[1]
    return MemoryStick(root, tuple(objects), tuple(connections), design_data)


def read_object(stick_object: StickObject, config: Path) -> bytes:
    """The loadable object of an OBJECT.CFG line: its .BIN ungzipped (a plain one as it is);
    ConfigError naming the line when it is missing or neither."""
    try:
        data = stick_object.file.read_bytes()
    except OSError as error:
        hint = " (not built? run make install in the program's folder)" if not stick_object.file.exists() else ""
        raise ConfigError(
            f"cannot read {stick_object.ms_path}: {error.strerror or error}{hint}", config, stick_object.line
        ) from None
    if data[:2] == GZIP_MAGIC:
        try:
            data = gzip.decompress(data)
        except (OSError, EOFError, zlib.error) as error:
            raise ConfigError(
                f"{stick_object.ms_path} is a damaged gzip file: {error}", config, stick_object.line
            ) from None
    with open("/proc/self/exe", "rb") as interpreter:  # this process's executable
        this_machine = _elf_kind(interpreter.read(20))
    if _elf_kind(data[:20]) != this_machine:  # not ELF, or a robot's MIPS ELF32
        raise ConfigError(
            f"{stick_object.ms_path} is not an object built for this machine (a Sony SDK build for the "
            "robot? rebuild with OPENRSDK_ROOT=$(aibo-sim openr sdk))",
            config,
            stick_object.line,
        )
    extent = _elf_extent(data)
    if extent > len(data):  # the loader would read past its end (SIGBUS)
        raise ConfigError(
            f"{stick_object.ms_path} is cut short: its headers reach byte {extent}, it has {len(data)} "
            "(rebuild it with make install)",
            config,
            stick_object.line,
        )
    return data


def _elf_extent(data: bytes) -> int:
    """How many bytes an ELF file's headers say it holds: its program and section header tables
    and its segments' contents (more than it has where even those tables are cut)."""
    order, wide = "<" if data[5] == 1 else ">", data[4] == 2
    word, offset_at, size_at = ("Q", 8, 32) if wide else ("I", 4, 16)  # in a program header
    try:
        phoff, shoff = struct.unpack_from(order + word * 2, data, 32 if wide else 28)
        phentsize, phnum, shentsize, shnum = struct.unpack_from(order + "HHHH", data, 54 if wide else 42)
        extent = max(phoff + phnum * phentsize, shoff + shnum * shentsize)
        for at in range(phoff, phoff + phnum * phentsize, phentsize or 1):  # a .o has none (size 0)
            offset, size = (struct.unpack_from(order + word, data, at + k)[0] for k in (offset_at, size_at))
            extent = max(extent, offset + size)
    except struct.error:
        return len(data) + 1
    return extent
