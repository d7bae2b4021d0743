"""A memory-stick project for a C or C++ controller: the controller linked with the Webots OPEN-R
wrapper object ``Controller`` (``openr_bridge/wrapper``), built with Sony's tools.

``build_ms(controller, out_dir)`` writes::

    Makefile                       make [OPENRSDK_ROOT=...] install: every object below
    Controller/Makefile            Sony's form: OPENRSDK_ROOT (default /usr/local/OPEN_R_SDK),
                                   stubgen2, mkbin, install gzips controller.bin into
                                   MS/OPEN-R/MW/OBJS/CONTROLL.BIN
    Controller/stub.cfg, .ocf      the wrapper's services (the report's Image observer among them)
    Controller/*.h, *.cc           the wrapper's sources
    Controller/Ers7Table.h         the robot's devices, from aibo_sim.ers7 and the robot model
    Controller/include/device/     the Webots API's headers (aibo_sim/cbind/include/device)
    Controller/controller/         the controller's sources and headers (main() renamed by -D)
    MS/OPEN-R/MW/CONF/OBJECT.CFG   /MS/OPEN-R/MW/OBJS/CONTROLL.BIN
    MS/OPEN-R/MW/CONF/CONNECT.CFG  the wrapper's three connections to OVirtualRobotComm
    MS/OPEN-R/MW/OBJS/             empty until make install
    MS/OPEN-R/MW/DATA/P/           the motion files the controller opens, as 8.3 upper-case names

``make OPENRSDK_ROOT=$(aibo-sim openr sdk) install`` builds it for the simulator (``MS`` is then
the memory stick to run); the same Makefile with Sony's SDK builds it for the robot.

The motion files are the ``"....mtn"`` string literals of the controller's sources (any case;
comments and printf formats left out), found as ``aibo-sim run`` finds them for the controller:
in its folder, then among the bundled motions, ignoring case. On the stick a name becomes
``short_name(name)`` in ``/MS/OPEN-R/MW/DATA/P/``, where the wrapper's ``mtn_new`` looks (a
``/MS/...`` literal keeps its path); names built at run time are not found here.

Bad input is a ``BuildMsError`` (a ValueError), one line naming the argument.
"""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path

import openr_bridge
from openr_bridge.memory_stick import is_8_3
from openr_bridge.primitive import REQUEST_NAMES, allowed_values
from openr_bridge.wrapper import WRAPPER_SOURCES

from .. import ers7
from ..cbind.build import C_SUFFIXES, INCLUDE, controller_sources, is_c_controller
from ..mjcf import KP_PER_SONY_P
from ..placement import out_path
from ..robot import find_file
from ..runner import motion_dirs
from ..sim import Servos, load_model
from .host import STANDARD_PSHIFT, TOUCH_AD_PER_NEWTON

WRAPPER_OBJECTS = ("ControllerStub.o", "Controller.o", "Robot.o", "Mtn.o", "Picture.o", "WebotsApi.o")
STANDARD_SHIFTS = (STANDARD_PSHIFT, 0x02, 0x0F)  # Sony's fixed PSHIFT, ISHIFT, DSHIFT (Model Information 2.2)
OBJECT_FILE = "CONTROLL.BIN"  # the wrapper object's name on the stick, as Webots named it
DATA_FOLDER = ("OPEN-R", "MW", "DATA", "P")
HEADER_SUFFIXES = (".h", ".hh", ".hpp")
CONNECTIONS = (
    "Controller.Effector.OCommandVectorData.S OVirtualRobotComm.Effector.OCommandVectorData.O",
    "OVirtualRobotComm.Sensor.OSensorFrameVectorData.S Controller.Sensor.OSensorFrameVectorData.O",
    "OVirtualRobotComm.FbkImageSensor.OFbkImageVectorData.S Controller.Image.OFbkImageVectorData.O",
)
# The controller's main() under another name, as the wrapper calls it (Controller.cc).
MAIN = {".c": "aibo_controller_main_c", ".cc": "aibo_controller_main_cc", ".cpp": "aibo_controller_main_cc"}
_SAFE_NAME = re.compile(r"[A-Za-z0-9_.+-]+")
_UNSAFE_IN_MAKE = re.compile(r"[\s'\"`$&|;<>()*?\[\]#~!{}\\]")  # in a folder's path: make and sh split or read it
_LITERAL = re.compile(r'//[^\n]*|/\*.*?\*/|"((?:[^"\\\n]|\\.)*)"|\'(?:[^\'\\\n]|\\.)*\'', re.S)


