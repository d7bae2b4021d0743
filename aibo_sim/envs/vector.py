"""Processes for aibo-sim's environments: a worker for Gymnasium's ``AsyncVectorEnv`` that
busy-waits for its next command, and ``HybridVectorEnv``, which steps one environment in the
calling process while the others step in such workers.

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

With ``AsyncVectorEnv`` the calling process sits idle while its workers step.
``HybridVectorEnv`` steps its first environment in the calling process, at the same time as
the others in workers: N environments in N processes, all of them stepping. On the project's
2-core machine 2 environments step 1.51-1.58x as fast as one, 2 ``AsyncVectorEnv`` workers
1.37-1.43x (``python -m benchmarks.envs``, over several runs). It is what ``make_vec`` makes
for aibo-sim's ids without a mode::

    envs = gymnasium.make_vec("aibo_sim/HeadTrackBall-v0", 2)  # or HybridVectorEnv(id, 2)
"""

from __future__ import annotations

import copy as copying
import math
import numbers
import os
import signal
import time
from multiprocessing.connection import Connection

import gymnasium
import numpy as np
from gymnasium.vector import AsyncVectorEnv, AutoresetMode, VectorEnv
from gymnasium.vector.async_vector_env import AsyncState, _async_worker  # private, but AsyncVectorEnv's own
from gymnasium.vector.utils import batch_space, concatenate, create_empty_array, iterate

from .threaded import SyncAttributes, check_actions, check_autoreset_mode, reset_arguments, values_per_env, write_row

SPIN_S = 0.005  # a step loop with the camera turns around in well under this
_yield_core = getattr(os, "sched_yield", lambda: time.sleep(0))  # sched_yield is POSIX-only


def poll_until(connection: Connection | None, deadline: float) -> None:
    """Poll ``connection`` (a pipe's end; None or closed: return) until it has something to read
    or ``time.perf_counter()`` passes ``deadline``, yielding the core between polls."""
    while connection is not None and not connection.closed and not connection.poll() and time.perf_counter() < deadline:
        _yield_core()


class BusyWaitConnection:
    """One end of a pipe whose ``recv`` polls for up to ``spin_s`` seconds before blocking."""

    def __init__(self, connection: Connection, spin_s: float):
        self._connection, self._spin_s = connection, spin_s

    def recv(self):
        """The next object sent, polled for up to ``spin_s`` seconds, then waited for as usual."""
        poll_until(self._connection, time.perf_counter() + self._spin_s)
        return self._connection.recv()

    def __getattr__(self, name):
        return getattr(self._connection, name)


class BusyWaitWorker:
    """``AsyncVectorEnv(worker=...)``: Gymnasium's worker, waiting for commands by polling.

    It ignores SIGINT: Ctrl-C in a terminal reaches the whole process group, and Gymnasium's
    worker would end on it; the calling process gets the KeyboardInterrupt and decides (its
    ``close`` ends the workers; a ``HybridVectorEnv`` can be reset and used again)."""

    def __init__(self, spin_s: float = SPIN_S):
        if not (isinstance(spin_s, (int, float)) and math.isfinite(spin_s) and spin_s >= 0):
            raise ValueError(f"spin_s must be a finite number of seconds >= 0, not {spin_s!r}")
        self.spin_s = float(spin_s)

    def __call__(self, index, env_fn, pipe, *worker_args) -> None:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        _async_worker(index, env_fn, BusyWaitConnection(pipe, self.spin_s), *worker_args)


def _with_workers_infos(infos: dict, workers_infos: dict, num_envs: int) -> dict:
    """``infos`` of environment 0 (as ``VectorEnv._add_info`` made them) with the vector infos of
    environments 1 to ``num_envs`` - 1 added: what ``_add_info`` would make of all of them."""
    for key, value in workers_infos.items():
        if key.startswith("_") and key[1:] in workers_infos:  # a mask (an env's own "_x" is data)
            continue
        if isinstance(value, dict):
            merged = _with_workers_infos(infos.get(key, {}), value, num_envs)
        else:
            merged = infos.get(key)
            if merged is None:  # environment 0 did not have it: the workers' first sets the type
                merged = (
                    np.full(num_envs, None, object)
                    if value.dtype == object
                    else np.zeros((num_envs, *value.shape[1:]), value.dtype)
                )
            merged[1:] = value
        mask = infos.get(f"_{key}", np.zeros(num_envs, np.bool_))
        mask[1:] = workers_infos[f"_{key}"]
        infos[key], infos[f"_{key}"] = merged, mask
    return infos


