"""The OPEN-R runtime's cost: wall time per 8 ms frame of a memory stick against the same program in Python.

``benchmarks/head_swing/HeadSwing`` is an OPEN-R object built by a Sony-style Makefile against the
host SDK (``make OPENRSDK_ROOT=$(aibo-sim openr sdk) install``, done here before timing): it
swings the head with one set-point every 8 ms frame, observes the sensor vectors (every 32 ms)
and the camera's images. ``benchmarks/head_swing/head_swing.py`` does the same through the
Webots-era API, on the default backend (the reference) and on the openr backend (its images
through OPEN-R's message, as the object's). All run through ``run_controller`` with the default
``ers7`` camera and no frames written; the ratio is what the runtime costs: the sensor vector
every frame; a round trip to its process on the frames where object code runs (a sensor
vector, an image or an effector ready event for HeadSwing: 540 of 1250 frames; the runtime
foretells the others and their set-points, ``host_protocol``'s Lookahead); the image message,
which the runtime makes from the sensor's Y, Cr, Cb frame in the shared memory that becomes
its region. Sony's MovingHead7 and BallTrackingHead7 are timed too when
``../shared/data/openr-samples`` is there. Best of ``REPEATS``, alternating: on the shared
2-core machine one program's 10 s runs differ by up to 1.5x from one to the next, so that a
best of three could meet or miss the target by luck (docs/benchmark-notes.md).

Run: ``python -m benchmarks --only openr``
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from pathlib import Path

from aibo_sim.config import WorldConfig
from aibo_sim.openr.sdk import sdk_root
from aibo_sim.runner import run_controller
from aibo_sim.sim import FRAME_MS

from .common import REPEATS, SIM_SECONDS, SteadyRate, row

ROOT = Path(__file__).resolve().parents[1]
PROGRAM = ROOT / "benchmarks" / "head_swing"
TWIN = PROGRAM / "head_swing.py"
SAMPLES = ROOT.parent / "shared" / "data" / "openr-samples"
SONY = ("ers7/MovingHead7", "ers7/BallTrackingHead7")


def build(folder: Path) -> None:
    """Build and install a program as Sony's samples are built; RuntimeError ending with make's output."""
    done = subprocess.run(
        ["make", f"OPENRSDK_ROOT={sdk_root()}", "install"],
        cwd=folder,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    if done.returncode != 0:
        raise RuntimeError(f"make install in {folder} failed (exit {done.returncode}):\n{done.stdout.rstrip()}")


def real_time_factor(program: Path, rounds: int, **options) -> float:
    return max(
        run_controller(program, duration=SIM_SECONDS, progress=False, **options).real_time_factor for _ in range(rounds)
    )


def measure() -> list[dict]:
    build(PROGRAM)
    programs = {"sim": (TWIN, {}), "openr": (TWIN, {"backend": "openr"}), "stick": (PROGRAM, {})}
    rates = {name: SteadyRate() for name in programs}
    for _ in range(REPEATS):
        for name, (program, options) in programs.items():
            rates[name].add(program, **options)
    # wall time a frame costs, the run's startup left out (6-13 % of a 10 s run, more the stick's)
    frame_ms = {name: FRAME_MS / rate.real_time_factor for name, rate in rates.items()}
    twin = "wall time per 8 ms frame, head swing in Python (head_swing.py, sim backend)"
    rows = [
        row(twin, frame_ms["sim"], "ms"),
        row(
            "wall time per 8 ms frame, the same in Python on the openr backend (images through OPEN-R's message)",
            frame_ms["openr"],
            "ms",
            twin,
            frame_ms["sim"] / frame_ms["openr"],
        ),
        row(
            "wall time per 8 ms frame, the same program as an OPEN-R object on a memory stick (HeadSwing)",
            frame_ms["stick"],
            "ms",
            twin,
            frame_ms["sim"] / frame_ms["stick"],
            target=("ratio", ">=", 1 / 1.2),
        ),  # at most 1.2x the Python controller's cost
    ]
    if SAMPLES.is_dir():
        with tempfile.TemporaryDirectory() as scratch:
            samples = Path(scratch) / "openr-samples"
            shutil.copytree(SAMPLES, samples)  # their Makefiles build objects of neighbouring samples
            for program in SONY:
                name = Path(program).name
                copy = samples / program
                (copy / "MS" / "OPEN-R" / "MW" / "OBJS").mkdir(parents=True, exist_ok=True)
                build(copy)
                options = {"world": WorldConfig(ball_type="pink")} if name == "BallTrackingHead7" else {}
                value = real_time_factor(copy, REPEATS, **options)
                rows.append(row(f"real-time factor, Sony's {name} (memory stick)", value, "x"))
    return rows


if __name__ == "__main__":
    for r in measure():
        print(r)
