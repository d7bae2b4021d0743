"""Benchmarks: every figure is a ratio against a reference measured in the same run."""

import aibo_sim  # noqa: F401  (chooses the headless GL backend before mujoco is imported)
