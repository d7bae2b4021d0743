"""OPEN-R's wiring files: each object's ``stub.cfg`` and the memory stick's ``CONNECT.CFG``.

stub.cfg (report section 2.1.5), one item a line::

    ObjectName : Controller
    NumOfOSubject : 1
    NumOfOObserver : 1
    Service : "Controller.Image.OFbkImageVectorData.O", null, Notify()

A service name is Object.Subname.Data.Kind with Kind ``S`` (subject) or ``O`` (observer); the
two members are ``null`` or ``Name()``. There must be at least one subject and one observer
(a dummy where none is needed) and exactly as many as ``NumOfOSubject`` / ``NumOfOObserver``
(Sony's stubgen2 also reads ``NumOfSubject`` / ``NumOfObserver``). ``Extra : Name()`` lines
add entries of the object's own (called with a message pointer, as ``OPENR::ObservePowerStatus``
calls one).

CONNECT.CFG (section 2.1.6) has one connection a line, a subject service, white space, an
observer service, both with the same data name. It lives in ``OPEN-R/MW/CONF/`` of the
memory stick, found in any letter case (``find_connect_cfg``). A line ``[ERS-7]`` starts the
lines for one robot design (Sony's CONNECT.CFG, OBJECT.CFG and DESIGNDB.CFG have sections
``[ERS-210]``, ``[ERS-7]``...): lines before any section are every design's, a section's only
its design's (``design_lines``).

Files are ASCII; blank lines, CRLF and ``//`` comment lines (stub.cfg, as in Sony's samples)
or ``#`` comments (CONNECT.CFG) are accepted. Names are case-sensitive, as in OPEN-R. Every
problem raises ``ConfigError`` with the file and line: the first one, found in one pass over
the file (parsing takes time linear in its size), quoting at most ``QUOTE_LIMIT`` characters
of the offending text (a longer one is cut, with its length noted). Only regular files are
read: a FIFO, a device or a folder in a file's place is refused, not waited on.
"""

import os
import re
import stat
from dataclasses import dataclass
from pathlib import Path

from .errors import ConfigError, NotRegularFile

_NAME = r"[A-Za-z_][A-Za-z0-9_]*"
_SERVICE_NAME = re.compile(rf"({_NAME})\.({_NAME})\.({_NAME})\.({_NAME})")
_MEMBER = rf"null|{_NAME}[ \t]*\(\)"  # Sony's stubgen2 takes "Ready ()" too
_STUB_LINE = re.compile(
    r"[ \t]*([A-Za-z]+)[ \t]*:(.*)"
)  # the value is stripped after (a lazy group would backtrack quadratically)
_SERVICE_LINE = re.compile(rf'"([^"]*)"[ \t]*,[ \t]*({_MEMBER})[ \t]*,[ \t]*({_MEMBER})')
_COUNT_KEYS = {"NumOfOSubject": "S", "NumOfOObserver": "O"}
_COUNT_ALIASES = {"NumOfSubject": "NumOfOSubject", "NumOfObserver": "NumOfOObserver"}
KINDS = {"S": "subject", "O": "observer"}
QUOTE_LIMIT = 80  # characters of an offending line or field quoted in a ConfigError


def _quote(text: str) -> str:
    """``repr(text)``, cut to QUOTE_LIMIT characters with a note of the full length."""
    if len(text) <= QUOTE_LIMIT:
        return repr(text)
    return f"{text[:QUOTE_LIMIT]!r}... ({len(text)} characters in all)"


def cut(text) -> str:
    """``str(text)`` cut to QUOTE_LIMIT characters with a note of the full length."""
    text = str(text)
    return text if len(text) <= QUOTE_LIMIT else f"{text[:QUOTE_LIMIT]}... ({len(text)} characters in all)"


@dataclass(frozen=True)
class ServiceName:
    """``Object.Subname.Data.Kind``, Kind ``S`` (subject) or ``O`` (observer)."""

    object: str
    sub: str
    data: str
    kind: str

    def __str__(self) -> str:
        return f"{self.object}.{self.sub}.{self.data}.{self.kind}"


@dataclass(frozen=True)
class Service:
    """A stub.cfg service; the methods are None for ``null``."""

    name: ServiceName
    connect_method: str | None
    notify_method: str | None  # Notify() of an observer, Ready() of a subject
    line: int


@dataclass(frozen=True)
class StubConfig:
    """A parsed stub.cfg: the object's name, its services in listed order, its Extra entries."""

    path: str
    object_name: str
    services: tuple[Service, ...]
    extras: tuple[str, ...] = ()  # the Extra entries' member names, in order

    def of_kind(self, kind: str) -> list[Service]:
        """The services of kind ``kind`` (``"S"`` or ``"O"``), in listed order."""
        return [service for service in self.services if service.name.kind == kind]


