"""OPEN-R's wiring files: each object's ``stub.cfg`` and the memory stick's ``CONNECT.CFG``.

stub.cfg (report section 2.1.5), one item a line::

    ObjectName : Controller
    NumOfOSubject : 1
    NumOfOObserver : 1
    Service : "Controller.Image.OFbkImageVectorData.O", null, Notify()

A service name is Object.Subname.Data.Kind with Kind ``S`` (subject) or ``O`` (observer); the
two members are ``null`` or ``Name()``. There must be at least one subject and one observer
(a dummy where none is needed) and exactly as many as ``NumOfOSubject`` / ``NumOfOObserver``.

CONNECT.CFG (section 2.1.6) has one connection a line, a subject service, white space, an
observer service, both with the same data name. It lives in ``OPEN-R/MW/CONF/`` of the
memory stick, found in any letter case (``find_connect_cfg``).

Files are ASCII; blank lines, CRLF and ``//`` comment lines (stub.cfg, as in Sony's samples)
or ``#`` comments (CONNECT.CFG) are accepted. Names are case-sensitive, as in OPEN-R. Every
problem raises ``ConfigError`` with the file and line.
"""

import re
from dataclasses import dataclass
from pathlib import Path

from .errors import ConfigError

_NAME = r"[A-Za-z_][A-Za-z0-9_]*"
_SERVICE_NAME = re.compile(rf"({_NAME})\.({_NAME})\.({_NAME})\.({_NAME})")
_MEMBER = rf"null|{_NAME}\(\)"
_STUB_LINE = re.compile(r"[ \t]*([A-Za-z]+)[ \t]*:[ \t]*(.*?)[ \t]*")
_SERVICE_LINE = re.compile(rf'"([^"]*)"[ \t]*,[ \t]*({_MEMBER})[ \t]*,[ \t]*({_MEMBER})')
_COUNT_KEYS = {"NumOfOSubject": "S", "NumOfOObserver": "O"}
KINDS = {"S": "subject", "O": "observer"}


@dataclass(frozen=True)
class ServiceName:
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
    path: str
    object_name: str
    services: tuple[Service, ...]

    def of_kind(self, kind: str) -> list[Service]:
        return [service for service in self.services if service.name.kind == kind]


@dataclass(frozen=True)
class Connection:
    """A CONNECT.CFG line: subject service to observer service."""

    subject: ServiceName
    observer: ServiceName
    path: str
    line: int


def parse_stub_cfg(source: bytes | str, path: str = "stub.cfg") -> StubConfig:
    values: dict[str, tuple[str, int]] = {}
    services: list[Service] = []
    for number, line in _lines(source, path):
        if not line.strip() or line.lstrip().startswith("//"):
            continue
        match = _STUB_LINE.fullmatch(line)
        if not match:
            raise ConfigError(f"expected 'Key : value', got {line!r}", path, number)
        key, value = match.groups()
        if key == "Service":
            services.append(_parse_service(value, path, number, services))
        elif key in ("ObjectName", *_COUNT_KEYS):
            if key in values:
                raise ConfigError(f"{key} given twice (first on line {values[key][1]})", path, number)
            values[key] = (value, number)
        else:
            raise ConfigError(
                f"unknown item {key!r} (ObjectName, NumOfOSubject, NumOfOObserver, Service)", path, number
            )

    missing = [key for key in ("ObjectName", *_COUNT_KEYS) if key not in values]
    if missing:
        raise ConfigError(f"no {' and no '.join(missing)} line", path)
    object_name, number = values["ObjectName"]
    if not re.fullmatch(_NAME, object_name):
        raise ConfigError(f"ObjectName {object_name!r} is not a name", path, number)
    for key, kind in _COUNT_KEYS.items():
        count, number = values[key]
        if not re.fullmatch(r"[0-9]+", count):
            raise ConfigError(f"{key} {count!r} is not a number", path, number)
        listed = [service.line for service in services if service.name.kind == kind]
        if int(count) < 1:
            raise ConfigError(f"{key} must be at least 1 (register a dummy {KINDS[kind]})", path, number)
        if int(count) != len(listed):
            raise ConfigError(
                f"{key} is {int(count)} but {len(listed)} {KINDS[kind]} services are listed {listed}", path, number
            )
    return StubConfig(path, object_name, tuple(services))


