"""The busy-waiting worker for Gymnasium's AsyncVectorEnv and HybridVectorEnv (aibo_sim.envs.vector)."""

import math
import multiprocessing
import os
import signal
import threading
import time

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

from aibo_sim.envs.threaded import ThreadedVectorEnv
from aibo_sim.envs.vector import BusyWaitConnection, BusyWaitWorker, HybridVectorEnv

HEAD_TRACK = "aibo_sim/HeadTrackBall-v0"
INFO_ENV = "aibo_sim_tests/Infos-v0"


class _InfoEnv(gym.Env):
    """Infos that test the merge: an env's own "_private" key, one key only some steps have,
    and whether reset saw ``options=None``; episodes of 2 steps."""

    observation_space = gym.spaces.Box(0.0, 1.0, (2,), np.float32)
    action_space = gym.spaces.Box(-1.0, 1.0, (1,), np.float32)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.steps = 0
        return np.zeros(2, np.float32), {"options_was_none": options is None, "_private": 7}

    def step(self, action):
        self.steps += 1
        info = {"_private": self.steps, **({"odd": float(action[0])} if self.steps % 2 else {})}
        return np.full(2, self.steps / 10, np.float32), float(action[0]), False, self.steps >= 2, info


if INFO_ENV not in gym.registry:
    gym.register(INFO_ENV, entry_point=_InfoEnv)


def test_recv_returns_waiting_messages_in_order():
    receiver, sender = multiprocessing.Pipe(duplex=False)
    for message in ("step", ("reset", {"seed": 3}), None):
        sender.send(message)
    busy = BusyWaitConnection(receiver, spin_s=0.01)
    assert [busy.recv() for _ in range(3)] == ["step", ("reset", {"seed": 3}), None]
    assert not busy.poll()  # everything else is the pipe's own


@pytest.mark.parametrize("spin_s", [0.0, 0.002, 1.0])
def test_recv_gets_a_message_sent_after_the_spinning_ends_or_during_it(spin_s):
    receiver, sender = multiprocessing.Pipe(duplex=False)
    late = threading.Timer(0.05, sender.send, args=("late",))
    late.start()
    assert BusyWaitConnection(receiver, spin_s).recv() == "late"
    late.join()


def test_recv_raises_eof_when_the_other_end_is_closed():
    receiver, sender = multiprocessing.Pipe(duplex=False)
    sender.close()
    with pytest.raises(EOFError):
        BusyWaitConnection(receiver, spin_s=0.01).recv()


@pytest.mark.parametrize("spin_s", [-0.001, math.nan, math.inf, "0.005", None])
def test_worker_rejects_a_bad_spin_time_naming_it(spin_s):
    with pytest.raises(ValueError, match="spin_s must be a finite number of seconds >= 0"):
        BusyWaitWorker(spin_s)


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:.*ERROR:UserWarning")  # Gymnasium's report of the error below
def test_async_envs_with_the_busy_wait_worker_step_as_sync_ones_bit_for_bit():
    # This process has used OpenGL already: forked workers could deadlock in Mesa, spawn them.
    busy = gym.make_vec(HEAD_TRACK, 2, "async", vector_kwargs={"context": "spawn", "worker": BusyWaitWorker()})
    sync = gym.make_vec(HEAD_TRACK, 2, "sync")
    busy.action_space.seed(4)
    actions = [busy.action_space.sample() for _ in range(6)]
    try:
        runs = []
        for envs in (busy, sync):
            obs, _ = envs.reset(seed=[7, 8])
            steps = [(obs, np.zeros(2))]
            for action in actions:
                obs, reward, _, _, _ = envs.step(action)
                steps.append((obs, reward))
            runs.append(steps)
        for (obs_busy, reward_busy), (obs_sync, reward_sync) in zip(*runs, strict=True):
            assert np.array_equal(reward_busy, reward_sync)
            for key in obs_sync:
                assert np.array_equal(obs_busy[key], obs_sync[key]), key
        assert not np.array_equal(runs[0][-1][0]["image"][0], runs[0][-1][0]["image"][1])  # two different balls
        # An error inside a worker reaches the caller as the environment raised it.
        with pytest.raises(ValueError, match="actions must be finite"):
            busy.step(np.full(busy.action_space.shape, np.nan, np.float32))
    finally:
        busy.close()
        sync.close()


