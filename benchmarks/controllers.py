"""A C controller against the same controller in Python: real-time factor of ``aibo-sim run``.

``benchmarks/c_vs_python/sweep`` (C, compiled before timing) and its twin ``sweep.py``: every
32 ms step they read the camera image, the IR distance and the head's position and set the
head's target, as a tracking controller does; their own work is small, so the ratio is what
the binding costs (each call travels to this process over a socket, ``aibo_sim.cbind``).
Sim backend, the default ``ers7`` camera, no frames written, their steady rate (``SteadyRate``:
startup left out); best of ``REPEATS``, the two alternating so that both see the shared machine's quiet and busy spells.

Run: ``python -m benchmarks --only controllers``
"""

from __future__ import annotations

from pathlib import Path

from aibo_sim.cbind import compile_controller

from .common import REPEATS, SteadyRate, row

ROOT = Path(__file__).resolve().parents[1]
CONTROLLERS = {
    "Python": ROOT / "benchmarks" / "c_vs_python" / "sweep.py",
    "C": ROOT / "benchmarks" / "c_vs_python" / "sweep",
}


def measure() -> list[dict]:
    compile_controller(CONTROLLERS["C"])
    rates = {language: SteadyRate() for language in CONTROLLERS}
    for _ in range(REPEATS):
        for language, path in CONTROLLERS.items():
            rates[language].add(path)
    best = {language: rate.real_time_factor for language, rate in rates.items()}  # startup left out
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
