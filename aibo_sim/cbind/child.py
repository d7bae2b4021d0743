"""A child process that a run serves over a socket (a C controller; the OPEN-R runtime): how it
starts, how the serve loop waits for it, how a signal ends it and how it stops. ``Child`` is
the one place of this discipline:

- ``start()`` runs the program in a session, and so a process group, of its own (a terminal's
  Ctrl-C reaches aibo-sim alone, which ends the child as it ends a run), set to be killed with
  SIGKILL when the thread that started it dies, however it dies (Linux's ``PR_SET_PDEATHSIG``,
  set between fork and exec; a parent that died before that is noticed): a parent killed with
  SIGKILL leaves no child behind. PDEATHSIG watches the starting *thread*, not the process: the
  thread that starts a child must be the one that serves and stops it.
- In the main thread, from ``start`` to ``stop`` it holds SIGINT and SIGTERM (unless ignored):
  the first one is noted (``pending``) for the serve loop to act on between two messages (the
  child then ends as it can: a controller runs its ``robot_die`` functions); a second one acts
  at once, as the handler it had before would have.
- ``wait(channel, notice_s, on_wait)`` is the serve loop's wait for the child's next message:
  True when ``channel`` has data, False once the child has exited and nothing is left to read
  (its process group is killed then: a grandchild holding the socket open cannot keep the run
  waiting). Every ``notice_s`` of wall time without a message it calls ``on_wait(seconds)``.
  Once a signal is pending, a child that sends nothing for ``GRACE_S`` is stopped, one line on
  stderr says so (with ``grace_note``: what could not run then) and the signal is raised again;
  so is one still calling ``STOP_GRACE_S`` after it (``stop_if_overdue``, at each call).
- ``stop()`` kills the whole process group (the child and whatever it started in it), reaps the
  child and returns its exit status (``returncode``); the signals go back to their handlers.
  Used as a context manager (``with Child(...) as child``), the child starts on entry and stops
  on exit, where a pending signal is raised again under the handler it had before (so SIGTERM
  reaches ``cli``'s ``Terminated``, Ctrl-C is a KeyboardInterrupt).

A grandchild that makes a session of its own (``setsid``) leaves the group: it is not stopped.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import os
import select
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable

from ..exit_status import STOP_GRACE_S

GRACE_S = 2.0  # after a signal, how long a child may stay silent before it is stopped
EXIT_POLL_S = 0.1  # how often the child's exit is checked where no pidfd tells it
PR_SET_PDEATHSIG = 1  # <linux/prctl.h>
SIGNALS = (signal.SIGINT, signal.SIGTERM)

try:  # resolved here, before any fork: the child only calls it
    _prctl = ctypes.CDLL(None, use_errno=True).prctl if sys.platform.startswith("linux") else None
except (OSError, AttributeError):
    _prctl = None


def die_with_parent_thread() -> None:
    """Have this process killed with SIGKILL when the thread that made it ends (Linux; nothing
    elsewhere). ``shards.die_with_parent`` adds a portable watch for dump workers."""
    if _prctl is not None:
        _prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)


def _in_child(parent: int) -> None:
    """Between fork and exec: die with the parent's thread, or now if the parent died already."""
    die_with_parent_thread()
    if os.getppid() != parent:
        os._exit(1)


