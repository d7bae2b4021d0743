"""Timing helpers shared by the benchmark modules."""

import time

REPEATS = 5  # a measurement's best of so many
SIM_SECONDS = 10.0  # simulated seconds of a timed run
STARTUP_SECONDS = 1.0  # simulated seconds of the short run whose wall time, startup included, a long one's loses


class SteadyRate:
    """A program's steady real-time factor, its startup (compiling, the runtime's process, the
    first frames) left out: the simulated time between a ``STARTUP_SECONDS`` run and a
    ``SIM_SECONDS`` one over the difference of their wall times, each the best of the runs given."""

    def __init__(self):
        self.short = self.long = float("inf")

    def add(self, program, **options) -> None:
        """One short and one long ``run_controller`` of ``program`` (``options`` its own)."""
        from aibo_sim.runner import run_controller

        def wall(duration: float) -> float:
            return run_controller(program, duration=duration, progress=False, **options).wall_s

        self.short = min(self.short, wall(STARTUP_SECONDS))
        self.long = min(self.long, wall(SIM_SECONDS))

    @property
    def real_time_factor(self) -> float:
        return (SIM_SECONDS - STARTUP_SECONDS) / (self.long - self.short)


def best_mean_seconds(run, iterations: int) -> float:
    """Best over ``REPEATS`` of the mean time of ``iterations`` calls (after one warm-up)."""
    run()
    best = float("inf")
    for _ in range(REPEATS):
        start = time.perf_counter()
        for _ in range(iterations):
            run()
        best = min(best, (time.perf_counter() - start) / iterations)
    return best


def row(
    name: str,
    value: float,
    unit: str,
    reference: str | None = None,
    ratio: float | None = None,
    target: tuple[str, str, float] | None = None,
) -> dict:
    """One table row; ``ratio`` compares with the row named ``reference`` (> 1: this is faster).

    ``target`` is the issue's goal for this row as (``"value"`` or ``"ratio"``, ``">="`` or
    ``"<="``, threshold); the row records it and whether it was met.
    """
    entry = {"name": name, "value": value, "unit": unit, "reference": reference, "ratio": ratio}
    if target is not None:
        quantity, comparison, threshold = target
        measured = entry[quantity]
        met = measured is not None and (measured >= threshold if comparison == ">=" else measured <= threshold)
        entry["target"] = f"{quantity} {comparison} {threshold:g}"
        entry["met"] = bool(met)
    return entry