@pytest.mark.slow
@pytest.mark.skipif(not os.path.exists("/proc/self/stat"), reason="reads CPU times from Linux's /proc")
def test_a_waiting_worker_polls_for_spin_s_only():
    # With spin_s=0 a worker with nothing to do sleeps in recv and its CPU time stays flat;
    # with spin_s=10 it polls, and its CPU time grows.
    envs = gym.make_vec("CartPole-v1", 1, "async", vector_kwargs={"context": "spawn", "worker": BusyWaitWorker(0.0)})
    busy = gym.make_vec("CartPole-v1", 1, "async", vector_kwargs={"context": "spawn", "worker": BusyWaitWorker(10.0)})
    try:
        for vector_env in (envs, busy):
            vector_env.reset(seed=0)
            vector_env.step(vector_env.action_space.sample())
        cpu = [_cpu_seconds(vector_env.processes[0].pid) for vector_env in (envs, busy)]
        time.sleep(0.5)
        idle_cpu, spinning_cpu = (_cpu_seconds(v.processes[0].pid) - c for v, c in zip((envs, busy), cpu))
        assert idle_cpu < 0.1 < spinning_cpu
    finally:
        envs.close()
        busy.close()


def _cpu_seconds(pid: int) -> float:
    """User + system CPU time of a process, from /proc (Linux)."""
    fields = open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")  # utime + stime


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:.*ERROR:UserWarning")  # Gymnasium's report of the worker's error
def test_hybrid_env_reports_errors_from_either_side_and_refuses_once_a_worker_or_itself_ended():
    envs = HybridVectorEnv(HEAD_TRACK, 2, camera_layer="M")
    zero = np.zeros(envs.action_space.shape, np.float32)
    try:
        assert envs.get_attr("camera_layer") == ("M", "M")
        envs.set_attr("randomize", [{}, {"ball_start": 0.0}])
        assert envs.get_attr("randomize") == ({}, {"ball_start": 0.0})
        obs, _ = envs.reset(seed=3)
        assert obs["image"].shape == (2, 80, 104, 3)
        for row in (0, 1):  # refused here, before any environment steps: none is left half-stepped
            bad = zero.copy()
            bad[row, 0] = np.nan
            with pytest.raises(ValueError, match=rf"^environment {row}'s action is not finite: nan at index 0$"):
                envs.step(bad)
        envs.step(zero)
        # A worker's own error reaches the caller as the environment raised it; that worker has ended.
        envs.set_attr("randomize", [{}, {"ball_start": -1.0}])  # set_attr checks nothing: its reset raises
        with pytest.raises(ValueError, match="high - low < 0"):
            envs.reset(seed=4)
        with pytest.raises(gym.error.ClosedEnvironmentError, match="environment 1's worker process ended"):
            envs.step(zero)
    finally:
        envs.close()
    with pytest.raises(gym.error.ClosedEnvironmentError, match="this HybridVectorEnv is closed"):
        envs.reset()
    with pytest.raises(ValueError, match="num_envs must be a whole number >= 1, not 0"):
        HybridVectorEnv(HEAD_TRACK, 0)


def test_hybrid_env_with_a_killed_worker_says_which_and_closes_the_others():
    """A worker killed (or crashed in MuJoCo or OpenGL) gave BrokenPipeError at step and at close,
    which left the env open and the other workers running."""
    envs = HybridVectorEnv(HEAD_TRACK, 3, camera_layer="L")
    envs.reset(seed=0)
    killed, other = envs._workers.processes
    os.kill(killed.pid, signal.SIGKILL)
    killed.join(10)
    with pytest.raises(
        gym.error.ClosedEnvironmentError, match=r"environment 1's worker process ended \(exit code -9\)"
    ):
        envs.step(np.zeros(envs.action_space.shape, np.float32))
    envs.close()
    other.join(10)
    assert envs.closed and not other.is_alive()


