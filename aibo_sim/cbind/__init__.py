"""C and C++ controllers: the Webots-era headers, their compilation and their binding.

A C or C++ controller (``.c``, ``.cc``, ``.cpp``, or a folder of them whose main file shares
its name, as in Webots) is compiled with the system compiler against the headers in
``include/device/`` and ``libaibo.c`` (``build.py``: cached by the hash of what goes in), then
runs as a child process, as Webots ran its controllers. Each API call it makes travels over a
socket to this process, which makes the same call on the Python API (``aibo_sim.controller``):
the semantics, the values and the errors are the Python API's by construction (``serve.py``).
"""

from .build import C_SUFFIXES, CompileError, compile_controller, controller_sources, is_c_controller
from .serve import CControllerError, run_c_controller

__all__ = [
    "C_SUFFIXES",
    "CControllerError",
    "CompileError",
    "compile_controller",
    "controller_sources",
    "is_c_controller",
    "run_c_controller",
]