@dataclass(frozen=True)
class Connection:
    """A CONNECT.CFG line: subject service to observer service."""

    subject: ServiceName
    observer: ServiceName
    path: str
    line: int


def parse_stub_cfg(source: bytes | str, path: str = "stub.cfg") -> StubConfig:
    """Parse the text of a stub.cfg.

    :param path: the file's name in error messages.
    :raises ConfigError: naming the line of a problem.
    """
    values: dict[str, tuple[str, int]] = {}
    services: list[Service] = []
    extras: list[str] = []
    first_line: dict[ServiceName, int] = {}  # each service's line, for the repeat check
    for number, line in _lines(source, path):
        if not line.strip() or line.lstrip().startswith(("//", "#")):  # comments
            continue
        match = _STUB_LINE.fullmatch(line)
        if not match:
            raise ConfigError(f"expected 'Key : value', got {_quote(line)}", path, number)
        key, value = _COUNT_ALIASES.get(match[1], match[1]), match[2].strip(" \t")
        if key == "Service":
            services.append(_parse_service(value, path, number, first_line))
        elif key == "Extra":
            if not re.fullmatch(rf"{_NAME}\(\)", value):
                raise ConfigError(f"Extra {_quote(value)} is not a member 'Name()'", path, number)
            if value[:-2] in extras:
                raise ConfigError(f"Extra {value} given twice", path, number)
            extras.append(value[:-2])
        elif key in ("ObjectName", *_COUNT_KEYS):
            if key in values:
                raise ConfigError(f"{key} given twice (first on line {values[key][1]})", path, number)
            values[key] = (value, number)
        else:
            raise ConfigError(
                f"unknown item {_quote(key)} (ObjectName, NumOfOSubject, NumOfOObserver, Service, Extra)", path, number
            )

    missing = [key for key in ("ObjectName", *_COUNT_KEYS) if key not in values]
    if missing:
        raise ConfigError(f"no {' and no '.join(missing)} line", path)
    object_name, number = values["ObjectName"]
    if not re.fullmatch(_NAME, object_name):
        raise ConfigError(f"ObjectName {_quote(object_name)} is not a name", path, number)
    for key, kind in _COUNT_KEYS.items():
        count, number = values[key]
        if not re.fullmatch(r"[0-9]+", count):
            raise ConfigError(f"{key} {_quote(count)} is not a number", path, number)
        listed = [service.line for service in services if service.name.kind == kind]
        if int(count) < 1:
            raise ConfigError(f"{key} must be at least 1 (register a dummy {KINDS[kind]})", path, number)
        if int(count) != len(listed):
            raise ConfigError(
                f"{key} is {int(count)} but {len(listed)} {KINDS[kind]} services are listed {cut(listed)}",
                path,
                number,
            )
    return StubConfig(path, object_name, tuple(services), tuple(extras))


ROBOT_DESIGN = "ERS-7"
_SECTION = re.compile(r"[ \t]*\[([^\]]*)\][ \t]*")


def design_lines(source: bytes | str, path: str, design: str = ROBOT_DESIGN):
    """(line number, text without its ``#`` comment) of each non-blank line for ``design``."""
    section = None
    for number, line in _lines(source, path):
        text = line.split("#", 1)[0]
        match = _SECTION.fullmatch(text)
        if match:
            section = match[1].strip()
        elif text.strip() and section in (None, design):
            yield number, text


def parse_connect_cfg(source: bytes | str, path: str = "CONNECT.CFG") -> list[Connection]:
    """The connections of a CONNECT.CFG's text (its lines for the ERS-7), in file order.

    :param path: the file's name in error messages.
    :raises ConfigError: naming the line of a problem.
    """
    connections: list[Connection] = []
    first_line: dict[tuple[ServiceName, ServiceName], int] = {}  # each connection's line, for the repeat check
    names: dict[str, ServiceName] = {}  # each service name's text parsed once
    for number, line in design_lines(source, path):
        fields = line.split()
        if len(fields) != 2:
            raise ConfigError(f"expected 'subject-service observer-service', got {_quote(line.strip())}", path, number)
        subject, observer = (
            names.get(field) or names.setdefault(field, _service_name(field, path, number)) for field in fields
        )
        for name, kind in ((subject, "S"), (observer, "O")):
            if name.kind != kind:
                raise ConfigError(
                    f"{cut(name)} should be {KINDS[kind]} ('.{kind}'), the line being subject then observer",
                    path,
                    number,
                )
        if subject.data != observer.data:
            raise ConfigError(
                f"data names differ: {_quote(subject.data)} is sent, {_quote(observer.data)} expected", path, number
            )
        if (subject, observer) in first_line:
            raise ConfigError(f"connection repeated from line {first_line[subject, observer]}", path, number)
        first_line[subject, observer] = number
        connections.append(Connection(subject, observer, path, number))
    return connections


