"""Our host SDK and build-ms projects against Sony's own OPEN-R SDK, where one is installed.

Sony's SDK is not ours to ship: these run where ``OPENRSDK_ROOT`` (the variable Sony's Makefiles
read; default ``/usr/local/OPEN_R_SDK``) holds it, with its perl ``OPEN_R/bin/stubgen2`` and its
headers, and are skipped elsewhere. Where it has its MIPS compiler (``bin/mipsel-linux-g++``, gcc 3.3),
a project's objects are built with it by the project's own Makefile; without, the sources are
checked with this machine's compiler at 32 bits (the robot's sizes), syntax only. Sony's libraries
are not needed: nothing here links.
"""

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest
from openr_support import PROGRAMS, SAMPLES

from aibo_sim.openr.build_ms import WRAPPER_OBJECTS, build_ms
from aibo_sim.openr.sdk import sdk_root
from openr_bridge.wrapper import WRAPPER_SOURCES

SONY = Path(os.environ.get("OPENRSDK_ROOT", "/usr/local/OPEN_R_SDK")) / "OPEN_R"
SONY_CXX = SONY.parent / "bin" / "mipsel-linux-g++"
ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.skipif(
    not (SONY / "bin" / "stubgen2").is_file() or not (SONY / "include" / "OPENR" / "OObject.h").is_file(),
    reason=f"Sony's OPEN-R SDK is not at {SONY.parent} (set OPENRSDK_ROOT)",
)


def stubgen(tool: list[str], stub_cfg: Path, folder: Path) -> dict[str, str]:
    """Run a stubgen2 on a copy of stub_cfg in folder: the files it writes, by name."""
    folder.mkdir(parents=True)
    shutil.copy(stub_cfg, folder / "stub.cfg")
    subprocess.run([*tool, "stub.cfg"], cwd=folder, check=True, capture_output=True)
    return {p.name: p.read_text() for p in folder.iterdir() if p.name != "stub.cfg"}


def declarations(header: str) -> str:
    """A header's code without comments, whitespace or a list's trailing comma."""
    return re.sub(r",}", "}", re.sub(r"\s+", "", re.sub(r"//[^\n]*", "", header)))


@pytest.mark.parametrize(
    "stub_cfg",
    [WRAPPER_SOURCES / "stub.cfg", *sorted(PROGRAMS.glob("*/stub.cfg")), *sorted(SAMPLES.rglob("stub.cfg"))],
    ids=lambda path: path.parent.name,  # Sony's samples where the test data has them
)
def test_our_stubgen2_declares_what_sonys_declares(stub_cfg, tmp_path):
    ours = stubgen([str(Path(sdk_root()) / "OPEN_R" / "bin" / "stubgen2")], stub_cfg, tmp_path / "ours")
    sonys = stubgen(["perl", str(SONY / "bin" / "stubgen2")], stub_cfg, tmp_path / "sony")
    assert sorted(ours) == sorted(sonys)
    for header in ("def.h", "entry.h"):  # the selectors and service names the objects compile with
        assert declarations(ours[header]) == declarations(sonys[header]), header


def thirty_two_bit_flags(tmp_path: Path) -> list[str]:
    """g++ flags for 32-bit syntax checks: -m32, plus the 64-bit include folders (and an empty
    gnu/stubs-32.h) where the 32-bit C and C++ headers are not installed."""
    probe = tmp_path / "probe.cc"
    probe.write_text("#include <vector>\n#include <stdio.h>\n")
    if subprocess.run(["g++", "-m32", "-fsyntax-only", str(probe)], capture_output=True).returncode == 0:
        return ["-m32"]
    listing = subprocess.run(["g++", "-xc++", "-E", "-v", "/dev/null"], capture_output=True, text=True).stderr
    folders = listing.split("search starts here:")[-1].split("End of search list.")[0].split()
    (tmp_path / "stubs" / "gnu").mkdir(parents=True)
    (tmp_path / "stubs" / "gnu" / "stubs-32.h").write_text("")
    return ["-m32", f"-I{tmp_path / 'stubs'}", *(f"-idirafter{folder}" for folder in folders)]


