"""aibo_sim first: it chooses the headless OpenGL backend (MUJOCO_GL), which MuJoCo reads once
when imported, so that a test file importing mujoco first renders as the others do, in any order."""

import gc

import pytest

import aibo_sim  # noqa: F401
from aibo_sim.sim import release_freed_memory


@pytest.fixture(autouse=True, scope="module")
def _free_each_modules_memory():
    """After each test module, what its tests left unreachable (simulations and their renderers,
    environments) is collected and its memory given back: the run's peak stays that of its
    largest module, not the sum of them all."""
    yield
    gc.collect()
    release_freed_memory()