class HybridVectorEnv(SyncAttributes, VectorEnv):
    """``num_envs`` environments ``gymnasium.make(env_id, **env_kwargs)``: the first made and
    stepped in the calling process, the others in spawned worker processes (Gymnasium's
    ``AsyncVectorEnv`` with ``BusyWaitWorker(spin_s)``), all stepping at once.

    Same seeds, same observations, rewards and infos as Gymnasium's ``SyncVectorEnv``
    (next-step autoreset, ``reset_mask``), bit for bit. ``copy=False`` returns the batch
    buffers themselves (valid until the next step). An error in one environment's step is
    raised once the others have finished theirs (they have stepped: reset before going on);
    a worker that raised has ended (Gymnasium's way): make a new one. After Ctrl-C during a
    step, ``step`` raises ``ResetNeeded`` until ``reset`` (of all of them). Spawned workers import
    the calling script: guard its top level with ``if __name__ == "__main__":``.
    """

    def __init__(
        self,
        env_id: str,
        num_envs: int,
        *,
        copy: bool = True,
        spin_s: float = SPIN_S,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        **env_kwargs,
    ):
        check_autoreset_mode("HybridVectorEnv", autoreset_mode)
        if not isinstance(num_envs, numbers.Integral) or isinstance(num_envs, bool) or num_envs < 1:
            raise ValueError(f"num_envs must be a whole number >= 1, not {num_envs!r}")
        self.num_envs, self.copy, self._spin_s = int(num_envs), copy, BusyWaitWorker(spin_s).spin_s
        spec = gymnasium.spec(env_id)  # a spawned worker makes it from the spec: it imports the entry point
        self._env = gymnasium.make(spec, **env_kwargs)
        self._workers = None
        try:
            if self.num_envs > 1:
                self._workers = AsyncVectorEnv(
                    [lambda: gymnasium.make(spec, **env_kwargs)] * (self.num_envs - 1),
                    copy=False,
                    context="spawn",
                    worker=BusyWaitWorker(spin_s),
                )
            self.single_observation_space, self.single_action_space = (
                self._env.observation_space,
                self._env.action_space,
            )
            self.observation_space = batch_space(self.single_observation_space, self.num_envs)
            self.action_space = batch_space(self.single_action_space, self.num_envs)
            self._observations = create_empty_array(self.single_observation_space, self.num_envs)
            self._workers_actions = create_empty_array(self.single_action_space, self.num_envs - 1)
        except BaseException:
            self.close_extras()
            raise
        self.metadata = {**self._env.metadata, "autoreset_mode": AutoresetMode.NEXT_STEP}
        self.render_mode = self._env.render_mode
        self._autoreset = False  # the first environment's episode ended in the last step
        self._interrupted = False  # Ctrl-C stopped a step: the environments may be a step apart

    def _check_running(self) -> None:
        """ClosedEnvironmentError once closed or a worker ended; first collects a call the
        workers were left running when Ctrl-C interrupted the wait for it."""
        if self.closed:
            raise gymnasium.error.ClosedEnvironmentError("this HybridVectorEnv is closed: make a new one")
        if self._workers is not None and None in self._workers.parent_pipes:  # Gymnasium ends a worker that raised
            index = self._workers.parent_pipes.index(None) + 1
            raise gymnasium.error.ClosedEnvironmentError(
                f"environment {index}'s worker process ended after the error it raised: make a new HybridVectorEnv"
            )
        if self._workers is not None:  # killed, or crashed in MuJoCo or OpenGL: its pipe is broken
            for index, process in enumerate(self._workers.processes, start=1):
                if process.exitcode is not None:
                    raise gymnasium.error.ClosedEnvironmentError(
                        f"environment {index}'s worker process ended (exit code {process.exitcode}): "
                        "close this HybridVectorEnv and make a new one"
                    )
        if self._workers is not None and self._workers._state is not AsyncState.DEFAULT:
            self._wait_for_workers()
            {
                AsyncState.WAITING_STEP: self._workers.step_wait,
                AsyncState.WAITING_RESET: self._workers.reset_wait,
                AsyncState.WAITING_CALL: self._workers.call_wait,
            }[self._workers._state]()

    def _wait_for_workers(self) -> None:
        """Poll the workers' pipes, yielding the core, for up to ``spin_s``: a process that sleeps
        in ``recv`` wakes slowly (see ``BusyWaitWorker``)."""
        deadline = time.perf_counter() + self._spin_s
        for pipe in self._workers.parent_pipes:
            poll_until(pipe, deadline)

    def _batched(self, infos: dict, workers_obs, workers_info: dict | None):
        """The batch's observations and infos, with the workers' (None: they had nothing to do)
        after the first environment's ``infos``."""
        if workers_info is not None:
            write_row(self._observations, slice(1, None), workers_obs)
            infos = _with_workers_infos(infos, workers_info, self.num_envs)
        return (copying.deepcopy(self._observations) if self.copy else self._observations), infos

    def reset(self, *, seed: int | list[int | None] | None = None, options: dict | None = None):
        """Reset the environments (those of ``options["reset_mask"]``, when given) as
        ``SyncVectorEnv`` does: an int ``seed`` seeds them ``seed + i``, a list one each.

        :returns: ``(observations, infos)``, batched.
        :raises ValueError: a wrong number of seeds or a bad ``reset_mask``.
        :raises gymnasium.error.ClosedEnvironmentError: closed, or a worker has ended.
        """
        self._check_running()
        seed, options, mask = reset_arguments(self.num_envs, seed, options)
        check_reset_options = getattr(self._env.unwrapped, "check_reset_options", None)
        if check_reset_options is not None:  # refused here, not in each worker (Gymnasium ends a worker that raised)
            check_reset_options(options)
        workers_busy = self._workers is not None and (mask is None or bool(mask[1:].any()))
        if workers_busy:  # the options as given: an environment sees None where SyncVectorEnv passes None
            self._workers.reset_async(seed[1:], options if mask is None else {**options, "reset_mask": mask[1:]})
        infos, workers_result = {}, (None, None)
        try:
            if mask is None or mask[0]:
                obs, info = self._env.reset(seed=seed[0], options=options)
                write_row(self._observations, 0, obs)
                infos, self._autoreset = self._add_info(infos, info, 0), False
        finally:
            if workers_busy:
                self._wait_for_workers()
                workers_result = self._workers.reset_wait()
        if mask is None or mask.all():
            self._interrupted = False
        return self._batched(infos, *workers_result)

    def step(self, actions):
        """Step every environment with its row of ``actions`` (next-step autoreset: an
        environment whose episode ended is reset instead, with reward 0).

        :returns: ``(observations, rewards, terminations, truncations, infos)``, batched.
        :raises ValueError: actions without one row per environment.
        :raises gymnasium.error.ResetNeeded: after a step interrupted by Ctrl-C, until ``reset``.
        :raises gymnasium.error.ClosedEnvironmentError: closed, or a worker has ended.
        """
        self._check_running()
        if self._interrupted:
            raise gymnasium.error.ResetNeeded(
                "a step of this HybridVectorEnv was interrupted: reset() all of its environments before stepping again"
            )
        check_actions(self.action_space, actions)
        try:
            return self._step(actions)
        except KeyboardInterrupt:
            self._interrupted = True
            raise

    def _step(self, actions):
        rows = list(iterate(self.action_space, actions))
        if self._workers is not None:
            self._workers.step_async(concatenate(self.single_action_space, rows[1:], self._workers_actions))
        workers_result = (None,) * 5
        try:
            if self._autoreset:
                obs, info = self._env.reset()
                reward, terminated, truncated = 0.0, False, False
            else:
                obs, reward, terminated, truncated, info = self._env.step(rows[0])
            self._autoreset = terminated or truncated
            write_row(self._observations, 0, obs)
            infos = self._add_info({}, info, 0)
        finally:
            if self._workers is not None:
                self._wait_for_workers()
                workers_result = self._workers.step_wait()
        workers_obs, workers_rewards, workers_terminations, workers_truncations, workers_info = workers_result
        observations, infos = self._batched(infos, workers_obs, workers_info)
        if self._workers is None:
            workers_rewards = workers_terminations = workers_truncations = ()
        return (
            observations,
            np.array([reward, *workers_rewards], np.float64),
            np.array([terminated, *workers_terminations], np.bool_),
            np.array([truncated, *workers_truncations], np.bool_),
            infos,
        )

    def render(self):
        """Each environment's ``render()``, in a tuple (``call``: all at once)."""
        return self.call("render")

    def call(self, name: str, *args, **kwargs) -> tuple:
        """Each environment's method ``name`` called with the arguments (or its attribute): the
        workers' while the first's runs here (one after the other before: a render of two ~1.2x
        slower)."""
        self._check_running()
        rest = ()
        if self._workers is not None:
            self._workers.call_async(name, *args, **kwargs)
        try:
            value = self._env.get_wrapper_attr(name)
            first = value(*args, **kwargs) if callable(value) else value
        finally:
            if self._workers is not None:
                self._wait_for_workers()
                rest = self._workers.call_wait()
        return (first, *rest)

    def get_attr(self, name: str) -> tuple:
        """Each environment's attribute ``name`` (looked up through its wrappers), in a tuple."""
        self._check_running()
        return (self._env.get_wrapper_attr(name), *(self._workers.get_attr(name) if self._workers is not None else ()))

    def set_attr(self, name: str, values) -> None:
        """Set attribute ``name`` of each environment: ``values`` one per environment (a list or
        tuple), or one value for all of them; ValueError for a wrong count."""
        self._check_running()
        values = values_per_env(name, values, self.num_envs)
        self._env.set_wrapper_attr(name, values[0])
        if self._workers is not None:
            self._workers.set_attr(name, list(values[1:]))

    def close_extras(self, **kwargs) -> None:
        """Close the workers (each closes its own environment; where one has died, the others are
        terminated) and the first environment."""
        try:
            if self._workers is not None:
                try:
                    self._workers.close(**kwargs)
                except (BrokenPipeError, EOFError, ConnectionResetError):
                    self._workers.close(terminate=True)
        finally:
            self._env.close()