class Child:
    """A served child process; see the module docstring. ``name`` names it in messages
    ("controller spin.c"); ``pass_fds`` and ``env`` are ``subprocess.Popen``'s."""

    def __init__(self, argv: list[str], *, name: str, pass_fds=(), env=None, grace_note: str | Callable[[], str] = ""):
        self.argv, self.name, self.pass_fds, self.env, self.grace_note = argv, name, pass_fds, env, grace_note
        self.pending: int | None = None  # the first SIGINT or SIGTERM, not acted on yet
        self._signalled_at = 0.0
        self._previous: dict[int, object] = {}
        self._process: subprocess.Popen | None = None
        self._exit_fd: int | None = None  # a pidfd: readable once the child has exited
        self._wake: tuple[int, ...] = ()  # a pipe a signal's handler writes to: a wait sees it at once

    @property
    def returncode(self) -> int | None:
        """The child's exit status (negative: the signal that ended it); None until its exit is seen."""
        return self._process.returncode

    def start(self) -> Child:
        """Start the child in its own session, dying with this thread, and note SIGINT and SIGTERM
        (from the main thread) for ``wait``; returns ``self``."""
        self._wake = os.pipe()
        for fd in self._wake:
            os.set_blocking(fd, False)
        if threading.current_thread() is threading.main_thread():
            for number in SIGNALS:
                if signal.getsignal(number) != signal.SIG_IGN:
                    self._previous[number] = signal.signal(number, self._note)
        try:
            self._process = subprocess.Popen(
                self.argv,
                pass_fds=self.pass_fds,
                env=self.env,
                start_new_session=True,
                preexec_fn=functools.partial(_in_child, os.getpid()),
            )
        except BaseException:
            self._close()
            raise
        with contextlib.suppress(AttributeError, OSError):  # pidfd: Linux 5.3
            self._exit_fd = os.pidfd_open(self._process.pid)
        return self

    def wait(self, channel, notice_s: float, on_wait) -> bool:
        """Wait for ``channel`` (a socket; None: for the child's exit alone); see the module docstring."""
        began, notices = time.monotonic(), 0
        sources = [self._wake[0], *(s for s in (channel, self._exit_fd) if s is not None)]
        while True:
            now = time.monotonic()
            deadlines = [began + (notices + 1) * notice_s]
            if self.pending is not None:
                deadlines.append(max(began, self._signalled_at) + GRACE_S)
            if self._exit_fd is None:
                deadlines.append(now + EXIT_POLL_S)
            ready = select.select(sources, [], [], max(0.0, min(deadlines) - now))[0]
            if channel is not None and channel in ready:
                return True
            if self._wake[0] in ready:
                with contextlib.suppress(OSError):
                    os.read(self._wake[0], 64)
            if (self._exit_fd is None or self._exit_fd in ready) and self._exited():
                self._kill_group()
                return channel is not None and bool(select.select([channel], [], [], 0)[0])
            now = time.monotonic()
            if self.pending is not None and now >= max(began, self._signalled_at) + GRACE_S:
                self._give_up(f"made no call for {GRACE_S:g} s after")
                return False
            if now >= began + (notices + 1) * notice_s:
                notices += 1
                on_wait(notices * notice_s)

    def stop(self) -> int:
        """Kill the process group, reap the child, give the signals back; the exit status."""
        try:
            if self._process.returncode is None:
                self._kill_group()
                self._process.wait()
        finally:
            self._close()
        return self._process.returncode

    def __enter__(self) -> Child:
        return self.start()

    def __exit__(self, kind, error, traceback) -> None:
        self.stop()
        number, self.pending = self.pending, None
        if number is not None and not isinstance(error, KeyboardInterrupt):
            signal.raise_signal(number)  # under the handler it had before: as if it came now

    def exits_within(self, seconds: float) -> bool:
        """Whether the child exits within ``seconds`` (left unreaped: ``stop`` reaps it)."""
        deadline = time.monotonic() + seconds
        while not self._exited():
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.005)
        return True

    def _exited(self) -> bool:
        """Whether the child has exited; left unreaped, so that its pid, its group's id, stays its own."""
        try:
            return os.waitid(os.P_PID, self._process.pid, os.WEXITED | os.WNOHANG | os.WNOWAIT) is not None
        except ChildProcessError:
            return True

    def _kill_group(self) -> None:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(self._process.pid, signal.SIGKILL)

    def stop_if_overdue(self) -> None:
        """A signal is pending and the child still calls ``STOP_GRACE_S`` after it (a robot_die
        function that loops, a C++ destructor that steps): stop it, as a Python controller is."""
        if self.pending is not None and time.monotonic() >= self._signalled_at + STOP_GRACE_S:
            self._give_up(f"still calling {STOP_GRACE_S:g} s after", with_note=False)

    def _give_up(self, why: str, with_note: bool = True) -> None:
        """A signal is pending and the child did not end (``why``): stop it, say so (with
        ``grace_note`` where it made no call), raise the signal."""
        number, self.pending = self.pending, None
        self.stop()
        grace_note = self.grace_note() if callable(self.grace_note) else self.grace_note  # as things stand now
        note = f"; {grace_note}" if grace_note and with_note else ""
        print(
            f"aibo-sim: {self.name} {why} {signal.Signals(number).name}: stopped, with its process group{note}",
            file=sys.stderr,
            flush=True,
        )
        signal.raise_signal(number)

    def _note(self, number, frame) -> None:
        if self.pending is None:
            self.pending, self._signalled_at = number, time.monotonic()
            with contextlib.suppress(OSError):
                os.write(self._wake[1], b"\0")
            return
        previous = self._previous[number]
        if callable(previous):
            previous(number, frame)
        elif previous != signal.SIG_IGN:
            signal.signal(number, signal.SIG_DFL)
            signal.raise_signal(number)

    def _close(self) -> None:
        """The signals back to their handlers; the descriptors closed (once)."""
        for number, handler in self._previous.items():
            signal.signal(number, signal.SIG_DFL if handler is None else handler)  # None: not set from Python
        self._previous.clear()
        for fd in (*self._wake, self._exit_fd):
            if fd is not None:
                with contextlib.suppress(OSError):
                    os.close(fd)
        self._wake, self._exit_fd = (), None