class BuildMsError(ValueError):
    """build_ms was given something it cannot build: the message names the argument."""


def short_name(name: str) -> str:
    """The 8.3 upper-case name a motion file ``name`` has on the stick (Robot.cc's ShortName):
    the last part of the path, ASCII letters in upper case, every byte other than a letter, a
    digit, '_' or '-' made '_', the stem cut to 8 and the extension to 3."""
    base = name.encode().rsplit(b"/", 1)[-1].upper().decode("latin-1")
    dot = base.rfind(".")
    stem, extension = (base[:dot], base[dot + 1 :]) if dot > 0 else (base, "")
    stem, extension = (re.sub(r"[^A-Z0-9_-]", "_", part)[:size] for part, size in ((stem, 8), (extension, 3)))
    return f"{stem}.{extension}" if extension else stem


def motion_names(sources) -> list[str]:
    """The ``.mtn`` string literals of the sources (any case; not printf formats such as
    "%s.mtn"), in order, each once."""
    names: list[str] = []
    for source in sources:
        for match in _LITERAL.finditer(Path(source).read_text(errors="replace")):
            text = match[1]
            if text is not None and text.lower().endswith(".mtn") and "%" not in text:
                text = re.sub(r"\\(.)", r"\1", text)
                if text not in names:
                    names.append(text)
    return names


def _stick_path(name: str) -> tuple[str, ...]:
    """Where on the stick the wrapper's mtn_new opens ``name`` (parts below the stick's root)."""
    if name[:4].upper() == "/MS/":
        return tuple(part.upper() for part in name[4:].split("/") if part)
    return (*DATA_FOLDER, short_name(name))


def _motions(main: Path, sources) -> dict[tuple[str, ...], Path]:
    """Each motion file's place on the stick and the file copied there; BuildMsError naming the
    controller for a literal that names no file, or two files that would share a place."""
    where = f"controller {main.parent if main.parent.name == main.stem else main}"
    found: dict[tuple[str, ...], Path] = {}
    for name in motion_names(sources):
        path = find_file(name, motion_dirs(main, working_folder=False))
        if not path.is_file():
            raise BuildMsError(
                f"{where} opens {name!r}, which is neither in {main.parent} nor among the bundled "
                "motions (models/motions): put the file beside the controller"
            )
        place = _stick_path(name)
        if not all(is_8_3(part) for part in place):
            raise BuildMsError(
                f"{where} opens {name!r}: /MS/... names must be 8.3 names of letters, digits and $&#{{}}~%'()-@^`!_ "
                "(the stick's FAT has no others)"
            )
        if place in found and found[place].resolve() != path.resolve():
            raise BuildMsError(
                f"{where} opens {name!r} and another motion that would both be "
                f"/MS/{'/'.join(place)} on the stick: rename one"
            )
        found[place] = path
    return found