@pytest.mark.parametrize("mode", [AutoresetMode.SAME_STEP, AutoresetMode.DISABLED, "sometimes"])
def test_an_autoreset_mode_other_than_next_step_is_refused_naming_it(mode):
    """make_vec passed it on to the environment: AiboEnv.__init__()'s TypeError, which named no mode."""
    for vector_env in (HybridVectorEnv, ThreadedVectorEnv):
        with pytest.raises(ValueError, match=rf"^autoreset_mode: {vector_env.__name__} resets an ended episode at"):
            vector_env(HEAD_TRACK, 2, autoreset_mode=mode)
    with pytest.raises(ValueError, match="autoreset_mode: HybridVectorEnv"):
        gym.make_vec(HEAD_TRACK, 2, autoreset_mode=mode)
    envs = HybridVectorEnv(HEAD_TRACK, 1, autoreset_mode="NextStep", camera=None)
    assert envs.metadata["autoreset_mode"] is AutoresetMode.NEXT_STEP
    envs.close()


def test_hybrid_env_of_one_runs_in_this_process_as_a_single_env():
    envs, single = HybridVectorEnv(HEAD_TRACK, 1, max_episode_steps=2), gym.make(HEAD_TRACK, max_episode_steps=2)
    try:
        assert envs._workers is None
        obs, _ = envs.reset(seed=9)
        single_obs, _ = single.reset(seed=9)
        action = np.full((1, 3), 0.3, np.float32)
        for step in range(3):  # the third step is the autoreset
            obs, reward, terminated, truncated, _ = envs.step(action)
            if step < 2:
                single_obs, single_reward, _, single_truncated, _ = single.step(action[0])
                assert reward[0] == single_reward and truncated[0] == single_truncated == (step == 1)
                assert np.array_equal(obs["image"][0], single_obs["image"])
        assert reward[0] == 0.0 and not truncated[0]  # the reset step
    finally:
        envs.close()
        single.close()


@pytest.mark.slow
@pytest.mark.parametrize("interrupted", ["first env's step", "wait for the worker"])
def test_hybrid_env_after_ctrl_c_needs_a_reset_and_then_steps_as_sync(monkeypatch, interrupted):
    """Ctrl-C in the first environment's step, or while the worker's step is awaited (its result
    then still in the pipe): step raises ResetNeeded, reset collects what is pending, and from
    there the environments step as Gymnasium's SyncVectorEnv does."""
    envs, sync = HybridVectorEnv(HEAD_TRACK, 2), gym.make_vec(HEAD_TRACK, 2, "sync")
    try:
        envs.action_space.seed(2)
        actions = [envs.action_space.sample() for _ in range(3)]
        envs.reset(seed=4)
        step_first, wait = envs._env.step, envs._wait_for_workers

        def ctrl_c(*_):
            raise KeyboardInterrupt

        if interrupted == "first env's step":
            monkeypatch.setattr(envs._env, "step", ctrl_c)
        else:
            monkeypatch.setattr(envs, "_wait_for_workers", ctrl_c)
        with pytest.raises(KeyboardInterrupt):
            envs.step(actions[0])
        monkeypatch.setattr(envs._env, "step", step_first)
        monkeypatch.setattr(envs, "_wait_for_workers", wait)
        with pytest.raises(gym.error.ResetNeeded, match="interrupted"):
            envs.step(actions[0])
        assert envs.get_attr("camera") == ("rgb", "rgb")  # the pending step collected first
        for vector_env in (envs, sync):
            vector_env.reset(seed=4)
        for action in actions:
            ours, theirs = envs.step(action), sync.step(action)
            assert np.array_equal(ours[1], theirs[1]) and np.array_equal(ours[0]["image"], theirs[0]["image"])
    finally:
        envs.close()
        sync.close()


