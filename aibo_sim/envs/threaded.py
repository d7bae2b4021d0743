"""A vector environment that steps its environments in threads of one process.

``ThreadedVectorEnv("aibo_sim/HeadTrackBall-v0", N, **env_kwargs)`` (``make_vec``'s default for
aibo-sim's ids is the faster ``HybridVectorEnv``, in processes) makes N environments, each
made, stepped and closed in a thread of its own. What runs in parallel is what leaves
Python's global interpreter lock: MuJoCo's physics step, its OpenGL rendering and OpenCV's
passes of the sensor model; the environments' Python code runs one thread at a time. Each
thread has its own OpenGL context, current in that thread alone (EGL allows one thread per
context). Observations are written by each thread straight into its row of one batch
buffer. Same seeds, same observations, rewards and infos as Gymnasium's ``SyncVectorEnv``
(next-step autoreset, ``reset_mask``), bit for bit; ``benchmarks/envs.py`` measures the
speed against one environment and Gymnasium's ``AsyncVectorEnv``.
"""

from __future__ import annotations

import copy as copying
import numbers
import queue
import threading

import gymnasium
import numpy as np
from gymnasium.spaces import Box
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space, create_empty_array, iterate


def write_row(batch, index: int, value) -> None:
    """Put one environment's ``value`` into row ``index`` of the batch arrays ``batch``."""
    if isinstance(batch, dict):
        for key, part in batch.items():
            write_row(part, index, value[key])
    elif isinstance(batch, tuple):
        for part, item in zip(batch, value):
            write_row(part, index, item)
    else:
        batch[index] = value


def reset_arguments(num_envs: int, seed, options: dict | None) -> tuple[list, dict | None, np.ndarray | None]:
    """A vector ``reset``'s seeds (one per environment: an int seeds them ``seed + i``), the
    options each environment gets (``SyncVectorEnv``'s: None stays None, ``reset_mask`` is taken
    out) and that mask (None when not given); ValueError for a wrong count or mask."""
    if seed is None:
        seed = [None] * num_envs
    elif isinstance(seed, int):
        seed = [seed + i for i in range(num_envs)]
    if len(seed) != num_envs:
        raise ValueError(f"seed: a list of num_envs = {num_envs} seeds, not {len(seed)}")
    mask = None
    if options is not None and "reset_mask" in options:
        options = dict(options)
        mask = options.pop("reset_mask")
        if not (isinstance(mask, np.ndarray) and mask.dtype == np.bool_ and mask.shape == (num_envs,) and mask.any()):
            raise ValueError(
                f"options['reset_mask'] must be a bool array of shape ({num_envs},) with a True value, not {mask!r}"
            )
    return seed, options, mask


def check_autoreset_mode(kind: str, mode) -> None:
    """ValueError unless ``mode`` is ``AutoresetMode.NEXT_STEP`` (or its value), the one these
    vector envs reset by: Gymnasium's ``make_vec`` passed any other on to the environment."""
    try:
        ok = AutoresetMode(mode) is AutoresetMode.NEXT_STEP
    except ValueError:
        ok = False
    if not ok:
        raise ValueError(
            f"autoreset_mode: {kind} resets an ended episode at the next step (AutoresetMode.NEXT_STEP), not "
            f"{mode!r}; for another mode, make_vec(..., vectorization_mode='sync' or 'async')"
        )


def values_per_env(name: str, values, num_envs: int) -> list:
    """``set_attr``'s values: one for each environment, or one value for all of them."""
    if not isinstance(values, (list, tuple)):
        return [values] * num_envs
    if len(values) != num_envs:
        raise ValueError(f"set_attr({name!r}): {num_envs} values, one per environment, not {len(values)}")
    return list(values)


def check_actions(action_space, actions) -> None:
    """ValueError unless a batch of Box actions has one row for each environment, all finite
    (checked before any environment steps: none is left half-stepped, no worker ends)."""
    if not isinstance(action_space, Box):
        return
    if np.shape(actions) != action_space.shape:
        raise ValueError(
            f"actions of shape {np.shape(actions)}: want {action_space.shape}, "
            f"one row for each of the {action_space.shape[0]} environments"
        )
    values = np.asarray(actions, np.float64)
    if not np.isfinite(values).all():
        row, column = np.argwhere(~np.isfinite(values))[0][:2]
        raise ValueError(f"environment {row}'s action is not finite: {values[row, column]} at index {column}")


