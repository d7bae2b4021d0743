"""Gymnasium environment throughput, beside Gymnasium's own ``Ant-v5`` measured in the same run.

Environment steps per second with camera observations (HeadTrackBall-v0, RGB of layer H,
208x160; one step = one 30 fps camera frame), for one environment and for ``make_vec`` with 2
async workers; the reference is ``Ant-v5`` with ``render_mode="rgb_array"`` at 208x160,
rendered every step, set up the same way. Also the peak RSS of a process running one
environment (RGB observations; OPEN-R observations, which add the colour tables), and, to
show what a worker costs, the time ``AsyncVectorEnv`` adds to a step of ``CartPole-v1``
(whose own step takes microseconds): pipes, shared memory and waking processes. Random
actions; the workers are spawned (forking a process that has used OpenGL can deadlock in
Mesa). Needs ``gymnasium[mujoco]`` for Ant-v5.

Run: ``python -m benchmarks.envs``
"""

from __future__ import annotations

import json
import subprocess
import sys
import time

import gymnasium as gym
import numpy as np

import aibo_sim.envs  # noqa: F401  (registers the environments; aibo_sim sets MUJOCO_GL for Ant-v5 too)

from .common import row

AIBO = "aibo_sim/HeadTrackBall-v0"
ANT = "Ant-v5"
ANT_KWARGS = {"render_mode": "rgb_array", "width": 208, "height": 160}
STEPS = 150

_PEAK_RSS = r"""
import re, sys, gymnasium as gym, aibo_sim.envs
env = gym.make(sys.argv[1], **{kwargs})
env.reset(seed=0)
for _ in range(100):
    _, _, terminated, truncated, _ = env.step(env.action_space.sample())
    if env.render_mode:
        env.render()
    if terminated or truncated:
        env.reset()
print(re.search(r"VmHWM:\s*(\d+) kB", open("/proc/self/status").read()).group(1))
"""


def _steps_per_second(env, render: bool) -> float:
    """Steps per second over ``STEPS`` calls to ``step`` (and ``render``), after one warm-up step."""
    env.action_space.seed(0)
    env.reset(seed=0)
    env.step(env.action_space.sample())
    start = time.perf_counter()
    for _ in range(STEPS):
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        if render:
            env.render()
        if np.ndim(terminated) == 0 and (terminated or truncated):  # vector envs reset themselves
            env.reset()
    elapsed = time.perf_counter() - start
    env.close()
    return STEPS * getattr(env, "num_envs", 1) / elapsed


def _peak_rss_mib(env_id: str, kwargs: dict) -> float:
    """Peak RSS of a fresh process running one environment for 100 steps.

    Read from VmHWM (Linux): getrusage's ru_maxrss would also count the RSS of this process,
    which the child inherits through fork and exec.
    """
    code = _PEAK_RSS.replace("{kwargs}", repr(kwargs))
    result = subprocess.run([sys.executable, "-c", code, env_id], capture_output=True, text=True, check=True)
    return int(result.stdout.split()[-1]) / 1024


def measure() -> list[dict]:
    """Steps/s (one env and 2 async workers) and peak RSS, each after the same for Ant-v5."""
    spawn = {"context": "spawn"}
    measured = {
        "1 env": (_steps_per_second(gym.make(AIBO), render=False),
                  _steps_per_second(gym.make(ANT, **ANT_KWARGS), render=True)),
        "make_vec async, 2 workers": (
            _steps_per_second(gym.make_vec(AIBO, 2, "async", vector_kwargs=spawn), render=False),
            _steps_per_second(gym.make_vec(ANT, 2, "async", vector_kwargs=spawn, **ANT_KWARGS), render=True)),
    }
    cartpole = 1 / _steps_per_second(gym.make_vec("CartPole-v1", 1, "async", vector_kwargs=spawn), render=False)
    cartpole -= 1 / _steps_per_second(gym.make("CartPole-v1"), render=False)
    rows = [row("time make_vec async adds to a step, 1 worker (CartPole-v1)", cartpole * 1e3, "ms")]
    for setting, (aibo, ant) in measured.items():
        reference = f"{ANT} steps/s with render_mode='rgb_array' 208x160, {setting}"
        rows.append(row(reference, ant, "steps/s"))
        rows.append(row(f"{AIBO} steps/s with camera observations, {setting}", aibo, "steps/s", reference, aibo / ant,
                        target=("ratio", ">=", 40)))
    reference = f"{ANT} peak RSS, one env rendering 208x160"
    ant_rss = _peak_rss_mib(ANT, ANT_KWARGS)
    rows.append(row(reference, ant_rss, "MiB"))
    for camera in ("rgb", "openr"):  # openr: + the 64 MiB colour tables each way
        aibo_rss = _peak_rss_mib(AIBO, {"camera": camera})
        rows.append(row(f"{AIBO} peak RSS, one env, camera={camera!r} (ratio < 1: smaller)", aibo_rss, "MiB",
                        reference, aibo_rss / ant_rss, target=("value", "<=", 400e6 / 2**20)))  # 400 MB
    return rows


if __name__ == "__main__":
    for measurement in measure():
        print(json.dumps(measurement))
