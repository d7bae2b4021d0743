"""Building OPEN-R programs with the host SDK and running memory sticks, for the tests."""

from __future__ import annotations

import shutil
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from aibo_sim.openr.host import MemoryStickRun
from aibo_sim.openr.sdk import sdk_root
from aibo_sim.sim import Simulation
from openr_bridge.memory_stick import load_memory_stick

PROGRAMS = Path(__file__).parent / "openr_programs"
SAMPLES = Path(__file__).resolve().parents[2] / "shared" / "data" / "openr-samples"


def make(folder: Path, *arguments: str) -> str:
    """``make OPENRSDK_ROOT=<our SDK> ARGUMENTS`` in ``folder``; its output (AssertionError if it failed)."""
    result = subprocess.run(
        ["make", f"OPENRSDK_ROOT={sdk_root()}", *arguments], cwd=folder, capture_output=True, text=True
    )
    assert result.returncode == 0, result.stdout + result.stderr
    return result.stdout + result.stderr


def build_programs(folder: Path) -> Path:
    """tests/openr_programs built into ``folder``; the folder of the objects (.BIN)."""
    shutil.copytree(PROGRAMS, folder / "src")
    make(folder / "src", f"INSTALLDIR={folder / 'MS'}", "install")
    return folder / "MS" / "OPEN-R" / "MW" / "OBJS"


def make_stick(
    folder: Path,
    objects: Path,
    names: list[str],
    connect: str = "",
    design_data: dict | None = None,
    data: dict | None = None,
) -> Path:
    """A memory stick in ``folder`` loading ``names`` (.BIN files of ``objects``), with a
    CONNECT.CFG, a DESIGNDB.CFG (keyword -> file name under DATA/P) and files under DATA/P."""
    conf, data_folder = folder / "OPEN-R" / "MW" / "CONF", folder / "OPEN-R" / "MW" / "DATA" / "P"
    for path in (conf, folder / "OPEN-R" / "MW" / "OBJS", data_folder):
        path.mkdir(parents=True, exist_ok=True)
    for name in names:
        shutil.copy(objects / f"{name}.BIN", folder / "OPEN-R" / "MW" / "OBJS")
    (conf / "OBJECT.CFG").write_text("".join(f"/MS/OPEN-R/MW/OBJS/{name}.BIN\n" for name in names))
    (conf / "CONNECT.CFG").write_text(connect)
    if design_data:
        (conf / "DESIGNDB.CFG").write_text(
            "[ERS-7]\n" + "".join(f"{key} /MS/OPEN-R/MW/DATA/P/{file}\n" for key, file in design_data.items())
        )
    for name, text in (data or {}).items():
        (data_folder / name).write_text(text)
    return folder


@dataclass
class Run:
    """A finished run: its console log, the sim, and per frame what the listener recorded."""

    run: MemoryStickRun
    console: str
    frames: list = field(default_factory=list)
    images: list = field(default_factory=list)  # the camera frames (aibo_sim.camera.CameraFrame) sent

    def lines(self, object_name: str) -> list[str]:
        """The console lines an object printed, without the time stamp and name."""
        marker = f" {object_name}: "
        return [line.split(marker, 1)[1] for line in self.console.splitlines() if marker in line]


def run_stick(stick: Path, seconds: float, workdir: Path, record=None, **simulation) -> Run:
    """Run ``stick`` for ``seconds``; ``record(run)``, if given, is kept for every frame, and
    every camera frame the objects got."""
    workdir.mkdir(parents=True, exist_ok=True)
    sim = Simulation(**simulation)
    try:
        run = MemoryStickRun(
            sim, load_memory_stick(stick), workdir, log_path=workdir / "console.log", sound_path=workdir / "speaker.wav"
        )
        run.end_ms = round(seconds * 1000)
        result = Run(run, "")
        if record is not None:
            run.frame_listeners.append(lambda r: result.frames.append(record(r)))
        run.camera_listeners.append(lambda index, rgb: result.images.append(sim.camera.frame()))
        try:
            run.run()
        finally:
            result.console = (workdir / "console.log").read_text() if (workdir / "console.log").exists() else ""
    finally:
        sim.close()
    return result


def degrees(value) -> np.ndarray:
    return np.degrees(np.asarray(value))