class SyncAttributes:
    """``np_random_seed``, ``np_random`` and ``autoreset_mode`` as ``SyncVectorEnv``'s: each
    environment's seed and generator (a ``VectorEnv``'s own are a generator no environment uses),
    the one mode these reset by."""

    autoreset_mode = AutoresetMode.NEXT_STEP

    @property
    def np_random_seed(self) -> tuple:
        return self.get_attr("np_random_seed")

    @property
    def np_random(self) -> tuple:
        return self.get_attr("np_random")


class _EnvThread(threading.Thread):
    """One environment, made, used and closed in this thread; runs the calls it is sent."""

    def __init__(self, index: int, make_env, results: queue.SimpleQueue):
        super().__init__(name=f"aibo-sim env {index}", daemon=True)
        self.index, self._make_env, self._results = index, make_env, results
        self.calls: queue.SimpleQueue = queue.SimpleQueue()  # (call number, function, args), None to end
        self.start()

    def run(self) -> None:
        try:
            env = self._make_env()
        except BaseException as exc:  # reported by the constructor
            self._results.put((0, self.index, None, exc))
            return
        self._results.put((0, self.index, None, None))
        while (call := self.calls.get()) is not None:
            number, function, args = call
            try:
                self._results.put((number, self.index, function(env, *args), None))
            except BaseException as exc:
                self._results.put((number, self.index, None, exc))
        env.close()


