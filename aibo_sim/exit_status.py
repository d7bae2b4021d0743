"""The exit statuses of the ``aibo-sim`` command (docs/controllers.md lists them); a module of its
own, importing nothing of aibo_sim's, for the code that ends the program before the command line
is loaded (``aibo_sim.__init__``, ``_gl``) as well as for the command line."""

import signal

EXIT_CONTROLLER = 1  # the controller failed (it raised, or called sys.exit with another status than 0)
EXIT_BAD_INPUT = 2  # bad input: one line naming it
EXIT_DIVERGED = 3  # the physics diverged
EXIT_INTERRUPTED = 128 + signal.SIGINT  # 130, as a shell reports a process that Ctrl-C ended
EXIT_BROKEN_PIPE = 128 + signal.SIGPIPE  # 141: standard output closed by its reader (`| head`)
EXIT_TERMINATED = 128 + signal.SIGTERM  # 143, as a shell reports a process that SIGTERM ended
STOP_GRACE_S = 10.0  # after a signal, the time a command has to stop cleanly (robot_die, run.json, temporary files)
