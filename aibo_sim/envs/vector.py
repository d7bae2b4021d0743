"""A worker for Gymnasium's ``AsyncVectorEnv`` that busy-waits for its next command.

Gymnasium's worker blocks on its pipe between two steps. On a virtual machine a process that
has slept resumes slowly, for a millisecond or so: caches and the host core have gone to
other work. Measured on the project's 2-core KVM machine: a HeadTrackBall step takes 1.3 ms
in a tight loop and 2.0-2.4 ms when each step follows a sleep of 0.5-3 ms. Environments
whose steps take about a millisecond lose a third or more of their speed this way; ones
whose steps take 50 ms do not notice.

``BusyWaitWorker`` runs Gymnasium's own worker, but reads each command by polling the pipe,
yielding the core to any other runnable process between polls (``sched_yield``), for up to
``spin_s`` seconds before blocking as usual. In a loop that steps the vector environment
again within ``spin_s`` the workers never sleep; a slower loop (a long policy update) costs
each worker at most ``spin_s`` of polling per step. Everything else (autoreset, shared
memory, errors re-raised in the main process, ``close``) is Gymnasium's::

    envs = gymnasium.make_vec("aibo_sim/HeadTrackBall-v0", 2, "async",
                              vector_kwargs={"worker": BusyWaitWorker(), "context": "spawn"})
"""

from __future__ import annotations

import math
import os
import time
from multiprocessing.connection import Connection

from gymnasium.vector.async_vector_env import _async_worker  # private, but what AsyncVectorEnv runs by default

SPIN_S = 0.005  # a step loop with the camera turns around in well under this
_yield_core = getattr(os, "sched_yield", lambda: time.sleep(0))  # sched_yield is POSIX-only


class BusyWaitConnection:
    """One end of a pipe whose ``recv`` polls for up to ``spin_s`` seconds before blocking."""

    def __init__(self, connection: Connection, spin_s: float):
        self._connection, self._spin_s = connection, spin_s

    def recv(self):
        deadline = time.perf_counter() + self._spin_s
        while not self._connection.poll() and time.perf_counter() < deadline:
            _yield_core()
        return self._connection.recv()

    def __getattr__(self, name):
        return getattr(self._connection, name)


class BusyWaitWorker:
    """``AsyncVectorEnv(worker=...)``: Gymnasium's worker, waiting for commands by polling."""

    def __init__(self, spin_s: float = SPIN_S):
        if not (isinstance(spin_s, (int, float)) and math.isfinite(spin_s) and spin_s >= 0):
            raise ValueError(f"spin_s must be a finite number of seconds >= 0, not {spin_s!r}")
        self.spin_s = float(spin_s)

    def __call__(self, index, env_fn, pipe, *worker_args) -> None:
        _async_worker(index, env_fn, BusyWaitConnection(pipe, self.spin_s), *worker_args)