def _c_string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def device_table() -> str:
    """Ers7Table.h: what the wrapper needs of the robot, from aibo_sim.ers7 (locators, speeds,
    Sony's gains), the robot model (the servos' ranges, as sim.Servos clips to them) and
    openr_bridge (the camera's layer H, field of view and settings)."""
    servos = Servos(load_model(ball=False))
    joints = [
        f"    {{{_c_string(j.locator)}, {float(servos.low[i])!r}, {float(servos.high[i])!r}, {j.max_speed!r}, "
        f"{j.gains[0]:#04x}, {j.gains[1]:#04x}, {j.gains[2]:#04x}}},"
        for i, j in enumerate(ers7.JOINTS)
    ]
    sensors = [
        f"    {{{_c_string(s.locator)}, {_c_string(s.kind)}, {(s.threshold or 0.0) * TOUCH_AD_PER_NEWTON!r}}},"
        for s in ers7.SENSORS
    ]
    settings = [
        f"    {{{_c_string(function)}, {REQUEST_NAMES[request]}, {_c_string(REQUEST_NAMES[request])}, "
        f"{_c_string(allowed_values(setting))}}},"
        for function, (request, setting) in openr_bridge.CAMERA_SETTING_FUNCTIONS.items()
    ]
    width, height = openr_bridge.LAYER_SIZE[openr_bridge.ofbkimageLAYER_H]
    return "\n".join(
        [
            "/* Ers7Table.h: the ERS-7's devices for the wrapper, written by aibo-sim build-ms from",
            " * aibo_sim/ers7.py, the robot model and openr_bridge; do not edit. */",
            "#ifndef AIBO_WRAPPER_ERS7_TABLE_H",
            "#define AIBO_WRAPPER_ERS7_TABLE_H",
            "",
            "#include <OPENR/OPrimitiveControl.h>",
            "",
            "namespace ers7 {",
            "",
            "/* Joints in aibo_sim.ers7's order: locator, set-point range (rad), speed limit (rad/s),",
            " * Sony's standard P, I, D. */",
            "struct Joint { const char* locator; double low, high, maxSpeed; word p, i, d; };",
            "const Joint JOINTS[] = {",
            *joints,
            "};",
            f"const word PSHIFT = {STANDARD_SHIFTS[0]:#04x}, ISHIFT = {STANDARD_SHIFTS[1]:#04x}, "
            f"DSHIFT = {STANDARD_SHIFTS[2]:#04x};",
            f"const double KP_PER_SONY_P = {KP_PER_SONY_P!r};  /* N m/rad per unit of the P register */",
            f"const double MAX_TORQUE = {ers7.MAX_TORQUE!r};  /* N m: a joint's torque at PWM_DUTY_FULL_SCALE */",
            f"const int PWM_DUTY_FULL_SCALE = {ers7.PWM_DUTY_FULL_SCALE};",
            "",
            "/* Sensors: locator, kind, touch threshold (AD units, for the pressure sensors). */",
            "struct Sensor { const char* locator; const char* kind; double touchThreshold; };",
            "const Sensor SENSORS[] = {",
            *sensors,
            "};",
            "const char* const ACCELEROMETER_ALIASES[] = {"
            + ", ".join(map(_c_string, ers7.ACCELEROMETER_ALIASES))
            + "};",
            "/* What a1, a2, a3 read of the body's x (forward), y (left), z (up) acceleration. */",
            "const int ACCELERATION_SIGNS[] = {" + ", ".join(map(str, ers7.OPENR_ACCELERATION_SIGNS)) + "};",
            "const char* const LEDS[] = {",
            *(f"    {_c_string(led.locator)}," for led in ers7.LEDS),
            "};",
            "",
            f"const double FIELD_OF_VIEW = {openr_bridge.FIELD_OF_VIEW!r};",
            f"const int IMAGE_WIDTH = {width}, IMAGE_HEIGHT = {height};  /* layer H */",
            "",
            "struct CameraSetting { const char* function; OPrimitiveRequest request; const char* requestName;",
            "                       const char* allowed; };",
            "const CameraSetting CAMERA_SETTINGS[] = {",
            *settings,
            "};",
            "",
            "}  // namespace ers7",
            "",
            "#endif",
            "",
        ]
    )


