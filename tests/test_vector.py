"""The busy-waiting worker for Gymnasium's AsyncVectorEnv (aibo_sim.envs.vector)."""

import math
import multiprocessing
import os
import threading
import time

import gymnasium as gym
import numpy as np
import pytest

from aibo_sim.envs.vector import BusyWaitConnection, BusyWaitWorker

HEAD_TRACK = "aibo_sim/HeadTrackBall-v0"


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
