"""The host OPEN-R SDK: an ``OPENRSDK_ROOT`` that Sony's sample Makefiles build against, unchanged.

``sdk_root()`` makes it once (in ``$XDG_CACHE_HOME/aibo-sim/openr-sdk/<key>/``, the key a hash
of everything that goes in) and returns its path; ``aibo-sim openr sdk`` prints it::

    bin/mipsel-linux-g++, -gcc     the host compiler (CXX, CC) at C++98 (gnu++98), position-
                                   independent, without fused multiply-add, with the headers'
                                   include paths
    bin/mipsel-linux-strip, -ar, -ranlib
    OPEN_R/bin/stubgen2            openr_bridge.stubgen: stub.cfg -> def.h, entry.h, <Name>Stub.*
    OPEN_R/bin/gzcp                gzip -c FROM > TO (whole or not at all, never through a link)
    OPEN_R/bin/mkbin               links an object's .o and .a files into a loadable object
                                   (a shared library; the .ocf loader hints are read and ignored)
    OPEN_R/bin/openr-host          the runtime aibo-sim starts to run a memory stick
    OPEN_R/include (+ R4000)       openr_bridge/sdk/include: our headers with Sony's names
    OPEN_R/lib                     libOPENR.so (openr_bridge/sdk/src), libObjectComm.so (part of it)

``make OPENRSDK_ROOT=$(aibo-sim openr sdk) install`` then writes each object, gzipped, to
``MS/OPEN-R/MW/OBJS/<NAME>.BIN``, as for the robot.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import stat
import sys
from pathlib import Path

import openr_bridge
from openr_bridge.host_protocol import c_header

from ..cbind.build import _compiler, _run, _version
from ..exit_status import scratch_folder

SOURCES = Path(openr_bridge.__file__).resolve().parent / "sdk"
# What every object and the library are compiled with: Sony's SDK compiled C++98 (GCC 3.3), whose
# old code today's compilers refuse unless permissive; objects are shared libraries; no fused
# multiply-add, so that an object's double arithmetic rounds as the source (and Python, and a C
# controller compiled by aibo_sim.cbind) says, on every machine.
CXXFLAGS = ("-std=gnu++98", "-fPIC", "-fpermissive", "-Wno-deprecated-declarations", "-ffp-contract=off")
CFLAGS = ("-fPIC", "-ffp-contract=off")
LIBRARY_SOURCES = ("kernel.cc", "objcomm.cc", "robot.cc", "msfs.cc", "interpose.c")


def _script(path: Path, text: str) -> None:
    path.write_text(text)
    path.chmod(path.stat().st_mode | stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH)


# gzip -c FROM > TO, TO written whole or not at all and never through a link (one there is
# replaced; a folder there is an error: mv -T): through a temporary name the shell creates anew
# (set -C), removed if stopped
GZCP = """#!/bin/sh
set -C
temporary="$2.$$.tmp"
trap 'rm -f "$temporary"' EXIT
trap 'rm -f "$temporary"; exit 1' HUP INT TERM
gzip -c "$1" > "$temporary" && mv -fT "$temporary" "$2"
"""


def _tool_scripts(root: Path, cxx: str, cc: str) -> dict[Path, str]:
    """The SDK's commands: shell wrappers of the host tools, Python entry points of ours."""
    include = f'-I"{root}/OPEN_R/include" -I"{root}/OPEN_R/include/R4000"'
    python = f"#!{sys.executable}\nimport sys\nsys.path.insert(0, {str(SOURCES.parent.parent)!r})\n"
    return {
        root / "bin" / "mipsel-linux-g++": f'#!/bin/sh\nexec "{cxx}" {" ".join(CXXFLAGS)} {include} "$@"\n',
        root / "bin" / "mipsel-linux-gcc": f'#!/bin/sh\nexec "{cc}" {" ".join(CFLAGS)} {include} "$@"\n',
        root / "bin" / "mipsel-linux-strip": '#!/bin/sh\nexec strip --strip-debug "$@"\n',
        root / "bin" / "mipsel-linux-ar": '#!/bin/sh\nexec ar "$@"\n',
        root / "bin" / "mipsel-linux-ranlib": '#!/bin/sh\nexec ranlib "$@"\n',
        root / "OPEN_R" / "bin" / "gzcp": GZCP,
        root / "OPEN_R" / "bin" / "stubgen2": python
        + "from openr_bridge.stubgen import main\nsys.exit(main(sys.argv[1:]))\n",
        root / "OPEN_R" / "bin" / "mkbin": python
        + f"from aibo_sim.openr.mkbin import main\nsys.exit(main(sys.argv[1:], {cxx!r}))\n",
    }