def test_a_build_ms_project_compiles_against_sonys_headers_at_the_robots_sizes(tmp_path):
    """The wrapper and a C controller, with Sony's stubgen2 and headers in place of ours: every
    structure-size check of the wrapper holds, and nothing leans on what only our headers declare."""
    controller = build_ms(ROOT / "controllers" / "ball_tracker_c", tmp_path / "project") / "Controller"
    subprocess.run(
        ["perl", str(SONY / "bin" / "stubgen2"), "stub.cfg"], cwd=controller, check=True, capture_output=True
    )
    flags = [
        *thirty_two_bit_flags(tmp_path),
        "-fsyntax-only",
        "-Wall",
        "-Werror",
        f"-I{controller}",
        f"-I{controller / 'include'}",
    ]
    flags += [f"-I{SONY / 'include' / 'R4000'}", f"-I{SONY / 'include'}"]
    sources = sorted(controller.glob("*.cc")) + sorted((controller / "controller").glob("*.c"))
    assert {p.name for p in sources} >= {"ControllerStub.cc", "Controller.cc", "Robot.cc", "Mtn.cc", "WebotsApi.cc"}
    for source in sources:
        compiler = (
            ["g++", "-std=gnu++98"]
            if source.suffix == ".cc"
            else ["gcc", "-std=gnu99", "-Dmain=aibo_controller_main_c"]
        )
        result = subprocess.run([*compiler, *flags, source.name], cwd=source.parent, capture_output=True, text=True)
        assert result.returncode == 0, f"{source.name}:\n{result.stderr}"


@pytest.mark.skipif(not SONY_CXX.is_file(), reason=f"no MIPS compiler at {SONY_CXX}")
def test_a_build_ms_project_makes_its_mips_objects_with_sonys_compiler(tmp_path):
    """The robot build up to mkbin's link: the project's Makefile, Sony's stubgen2, headers and gcc."""
    controller = build_ms(ROOT / "controllers" / "ball_tracker_c", tmp_path / "project") / "Controller"
    objects = [*WRAPPER_OBJECTS, *(f"controller/{p.name}.o" for p in sorted((controller / "controller").glob("*.c")))]
    result = subprocess.run(
        ["make", f"OPENRSDK_ROOT={SONY.parent}", *objects], cwd=controller, capture_output=True, text=True
    )
    assert result.returncode == 0, result.stderr
    assert "warning" not in result.stderr, result.stderr  # -Wall, as the host build
    for name in objects:
        header = (controller / name).read_bytes()[:20]
        # ELF, 32-bit, little-endian, relocatable, machine 8: MIPS
        assert (header[:4], header[4], header[5], header[16:18], header[18:20]) == (
            b"\x7fELF",
            1,
            1,
            b"\x01\x00",
            b"\x08\x00",
        ), name


CONSTANT = re.compile(r"^\s*const\s+\w+\s+(o[a-zA-Z]*[A-Z_][A-Z0-9_]+)\s*=", re.M)


def test_our_headers_constants_are_sonys_at_the_robots_sizes(tmp_path):
    """Every constant of Sony's OPENR headers that ours declare has Sony's value (our values,
    printed by a host program, are checked against Sony's headers at 32 bits); and every status
    code and message type of Sony's is ours too (a program checks them by Sony's names)."""
    ours_folder = Path(sdk_root()) / "OPEN_R" / "include" / "OPENR"
    headers = sorted(  # not the macros a stub's def.h and entry.h go with
        p.name
        for p in ours_folder.glob("*.h")
        if (SONY / "include" / "OPENR" / p.name).is_file() and "macro" not in p.name
    )
    sonys = {h: set(CONSTANT.findall((SONY / "include" / "OPENR" / h).read_text(errors="replace"))) for h in headers}
    ours = {h: set(CONSTANT.findall((ours_folder / h).read_text())) for h in headers}
    for header in ("OStatus.h", "ObjcommMessages.h"):  # status codes (oSUCCESS...), message types (omsgREADY...)
        wanted = {name for name in sonys[header] if re.match(r"o(msg)?[A-Z]", name)}
        assert wanted <= ours[header], sorted(wanted - ours[header])
    shared = sorted(set().union(*(sonys[h] & ours[h] for h in headers)))
    includes = "".join(f"#include <OPENR/{h}>\n" for h in headers)
    printer = tmp_path / "print.cc"
    printer.write_text(
        f"{includes}#include <stdio.h>\nint main() {{\n"
        + "".join(f'    printf("%s %lld\\n", "{n}", (long long)({n}));\n' for n in shared)
        + "    return 0;\n}\n"
    )
    include = Path(sdk_root()) / "OPEN_R" / "include"
    subprocess.run(["g++", f"-I{include}", "-o", str(tmp_path / "print"), str(printer)], check=True)
    values = dict(
        line.split()
        for line in subprocess.run([tmp_path / "print"], capture_output=True, text=True).stdout.splitlines()
    )
    assert len(values) == len(shared) > 400
    checks = tmp_path / "checks.cc"
    checks.write_text(
        includes + "".join(f"typedef char {n}_is_ours[(long long)({n}) == {values[n]}LL ? 1 : -1];\n" for n in shared)
    )
    flags = [*thirty_two_bit_flags(tmp_path), "-fsyntax-only", "-std=gnu++98", "-w"]
    result = subprocess.run(
        ["g++", *flags, f"-I{SONY / 'include' / 'R4000'}", f"-I{SONY / 'include'}", str(checks)],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 0, "\n".join(line for line in result.stderr.splitlines() if "_is_ours" in line)
