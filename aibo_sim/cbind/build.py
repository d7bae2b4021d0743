"""Compiling a C or C++ controller against the Webots-era headers, into a cache.

The executable lands in ``$XDG_CACHE_HOME/aibo-sim/c/<key>/`` (``~/.cache`` without it), the
key a hash of everything that goes into it: the sources' names and bytes, the headers they
include with quotes (found from the including file's folder, as the compiler finds them), the
binding's headers, ``libaibo.c``, the call table, the flags and the compilers' versions. A second
run of unchanged sources and headers compiles nothing. ``CC`` and ``CXX`` choose the compilers
(default ``cc`` and ``c++``).
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import re
import shutil
import signal
import subprocess
from functools import cache
from pathlib import Path

from ..exit_status import scratch_folder
from .protocol import c_header

C_SUFFIXES = (".c", ".cc", ".cpp")
PACKAGE = Path(__file__).resolve().parent
INCLUDE = PACKAGE / "include"
LIBRARY = PACKAGE / "libaibo.c"
# -ffp-contract=off: no fused multiply-add, so that a controller's double arithmetic rounds as
# the source (and Python) says, on every machine.
FLAGS = ("-O2", "-ffp-contract=off", "-pthread")
COMPILER_STOP_S = 2.0  # after SIGTERM, for a compiler's processes to remove their temporary files
QUOTED_INCLUDE = re.compile(rb'^[ \t]*#[ \t]*include[ \t]*"([^"\n]+)"', re.MULTILINE)
INSTALL_HINT = {
    "cc": "a C compiler (Debian/Ubuntu: apt-get install gcc)",
    "c++": "a C++ compiler (Debian/Ubuntu: apt-get install g++)",
}


class CompileError(RuntimeError):
    """No compiler, or the compiler refused the controller: the message says which, or is the
    compiler's own output (file:line: error ...)."""


def is_c_controller(path: str | os.PathLike) -> bool:
    """A C or C++ source file, or a folder holding one named like the folder."""
    path = Path(path)
    if path.is_dir():
        return any((path / (path.name + suffix)).is_file() for suffix in C_SUFFIXES)
    return path.suffix in C_SUFFIXES


def controller_sources(path: str | os.PathLike) -> tuple[Path, list[Path]]:
    """(main file, all sources) of a controller file or folder (its C and C++ files, not below)."""
    path = Path(path).resolve()
    if path.is_dir():
        main = next((path / (path.name + s) for s in C_SUFFIXES if (path / (path.name + s)).is_file()), None)
        if main is None:
            raise FileNotFoundError(
                f"{path}: no {' or '.join(path.name + s for s in C_SUFFIXES)} in this controller folder"
            )
        return main, sorted(p for p in path.iterdir() if p.suffix in C_SUFFIXES and p.is_file())
    if not path.is_file():
        raise FileNotFoundError(f"{path}: " + ("not a regular file" if path.exists() else "no such controller file"))
    return path, [path]


def local_headers(sources: list[Path]) -> list[Path]:
    """The headers that ``sources`` include with quotes, and those include in turn, found from the
    including file's folder (every ``#include "..."`` line, whatever the conditions around it)."""
    found: dict[Path, None] = {}
    pending = list(sources)
    while pending:
        including = pending.pop()
        for name in QUOTED_INCLUDE.findall(including.read_bytes()):
            header = (including.parent / os.fsdecode(name)).resolve()
            if header.exists() and not header.is_file():  # a FIFO the compiler would wait on for ever
                raise OSError(f"{header}: included by {including}: not a regular file")
            if header not in found and header not in sources and header.is_file():
                found[header] = None
                pending.append(header)
    return sorted(found)


def own_files(main: Path, sources: list[Path]) -> list[tuple[str, Path]]:
    """The controller's own files, each with its name in the compile cache's key and a dump's hash:
    the sources by their names, the headers they include with quotes (``local_headers``) by their
    paths from the main file's folder (a controller copied elsewhere keeps its key)."""
    headers = [(os.path.relpath(h, main.parent), h) for h in local_headers(sources)]
    return [(s.name, s) for s in sources] + headers