class ThreadedVectorEnv(SyncAttributes, VectorEnv):
    """``num_envs`` environments ``gymnasium.make(env_id, **env_kwargs)``, one thread each.

    Step it from one thread at a time. ``copy=False`` returns the batch buffers themselves
    (valid until the next step), as Gymnasium's vector environments do. A call interrupted
    (Ctrl-C) while the threads run leaves the environments a step apart from the batch:
    ``step`` then raises ``ResetNeeded`` until ``reset``; the interrupted call's results, when
    they come, are dropped.
    """

    def __init__(
        self,
        env_id: str,
        num_envs: int,
        *,
        copy: bool = True,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        **env_kwargs,
    ):
        check_autoreset_mode("ThreadedVectorEnv", autoreset_mode)
        if not isinstance(num_envs, numbers.Integral) or isinstance(num_envs, bool) or num_envs < 1:
            raise ValueError(f"num_envs must be a whole number >= 1, not {num_envs!r}")
        num_envs = int(num_envs)  # numpy's integers too, as Gymnasium's vector envs take them
        self.num_envs, self.copy = num_envs, copy
        self._results: queue.SimpleQueue = queue.SimpleQueue()  # (call number, env index, result, exception)
        self._calls, self._interrupted = 0, False
        self._threads = [
            _EnvThread(i, lambda: gymnasium.make(env_id, **env_kwargs), self._results) for i in range(num_envs)
        ]
        try:
            self._collect(range(num_envs))
            first = self.call_each(
                lambda env: (env.observation_space, env.action_space, env.metadata, env.render_mode), [0]
            )[0]
        except BaseException:
            self.close()
            raise
        self.single_observation_space, self.single_action_space, env_metadata, self.render_mode = first
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self.metadata = {**env_metadata, "autoreset_mode": AutoresetMode.NEXT_STEP}
        self._observations = create_empty_array(self.single_observation_space, num_envs)
        self._rewards = np.zeros(num_envs, np.float64)
        self._terminations = np.zeros(num_envs, np.bool_)
        self._truncations = np.zeros(num_envs, np.bool_)
        self._autoreset = np.zeros(num_envs, np.bool_)

    # ------------------------------------------------------------------ threads

    def _collect(self, indices) -> list:
        """The results of call number ``self._calls`` sent to ``indices``, in that order; the
        first error raised. Results of an earlier, interrupted call are dropped."""
        pending, results, error = set(indices), {}, None
        while pending:
            try:
                number, index, result, exc = self._results.get()
            except BaseException:
                self._interrupted = True
                raise
            if number != self._calls:
                continue
            pending.discard(index)
            results[index] = result
            if exc is not None and error is None:
                error = exc
        if error is not None:
            raise error
        return [results[i] for i in indices]

    def call_each(self, function, indices=None, args_per_env=None) -> list:
        """``function(env, *args)`` in the threads of the environments ``indices`` (default all),
        in parallel; their results in that order."""
        if self.closed:
            raise gymnasium.error.ClosedEnvironmentError("this ThreadedVectorEnv is closed: make a new one")
        indices = list(range(self.num_envs)) if indices is None else list(indices)
        self._calls += 1
        for k, i in enumerate(indices):
            self._threads[i].calls.put((self._calls, function, () if args_per_env is None else args_per_env[k]))
        return self._collect(indices)

    # ------------------------------------------------------------------ the vector API

    def reset(self, *, seed: int | list[int | None] | None = None, options: dict | None = None):
        """Reset the environments (those of ``options["reset_mask"]``, when given) as
        ``SyncVectorEnv`` does: an int ``seed`` seeds them ``seed + i``, a list one each.

        :returns: ``(observations, infos)``, batched.
        :raises ValueError: a wrong number of seeds or a bad ``reset_mask``.
        :raises gymnasium.error.ClosedEnvironmentError: after ``close``.
        """
        seed, options, mask = reset_arguments(self.num_envs, seed, options)
        if mask is None:
            mask = np.ones(self.num_envs, np.bool_)
        indices = np.flatnonzero(mask).tolist()
        observations = self._observations

        def reset_one(env, index, single_seed):
            obs, info = env.reset(seed=single_seed, options=options)
            write_row(observations, index, obs)
            return info

        env_infos = self.call_each(reset_one, indices, [(i, seed[i]) for i in indices])
        if mask.all():
            self._interrupted = False
        self._terminations[mask] = self._truncations[mask] = self._autoreset[mask] = False
        infos = {}
        for i, info in zip(indices, env_infos):
            infos = self._add_info(infos, info, i)
        return (copying.deepcopy(observations) if self.copy else observations), infos

    def step(self, actions):
        """Step every environment with its row of ``actions``, each in its thread (next-step
        autoreset: an environment whose episode ended is reset instead, with reward 0).

        :returns: ``(observations, rewards, terminations, truncations, infos)``, batched.
        :raises ValueError: actions without one row per environment.
        :raises gymnasium.error.ResetNeeded: after a call interrupted by Ctrl-C, until ``reset``.
        :raises gymnasium.error.ClosedEnvironmentError: after ``close``.
        """
        if self._interrupted:
            raise gymnasium.error.ResetNeeded(
                "a call of this ThreadedVectorEnv was interrupted while its environments "
                "ran: reset() all of them before stepping again"
            )
        check_actions(self.action_space, actions)
        observations, autoreset = self._observations, self._autoreset

        def step_one(env, index, action):
            if autoreset[index]:
                obs, info = env.reset()
                result = (0.0, False, False, info)
            else:
                obs, reward, terminated, truncated, info = env.step(action)
                result = (reward, terminated, truncated, info)
            write_row(observations, index, obs)
            return result

        results = self.call_each(step_one, None, list(enumerate(iterate(self.action_space, actions))))
        infos = {}
        for i, (reward, terminated, truncated, info) in enumerate(results):
            self._rewards[i], self._terminations[i], self._truncations[i] = reward, terminated, truncated
            infos = self._add_info(infos, info, i)
        self._autoreset = np.logical_or(self._terminations, self._truncations)
        return (
            (copying.deepcopy(observations) if self.copy else observations),
            self._rewards.copy(),
            self._terminations.copy(),
            self._truncations.copy(),
            infos,
        )

    def render(self):
        """Each environment's ``render()``, in a tuple."""
        return tuple(self.call_each(lambda env: env.render()))

    def call(self, name: str, *args, **kwargs) -> tuple:
        """Each environment's method ``name`` called with the arguments (or its attribute)."""

        def call_one(env):
            value = env.get_wrapper_attr(name)
            return value(*args, **kwargs) if callable(value) else value

        return tuple(self.call_each(call_one))

    def get_attr(self, name: str) -> tuple:
        """Each environment's attribute ``name`` (looked up through its wrappers), in a tuple."""
        return tuple(self.call_each(lambda env: env.get_wrapper_attr(name)))

    def set_attr(self, name: str, values) -> None:
        """Set attribute ``name`` of each environment: ``values`` one per environment (a list or
        tuple), or one value for all of them; ValueError for a wrong count."""
        values = values_per_env(name, values, self.num_envs)
        self.call_each(lambda env, value: env.set_wrapper_attr(name, value), None, [(v,) for v in values])

    def close_extras(self, **kwargs) -> None:
        """End the threads; each closes its environment."""
        for thread in self._threads:
            thread.calls.put(None)
        for thread in self._threads:
            thread.join()