def _key(cxx: str, cc: str) -> str:
    digest = hashlib.sha256()
    for path in sorted(SOURCES.rglob("*")):
        if path.is_file():
            digest.update(str(path.relative_to(SOURCES)).encode() + b"\0" + path.read_bytes() + b"\0")
    for part in (
        c_header(),
        *CXXFLAGS,
        *CFLAGS,
        sys.executable,
        str(SOURCES),
        Path(__file__).read_text(),
        (Path(__file__).parent / "mkbin.py").read_text(),
    ):
        digest.update(part.encode() + b"\0")
    for compiler in (cxx, cc):
        digest.update(compiler.encode() + _version(compiler) + b"\0")
    return digest.hexdigest()[:32]


def _cache_root() -> Path:
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "aibo-sim" / "openr-sdk"


def sdk_root() -> Path:
    """The SDK's folder, made if it is not in the cache; CompileError when the host compiler is
    missing or refuses the library (a bug of ours: the message is the compiler's)."""
    cxx, cc = _compiler("c++", "the host OPEN-R SDK"), _compiler("cc", "the host OPEN-R SDK")
    root = _cache_root() / _key(cxx, cc)
    if (root / "OPEN_R" / "bin" / "openr-host").is_file():
        return root
    root.parent.mkdir(parents=True, exist_ok=True)
    with scratch_folder(".build-", root.parent) as build:
        _build(build, root, cxx, cc)
        try:
            os.replace(build, root)  # whole or not at all; a racing build of the same key may have won
        except OSError:
            if not (root / "OPEN_R" / "bin" / "openr-host").is_file():
                raise
        else:
            build.mkdir()  # for TemporaryDirectory's clean-up
    return root


def _build(build: Path, root: Path, cxx: str, cc: str) -> None:
    """Lay out the SDK in ``build``, its scripts naming their final place ``root``."""
    for folder in ("bin", "OPEN_R/bin", "OPEN_R/lib", "obj"):
        (build / folder).mkdir(parents=True)
    shutil.copytree(SOURCES / "include", build / "OPEN_R" / "include")
    for path, text in _tool_scripts(root, cxx, cc).items():
        _script(build / path.relative_to(root), text)
    (build / "obj" / "openr_host_protocol.h").write_text(c_header())
    includes = ["-I", str(build / "OPEN_R" / "include"), "-I", str(build / "obj")]
    objects = []
    for name in LIBRARY_SOURCES:
        source = SOURCES / "src" / name
        compiler, flags = (cc, CFLAGS) if name.endswith(".c") else (cxx, CXXFLAGS)
        objects.append(build / "obj" / f"{source.stem}.o")
        _run(
            [compiler, *flags, "-O2", "-Wall", *includes, "-c", str(source), "-o", str(objects[-1])],
            source,
            "compiling",
        )
    library = build / "OPEN_R" / "lib" / "libOPENR.so"
    _run(
        [cxx, "-shared", "-Wl,-soname,libOPENR.so", "-o", str(library), *map(str, objects), "-ldl", "-lm"],
        library,
        "linking",
    )
    (build / "OPEN_R" / "lib" / "libObjectComm.so").write_text(
        "/* aibo-sim: ObjectComm (subjects, observers, RCRegion) is part of libOPENR. */\nINPUT(-lOPENR)\n"
    )
    main = SOURCES / "src" / "main.cc"
    host = build / "OPEN_R" / "bin" / "openr-host"
    _run(
        [
            cxx,
            *CXXFLAGS,
            "-O2",
            "-Wall",
            *includes,
            str(main),
            "-o",
            str(host),
            "-L",
            str(library.parent),
            "-lOPENR",
            "-Wl,-rpath,$ORIGIN/../lib",
            "-ldl",
        ],
        main,
        "building",
    )
    shutil.rmtree(build / "obj")
