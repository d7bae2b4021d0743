"""Chooses a headless OpenGL backend before MuJoCo is imported (MuJoCo reads MUJOCO_GL once).

``MUJOCO_GL`` is respected when set. Otherwise EGL is chosen when libEGL is installed, else
OSMesa when libOSMesa is, and ``MUJOCO_GL`` is set to the choice so that MuJoCo's own
renderer (and gymnasium's MuJoCo environments, and worker processes) render headless too.
No display is ever needed.

Mesa's software renderer (llvmpipe) draws small frames fastest in the calling thread, with
no rasteriser threads to hand work to and wait for: a 208x160 head-camera frame on a 2-core
machine takes ~0.46 ms with ``LP_NUM_THREADS=0`` against ~0.61 ms with 1 or 2 (a 416x320
frame about the same with 0 and 2). So ``LP_NUM_THREADS`` defaults to 0; set it to override.
"""

import ctypes.util
import os
import sys

from .exit_status import EXIT_BAD_INPUT

HEADLESS_LIBRARIES = (("egl", "EGL"), ("osmesa", "OSMesa"))
SYSTEM_PACKAGES = "EGL: Debian/Ubuntu 'libegl1 libgl1-mesa-dri' (Mesa's software renderer works); OSMesa: 'libosmesa6'"


def choose_gl_backend() -> str | None:
    chosen = os.environ.get("MUJOCO_GL", "").strip().lower()
    platform = os.environ.get("PYOPENGL_PLATFORM", "").strip().lower()
    if not chosen and platform in ("egl", "osmesa"):  # PyOpenGL's choice, which MuJoCo's must match
        chosen = os.environ["MUJOCO_GL"] = platform
    if not chosen:
        chosen = next((name for name, lib in HEADLESS_LIBRARIES if ctypes.util.find_library(lib)), "")
        if chosen:
            os.environ["MUJOCO_GL"] = chosen
    if chosen in ("egl", "osmesa"):
        os.environ.setdefault("PYOPENGL_PLATFORM", chosen)
        os.environ.setdefault("LP_NUM_THREADS", "0")
    return chosen or None


def import_mujoco() -> None:
    """Import MuJoCo, which loads the OpenGL library ``MUJOCO_GL`` names at import time;
    when that fails (e.g. ``MUJOCO_GL=osmesa`` without libOSMesa) the ImportError says so
    instead of PyOpenGL's traceback; imported by the command line (``aibo-sim``, ``python -m
    aibo_sim...``), that one line and exit status 2, as for any bad input."""
    try:
        import mujoco  # noqa: F401
    except Exception as exc:
        cause = exc
        while isinstance(cause, ImportError):  # pybind11's "initialization failed", perhaps twice
            cause = cause.__cause__
        if isinstance(cause, KeyboardInterrupt):  # Ctrl-C while it loaded: not a missing library
            raise cause from None
        error = ImportError(
            f"MuJoCo cannot load the OpenGL backend MUJOCO_GL={os.environ.get('MUJOCO_GL', '')!r} "
            f"({type(exc).__name__}: {exc}). Install {SYSTEM_PACKAGES}, or unset MUJOCO_GL to let aibo_sim choose."
        )
        if sys.argv and (sys.argv[0] == "-m" or os.path.basename(sys.argv[0]) == "aibo-sim"):  # while -m finds it
            print(f"aibo-sim: error: {error}", file=sys.stderr)
            raise SystemExit(EXIT_BAD_INPUT) from None
        raise error from None
