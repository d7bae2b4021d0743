"""aibo_sim first: it chooses the headless OpenGL backend (MUJOCO_GL), which MuJoCo reads once
when imported, so that a test file importing mujoco first renders as the others do, in any order."""

import aibo_sim  # noqa: F401