def makefile(sources: list[Path]) -> str:
    """Controller/Makefile: the wrapper and the controller's ``sources``, in Sony's form."""
    objects = [f"controller/{source.name}.o" for source in sources]
    rules = []
    for source, obj in zip(sources, objects):
        compiler, flags = ("$(CC)", "$(CFLAGS)") if source.suffix == ".c" else ("$(CXX)", "$(CXXFLAGS)")
        rules += [
            f"{obj}: controller/{source.name}",
            f"\t{compiler} {flags} -Dmain={MAIN[source.suffix]} -o $@ -c $<",
            "",
        ]
    return "\n".join(
        [
            "# The Webots OPEN-R wrapper object Controller linked with a controller, as aibo-sim build-ms",
            "# wrote it. make install builds MS/OPEN-R/MW/OBJS/CONTROLL.BIN with the OPEN-R SDK at",
            "# OPENRSDK_ROOT: Sony's for the robot, or $(aibo-sim openr sdk) for the simulator.",
            "",
            "OPENRSDK_ROOT?=/usr/local/OPEN_R_SDK",
            "INSTALLDIR?=../MS",
            "CXX=$(OPENRSDK_ROOT)/bin/mipsel-linux-g++",
            "CC=$(OPENRSDK_ROOT)/bin/mipsel-linux-gcc",
            "STRIP=$(OPENRSDK_ROOT)/bin/mipsel-linux-strip",
            "MKBIN=$(OPENRSDK_ROOT)/OPEN_R/bin/mkbin",
            "STUBGEN=$(OPENRSDK_ROOT)/OPEN_R/bin/stubgen2",
            "MKBINFLAGS=-p $(OPENRSDK_ROOT)",
            "LIBS=-L$(OPENRSDK_ROOT)/OPEN_R/lib -lObjectComm -lOPENR -lm",
            "INCLUDES=-I. -Iinclude -I$(OPENRSDK_ROOT)/OPEN_R/include/R4000 -I$(OPENRSDK_ROOT)/OPEN_R/include",
            "CXXFLAGS=-O2 -Wall $(INCLUDES)",
            "CFLAGS=-O2 -Wall -std=gnu99 $(INCLUDES)",
            "",
            "# exit() ends the controller as in the simulator (Controller.cc): ld's --wrap, as mkbin hands it to ld",
            "LDFLAGS=--wrap=exit",
            f"WRAPPER={' '.join(WRAPPER_OBJECTS)}",
            f"CONTROLLER={' '.join(objects)}",
            "",
            ".PHONY: all install clean",
            "",
            "all: controller.bin",
            "",
            "%.o: %.cc",
            "\t$(CXX) $(CXXFLAGS) -o $@ -c $<",
            "",
            "ControllerStub.cc: stub.cfg",
            "\t$(STUBGEN) stub.cfg",
            "",
            "# def.h and entry.h come from stubgen2",
            "Controller.o WebotsApi.o: ControllerStub.cc",
            "",
            *rules,
            "controller.bin: $(WRAPPER) $(CONTROLLER) Controller.ocf",
            "\t$(MKBIN) $(MKBINFLAGS) -o $@ $(WRAPPER) $(CONTROLLER) Controller.ocf $(LDFLAGS) $(LIBS)",
            "\t$(STRIP) $@",
            "",
            "install: controller.bin",
            f"\tgzip -c controller.bin > $(INSTALLDIR)/OPEN-R/MW/OBJS/{OBJECT_FILE}",
            "",
            "clean:",
            "\trm -f *.o controller/*.o controller.bin ControllerStub.h ControllerStub.cc def.h entry.h",
            "\trm -f *.elf *.snap.cc  # Sony's mkbin's own intermediate files, as its samples clean them",
            f"\trm -f $(INSTALLDIR)/OPEN-R/MW/OBJS/{OBJECT_FILE}",
            "",
        ]
    )


TOP_MAKEFILE = """\
# A memory stick written by aibo-sim build-ms: make [OPENRSDK_ROOT=...] install builds each
# object below into MS/OPEN-R/MW/OBJS.

COMPONENTS=Controller
INSTALLDIR=$(shell pwd)/MS

.PHONY: all install clean

all install clean:
\tfor component in $(COMPONENTS); do $(MAKE) -C $$component INSTALLDIR=$(INSTALLDIR) $@ || exit 1; done
"""