def _compiler(kind: str, needed_by: str = "this controller") -> str:
    """The path of the C (``cc``) or C++ (``c++``) compiler; CompileError naming it when missing
    (``needed_by`` says what needs it)."""
    variable = "CC" if kind == "cc" else "CXX"
    name = os.environ.get(variable) or kind
    found = shutil.which(name)
    if found is None:
        words = name.split()
        if len(words) > 1 and shutil.which(words[0]):
            raise CompileError(
                f"{variable}={name!r}: set {variable} to the compiler alone ({words[0]!r}): aibo-sim gives it its flags"
            )
        raise CompileError(f"no compiler {name!r} found: {needed_by} needs {INSTALL_HINT[kind]}, or set {variable}")
    return found


@cache
def _version(compiler: str) -> bytes:
    """What ``compiler --version`` says (asked once a process: each run and dump shard compiles)."""
    return subprocess.run([compiler, "--version"], capture_output=True).stdout


def _cache_root() -> Path:
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "aibo-sim" / "c"


def compile_controller(path: str | os.PathLike) -> Path:
    """The executable of the controller at ``path`` (file or folder), compiled if it is not
    in the cache; CompileError with the compiler's messages when it does not compile."""
    main, sources = controller_sources(path)
    compilers = {"cc": _compiler("cc")}
    if any(s.suffix != ".c" for s in sources):
        compilers["c++"] = _compiler("c++")
    header = c_header()
    digest = hashlib.sha256()
    for part in (
        *FLAGS,
        header,
        LIBRARY.read_text(),
        *(f.read_text() for f in sorted(INCLUDE.rglob("*.h"))),
        *(compilers[k].encode() + _version(compilers[k]) for k in sorted(compilers)),
    ):
        digest.update(part.encode() if isinstance(part, str) else part)
        digest.update(b"\0")
    for name, file in own_files(main, sources):
        digest.update(name.encode() + b"\0" + file.read_bytes() + b"\0")
    folder = _cache_root() / digest.hexdigest()[:32]
    executable = folder / main.stem
    if executable.is_file():
        return executable
    folder.parent.mkdir(parents=True, exist_ok=True)
    with scratch_folder(".build-", folder.parent) as build:
        (build / "aibo_ops.h").write_text(header)
        objects = []
        for source in [LIBRARY, *sources]:
            compiler = compilers["cc" if source.suffix == ".c" else "c++"]
            objects.append(build / f"{len(objects)}_{source.stem}.o")
            _run(
                [compiler, *FLAGS, "-I", str(INCLUDE), "-I", str(build), "-c", str(source), "-o", str(objects[-1])],
                source,
                "compiling",
            )
        command = [
            compilers.get("c++", compilers["cc"]),
            *map(str, objects),
            "-o",
            str(build / main.stem),
            "-pthread",
            "-lm",
        ]
        _run(command, main, "linking")
        try:
            os.replace(build, folder)  # whole or not at all; a racing build of the same key may have won
        except OSError:
            if not executable.is_file():
                raise
        else:
            build.mkdir()  # for TemporaryDirectory's clean-up
    return executable


def _run(command: list[str], source: Path, step: str) -> None:
    """Run a compiler ``step`` on ``source``; CompileError naming it, then the compiler's messages.
    Stopped (Ctrl-C, SIGTERM), its whole process group stops: its cc1 and as too, which outlived
    aibo-sim, their temporary files left in /tmp."""
    compiler = subprocess.Popen(  # errors="replace": it quotes the source's bytes
        command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, errors="replace", start_new_session=True
    )
    try:
        stdout, stderr = compiler.communicate()
    except BaseException:
        _stop_group(compiler)
        raise
    if compiler.returncode != 0:
        messages = (stderr or stdout).rstrip()
        raise CompileError(f"{source}: {step} failed" + (f":\n{messages}" if messages else ""))


def _stop_group(process: subprocess.Popen) -> None:
    """SIGTERM to ``process``'s group (gcc's passes then remove their temporary files), SIGKILL to
    what is left once its leader ended or after ``COMPILER_STOP_S``; reaped."""
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(process.pid, signal.SIGTERM)
    with contextlib.suppress(subprocess.TimeoutExpired):
        process.communicate(timeout=COMPILER_STOP_S)
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(process.pid, signal.SIGKILL)
    process.communicate()