def parse_connect_cfg(source: bytes | str, path: str = "CONNECT.CFG") -> list[Connection]:
    connections: list[Connection] = []
    for number, line in _lines(source, path):
        fields = line.split("#", 1)[0].split()
        if not fields:
            continue
        if len(fields) != 2:
            raise ConfigError(f"expected 'subject-service observer-service', got {line.strip()!r}", path, number)
        subject, observer = (_service_name(field, path, number) for field in fields)
        for name, kind in ((subject, "S"), (observer, "O")):
            if name.kind != kind:
                raise ConfigError(
                    f"{name} should be {KINDS[kind]} ('.{kind}'), the line being subject then observer", path, number
                )
        if subject.data != observer.data:
            raise ConfigError(f"data names differ: {subject.data!r} is sent, {observer.data!r} expected", path, number)
        for earlier in connections:
            if (earlier.subject, earlier.observer) == (subject, observer):
                raise ConfigError(f"connection repeated from line {earlier.line}", path, number)
        connections.append(Connection(subject, observer, path, number))
    return connections


def load_stub_cfg(path) -> StubConfig:
    return parse_stub_cfg(_read(path), str(path))


def load_connect_cfg(path) -> list[Connection]:
    return parse_connect_cfg(_read(path), str(path))


def find_connect_cfg(memory_stick) -> Path:
    """``OPEN-R/MW/CONF/CONNECT.CFG`` under a memory stick folder, in any letter case."""
    found = Path(memory_stick)
    for part in ("OPEN-R", "MW", "CONF", "CONNECT.CFG"):
        try:
            matches = [entry for entry in found.iterdir() if entry.name.upper() == part] if found.is_dir() else []
        except OSError as error:
            raise ConfigError(f"cannot list: {error.strerror}", found) from None
        if len(matches) != 1:
            problem = "no" if not matches else "more than one"
            raise ConfigError(f"{problem} {part} (any case) here; expected OPEN-R/MW/CONF/CONNECT.CFG", found)
        found = matches[0]
    return found


def _parse_service(value: str, path: str, number: int, earlier: list[Service]) -> Service:
    match = _SERVICE_LINE.fullmatch(value)
    if not match:
        raise ConfigError(f"expected '\"Object.Sub.Data.S|O\", member, member', got {value!r}", path, number)
    name = _service_name(match[1], path, number)
    if name.kind not in KINDS:
        raise ConfigError(f"service type {name.kind!r} of {name} is neither S nor O", path, number)
    for service in earlier:
        if service.name == name:
            raise ConfigError(f"service {name} listed twice (first on line {service.line})", path, number)
    connect, notify = (None if member == "null" else member[:-2] for member in match.groups()[1:])
    return Service(name, connect, notify, number)


def _service_name(text: str, path: str, number: int) -> ServiceName:
    match = _SERVICE_NAME.fullmatch(text)
    if not match:
        raise ConfigError(f"{text!r} is not a service name Object.Subname.Data.S|O", path, number)
    return ServiceName(*match.groups())


def _lines(source: bytes | str, path: str):
    if isinstance(source, bytes):
        try:
            source = source.decode("ascii")
        except UnicodeDecodeError as error:
            raise ConfigError(
                f"byte {source[error.start]:#04x} is not ASCII", path, source.count(b"\n", 0, error.start) + 1
            ) from None
    for number, line in enumerate(source.split("\n"), start=1):
        if not line.isascii():
            raise ConfigError("non-ASCII text", path, number)
        yield number, line.removesuffix("\r")


def _read(path) -> bytes:
    try:
        return Path(path).read_bytes()
    except OSError as error:
        raise ConfigError(f"cannot read: {error.strerror}", path) from None