def _check_out(out_dir) -> Path:
    if str(out_dir) == "":
        raise BuildMsError("--out is empty: give the folder to write the memory-stick project in")
    out = out_path(out_dir)  # a link to a folder is that folder
    if out.exists() and not out.is_dir():
        raise BuildMsError(f"--out {out_dir}: exists and is not a folder")
    if out.is_dir() and any(out.iterdir()):
        raise BuildMsError(f"--out {out_dir}: the folder exists and is not empty: give a new or empty one")
    unsafe = _UNSAFE_IN_MAKE.search(str(out.resolve()))  # the Makefiles' $(shell pwd), as Sony's own
    if unsafe:
        raise BuildMsError(
            f"--out {out_dir}: make cannot build in a folder whose path has {unsafe.group()!r} "
            "(a space or a character the shell reads): choose another"
        )
    return out


def build_ms(controller, out_dir) -> Path:
    """Write the memory-stick project of ``controller`` (a .c/.cc/.cpp file, or a folder holding
    its main file under the folder's name) in ``out_dir`` (new, or an empty folder); returns
    ``out_dir``. BuildMsError, naming the controller or --out, for bad input."""
    if str(controller) == "":
        raise BuildMsError("controller is empty: give a C or C++ controller file or folder")
    path = Path(controller)
    if not path.exists():
        raise BuildMsError(f"controller {path}: no such file or folder")
    if not is_c_controller(path):
        main_files = " or ".join(path.name + suffix for suffix in C_SUFFIXES)
        raise BuildMsError(
            f"controller {path}: "
            + (f"a folder with no {main_files}" if path.is_dir() else "not a C or C++ file (.c, .cc or .cpp)")
        )
    main, sources = controller_sources(path)
    files = (
        sources + sorted(p for p in main.parent.iterdir() if p.suffix in HEADER_SUFFIXES and p.is_file())
        if path.is_dir()
        else sources
    )
    for source in files:
        if not _SAFE_NAME.fullmatch(source.name):
            raise BuildMsError(
                f"controller {path}: {source.name!r} is a name make cannot handle (use letters, "
                "digits, '_', '.', '+' and '-')"
            )
    motions = _motions(main, sources)
    out = _check_out(out_dir)
    table = device_table()
    out.parent.mkdir(parents=True, exist_ok=True)
    building = out.parent / f".{out.name}.building-{os.getpid()}"
    shutil.rmtree(building, ignore_errors=True)  # left by a build of this process id that was killed
    try:
        building.mkdir()
        _write_project(building, files, sources, motions, table)
        os.replace(building, out)  # whole or not at all, onto a new or empty folder
    except OSError as exc:
        raise OSError(f"cannot write {out}: {exc.strerror or exc}") from None
    finally:
        shutil.rmtree(building, ignore_errors=True)
    return out


def _write_project(out: Path, files, sources, motions: dict, table: str) -> None:
    """The project's files in ``out``: the wrapper object with the controller, the stick."""
    project = out / "Controller"
    (project / "controller").mkdir(parents=True)
    for item in sorted(WRAPPER_SOURCES.iterdir()):
        if item.is_file():
            shutil.copyfile(item, project / item.name)
    (project / "Ers7Table.h").write_text(table)
    shutil.copytree(INCLUDE / "device", project / "include" / "device")
    for source in files:
        shutil.copyfile(source, project / "controller" / source.name)
    (project / "Makefile").write_text(makefile(sources))
    (out / "Makefile").write_text(TOP_MAKEFILE)

    stick = out / "MS" / "OPEN-R" / "MW"
    for folder in ("CONF", "OBJS"):
        (stick / folder).mkdir(parents=True)
    (stick / "CONF" / "OBJECT.CFG").write_text(f"/MS/OPEN-R/MW/OBJS/{OBJECT_FILE}\n")
    (stick / "CONF" / "CONNECT.CFG").write_text("\n".join(CONNECTIONS) + "\n")
    for place, source in motions.items():
        target = out.joinpath("MS", *place)
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(source, target)
