"""aibo-sim: a MuJoCo simulator of the Sony Aibo ERS-7 with OPEN-R's camera data path."""

import os
import signal
import sys

from .exit_status import EXIT_INTERRUPTED


def interrupted_while_loading(number, frame) -> None:
    """Ctrl-C while the ``aibo-sim`` program loads its modules: one line and 130, as later (not a
    traceback of whichever import it hit); ``cli.main`` hands Ctrl-C back to Python."""
    print("\naibo-sim: interrupted", file=sys.stderr, flush=True)
    os._exit(EXIT_INTERRUPTED)


if (
    sys.argv
    and os.path.basename(sys.argv[0]) == "aibo-sim"
    and signal.getsignal(signal.SIGINT) is signal.default_int_handler
):
    signal.signal(signal.SIGINT, interrupted_while_loading)

from ._gl import choose_gl_backend, import_mujoco  # noqa: E402  (after the handler: its imports take a while)

choose_gl_backend()  # before anything imports mujoco
import_mujoco()

from .envs import register_envs  # noqa: E402,F401  (registers the gymnasium environments)

__version__ = "0.1.0"