def load_stub_cfg(path) -> StubConfig:
    """Read and parse the stub.cfg at ``path``; ConfigError naming the file (and line)."""
    return parse_stub_cfg(read_config(path), str(path))


def load_connect_cfg(path) -> list[Connection]:
    """Read and parse the CONNECT.CFG at ``path``; ConfigError naming the file (and line)."""
    return parse_connect_cfg(read_config(path), str(path))


def find_connect_cfg(memory_stick) -> Path:
    """``OPEN-R/MW/CONF/CONNECT.CFG`` under a memory stick folder, in any letter case."""
    return find_in_stick(memory_stick, "CONNECT.CFG")


def find_in_stick(memory_stick, name: str) -> Path:
    """``OPEN-R/MW/CONF/<name>`` under a memory stick folder, in any letter case; ConfigError
    naming the folder where a part is missing (or ambiguous)."""
    found = Path(memory_stick)
    for part in ("OPEN-R", "MW", "CONF", name):
        try:
            matches = [entry for entry in found.iterdir() if entry.name.upper() == part] if found.is_dir() else []
        except OSError as error:
            raise ConfigError(f"cannot list: {error.strerror}", found) from None
        if len(matches) != 1:
            problem = "no" if not matches else "more than one"
            raise ConfigError(f"{problem} {part} (any case) here; expected OPEN-R/MW/CONF/{name}", found)
        found = matches[0]
    return found


def _parse_service(value: str, path: str, number: int, first_line: dict[ServiceName, int]) -> Service:
    match = _SERVICE_LINE.fullmatch(value)
    if not match:
        raise ConfigError(f"expected '\"Object.Sub.Data.S|O\", member, member', got {_quote(value)}", path, number)
    name = _service_name(match[1], path, number)
    if name.kind not in KINDS:
        raise ConfigError(f"service type {_quote(name.kind)} of {cut(name)} is neither S nor O", path, number)
    if name in first_line:
        raise ConfigError(f"service {cut(name)} listed twice (first on line {first_line[name]})", path, number)
    first_line[name] = number
    connect, notify = (None if member == "null" else member[:-2].rstrip(" \t") for member in match.groups()[1:])
    return Service(name, connect, notify, number)


def _service_name(text: str, path: str, number: int) -> ServiceName:
    match = _SERVICE_NAME.fullmatch(text)
    if not match:
        raise ConfigError(f"{_quote(text)} is not a service name Object.Subname.Data.S|O", path, number)
    return ServiceName(*match.groups())


def _lines(source: bytes | str, path: str):
    if isinstance(source, bytes):
        try:
            source = source.decode("ascii")
        except UnicodeDecodeError as error:
            raise ConfigError(
                f"byte {source[error.start]:#04x} is not ASCII", path, source.count(b"\n", 0, error.start) + 1
            ) from None
    ascii_text = source.isascii()  # one check for the whole text; line by line only to name the line
    for number, line in enumerate(source.split("\n"), start=1):
        if not ascii_text and not line.isascii():
            raise ConfigError("non-ASCII text", path, number)
        yield number, line.removesuffix("\r")


def read_regular_file(path) -> bytes:
    """The bytes of a regular file. Opened without blocking, so that a FIFO in its place (which
    a plain open would wait on for a writer) is refused at once, as is any other non-regular file
    (``NotRegularFile`` saying what it is); other failures are the ``OSError`` of the call."""
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            kind = (
                "a FIFO"
                if stat.S_ISFIFO(mode)
                else "a folder"
                if stat.S_ISDIR(mode)
                else "a device"
                if stat.S_ISCHR(mode) or stat.S_ISBLK(mode)
                else "a socket"
                if stat.S_ISSOCK(mode)
                else "a special file"
            )
            raise NotRegularFile(f"{kind}, not a regular file")
        with os.fdopen(fd, "rb", closefd=False) as file:
            return file.read()
    finally:
        os.close(fd)


def read_config(path) -> bytes:
    """``read_regular_file``, its failures a ``ConfigError`` naming the file."""
    try:
        return read_regular_file(path)
    except (OSError, NotRegularFile) as error:
        raise ConfigError(f"cannot read: {getattr(error, 'strerror', None) or error}", path) from None