@pytest.mark.slow
def test_hybrid_env_infos_and_reset_options_are_sync_ones():
    from test_threaded import assert_same  # noqa: I001  (the threaded env's comparison, dtypes included)

    hybrid, sync = HybridVectorEnv(INFO_ENV, 3), gym.make_vec(INFO_ENV, 3, "sync")
    try:
        actions = np.linspace(-0.9, 0.9, 15, dtype=np.float32).reshape(5, 3, 1)
        results = []
        for envs in (hybrid, sync):
            steps = [envs.reset(seed=1), envs.reset(options={"reset_mask": np.array([False, True, True])})]
            steps += [envs.step(action) for action in actions]
            results.append(steps)
        for ours, theirs in zip(*results, strict=True):
            for part_ours, part_theirs in zip(ours, theirs, strict=True):
                assert_same(part_ours, part_theirs)
        assert results[0][0][1]["options_was_none"].tolist() == [True, True, True]
        assert results[0][2][4]["_private"].tolist() == [1, 1, 1] and "__private" in results[0][2][4]
    finally:
        hybrid.close()
        sync.close()


@pytest.mark.parametrize("kind", [HybridVectorEnv, ThreadedVectorEnv])
def test_np_random_seed_np_random_and_autoreset_mode_are_as_sync_ones(kind):
    """They were the VectorEnv's own: a fresh random seed no environment used."""
    ours, sync = kind(INFO_ENV, 3), gym.make_vec(INFO_ENV, 3, "sync")
    try:
        for envs in (ours, sync):
            envs.reset(seed=9)
        assert ours.np_random_seed == sync.np_random_seed == (9, 10, 11)
        assert ours.autoreset_mode is sync.autoreset_mode is AutoresetMode.NEXT_STEP  # Sync has the attribute too
        draws = [[generator.integers(2**63) for generator in envs.np_random] for envs in (ours, sync)]
        assert draws[0] == draws[1] and len(set(draws[0])) == 3
    finally:
        ours.close()
        sync.close()


def test_hybrid_render_is_each_environments_as_sync_ones():
    """The workers render while the first does (they waited for it before): the same pictures."""
    hybrid = HybridVectorEnv(HEAD_TRACK, 2, camera=None, render_mode="rgb_array")
    sync = gym.make_vec(HEAD_TRACK, 2, "sync", camera=None, render_mode="rgb_array")
    try:
        for envs in (hybrid, sync):
            envs.reset(seed=3)
        ours, theirs = hybrid.render(), sync.render()
        assert len(ours) == 2 and all(np.array_equal(a, b) for a, b in zip(ours, theirs, strict=True))
    finally:
        hybrid.close()
        sync.close()


def test_a_reset_the_environment_refuses_ends_no_worker():
    """MatchVsScripted refuses a ball off the carpet: refused in this process, not in each worker,
    whose error ended it (the next reset: 'worker process ended'), as SyncVectorEnv goes on."""
    envs = HybridVectorEnv("aibo_sim/MatchVsScripted-v0", 2, camera=None)
    try:
        envs.reset(seed=0)
        with pytest.raises(ValueError, match="off the carpet"):
            envs.reset(seed=0, options={"ball": (100.0, 0.0)})
        _, infos = envs.reset(seed=0, options={"ball": (0.5, 0.0)})
        assert np.allclose(infos["ball_position"][:, :2], [(0.5, 0.0), (0.5, 0.0)], atol=1e-3)
        assert envs.get_attr("np_random_seed") == (0, 1)
    finally:
        envs.close()


def test_ctrl_c_in_a_terminal_leaves_busy_wait_workers_running():
    """A terminal's Ctrl-C reaches the workers too: they ignore it, the caller decides."""
    envs = HybridVectorEnv(INFO_ENV, 2)
    try:
        envs.reset(seed=0)
        os.kill(envs._workers.processes[0].pid, signal.SIGINT)
        time.sleep(0.3)
        assert envs._workers.processes[0].is_alive()
        assert envs.step(np.zeros((2, 1), np.float32))[1].tolist() == [0.0, 0.0]
    finally:
        envs.close()
