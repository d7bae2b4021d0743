"""The exit statuses of the ``aibo-sim`` command (docs/controllers.md lists them) and its end at
once (``exit_now``, which removes the ``scratch_folder``s first); a module of its own, importing
nothing of aibo_sim's, for the code that ends the program before the command line is loaded
(``aibo_sim.__init__``, ``_gl``) as well as for the command line."""

import contextlib
import os
import shutil
import signal
import tempfile
from pathlib import Path

EXIT_CONTROLLER = 1  # the controller failed (it raised, or called sys.exit with another status than 0)
EXIT_BAD_INPUT = 2  # bad input: one line naming it
EXIT_DIVERGED = 3  # the physics diverged
EXIT_INTERRUPTED = 128 + signal.SIGINT  # 130, as a shell reports a process that Ctrl-C ended
EXIT_BROKEN_PIPE = 128 + signal.SIGPIPE  # 141: standard output closed by its reader (`| head`)
EXIT_TERMINATED = 128 + signal.SIGTERM  # 143, as a shell reports a process that SIGTERM ended
STOP_GRACE_S = 10.0  # after a signal, the time a command has to stop cleanly (robot_die, run.json, temporary files)

_SCRATCH: set[str] = set()  # the scratch folders in use: exit_now removes them


@contextlib.contextmanager
def scratch_folder(prefix: str, parent=None):
    """A temporary folder (``tempfile.TemporaryDirectory``, in ``parent``), removed after the
    block, or by ``exit_now`` when the program ends without waiting for the thread using it."""
    with tempfile.TemporaryDirectory(dir=parent, prefix=prefix) as folder:
        _SCRATCH.add(folder)
        try:
            yield Path(folder)
        finally:
            _SCRATCH.discard(folder)


def exit_now(status: int):
    """End the process at once with ``status`` (``os._exit``: no thread is waited for, no clean-up
    runs), the scratch folders removed first (a memory stick's runtime stuck in a match's thread
    would leave its own in /tmp)."""
    for folder in list(_SCRATCH):
        shutil.rmtree(folder, ignore_errors=True)
    os._exit(status)
