"""A C controller against the same controller in Python: real-time factor of ``aibo-sim run``.

``benchmarks/c_vs_python/sweep`` (C, compiled before timing) and its twin ``sweep.py``: every
32 ms step they read the camera image, the IR distance and the head's position and set the
head's target, as a tracking controller does; their own work is small, so the ratio is what
the binding costs (each call travels to this process over a socket, ``aibo_sim.cbind``).
Sim backend, the default ``ers7`` camera, no frames written, ``SIM_SECONDS`` a run; best of
``REPEATS``, the two alternating so that both see the shared machine's quiet and busy spells.

Run: ``python -m benchmarks --only controllers``
"""

from __future__ import annotations

from pathlib import Path

from aibo_sim.cbind import compile_controller
from aibo_sim.runner import run_controller

from .common import REPEATS, SIM_SECONDS, row

ROOT = Path(__file__).resolve().parents[1]
CONTROLLERS = {
    "Python": ROOT / "benchmarks" / "c_vs_python" / "sweep.py",
    "C": ROOT / "benchmarks" / "c_vs_python" / "sweep",
}


def measure() -> list[dict]:
    compile_controller(CONTROLLERS["C"])
    best = dict.fromkeys(CONTROLLERS, 0.0)
    for _ in range(REPEATS):
        for language, path in CONTROLLERS.items():
            summary = run_controller(path, duration=SIM_SECONDS, progress=False)
            best[language] = max(best[language], summary.real_time_factor)
    python = "real-time factor, a camera-reading controller in Python (sweep.py)"
    return [
        row(python, best["Python"], "x"),
        row(
            "real-time factor, the same controller in C (sweep.c, compiled)",
            best["C"],
            "x",
            python,
            best["C"] / best["Python"],
            target=("ratio", ">=", 0.85),
        ),  # within 15 % of Python
    ]


if __name__ == "__main__":
    for r in measure():
        print(r)
