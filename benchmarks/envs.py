"""Gymnasium environment throughput, beside Gymnasium's own ``Ant-v5`` measured in the same run.

Environment steps per second with camera observations (HeadTrackBall-v0, RGB of layer H,
208x160; one step = one 30 fps camera frame), for one environment and for ``make_vec`` with 2
async workers, with Gymnasium's own worker and with ``aibo_sim.envs.vector.BusyWaitWorker``, and
for ``HybridVectorEnv`` with 2 environments (one stepped in the calling process);
the reference is ``Ant-v5`` with ``render_mode="rgb_array"`` at 208x160, rendered every step,
set up the same way. Each rate is the best of ``ROUNDS`` blocks of ``STEPS[env_id]`` steps,
stepped in a fresh process that alternates block by block with the reference's, so that both
see the shared machine's quiet and busy spells (measured one after the other, the ratio moved
between 34x and 46x from run to run). Fresh processes because Mesa reads ``LP_NUM_THREADS``
once per process, and each environment runs as its users get it (aibo_sim sets 0,
rasterising in the calling thread; Ant-v5 gets Mesa's default, one rasteriser thread per
core, which renders its 208x160 frames with shadows ~1.4x faster here than 0 does). Also the
peak RSS of a process running one environment (RGB observations; OPEN-R observations, which
add the colour tables), and, to show what a worker costs, the time ``AsyncVectorEnv`` with 2
workers adds to a step of 2 ``CartPole-v1`` (whose own step takes microseconds): pipes,
shared memory and waking processes. Random actions, drawn before each block is timed; the
workers are spawned (forking a process that has used OpenGL can deadlock in Mesa). Needs
``gymnasium[mujoco]`` for Ant-v5.

Run: ``python -m benchmarks.envs``
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

import aibo_sim.envs  # noqa: F401  (registers the environments; aibo_sim sets MUJOCO_GL for Ant-v5 too)
from aibo_sim.envs.threaded import ThreadedVectorEnv
from aibo_sim.envs.vector import BusyWaitWorker, HybridVectorEnv
from openr_bridge import LAYER_SIZE, ofbkimageLAYER_H

from .common import row

AIBO = "aibo_sim/HeadTrackBall-v0"  # the ers7 camera profile (the default)
AIBO_IDEAL = AIBO + "@ideal"  # the same with camera_profile="ideal"
ANT = "Ant-v5"
LAYER_H = LAYER_SIZE[ofbkimageLAYER_H]  # width, height
ANT_KWARGS = {"render_mode": "rgb_array", "width": LAYER_H[0], "height": LAYER_H[1]}  # as the head camera's
STEPS = {AIBO: 300, AIBO_IDEAL: 300, ANT: 40, "CartPole-v1": 300}
ROUNDS = 10  # blocks per environment and setting, alternating with the reference's
SPAWN = {"context": "spawn"}
THREADS, HYBRID = "threads", "hybrid"
SETTINGS = {  # name: vector_kwargs of make_vec with 2 async workers (None: one env; THREADS: aibo-sim's
    # ThreadedVectorEnv, 2 envs, against Ant-v5 in Gymnasium's sync vector env; HYBRID: HybridVectorEnv,
    # 2 envs, Ant-v5's too), the 40x target applies
    "1 env": (None, True),
    "make_vec async, 2 workers": (SPAWN, False),
    "make_vec async, 2 workers, BusyWaitWorker": ({**SPAWN, "worker": BusyWaitWorker()}, True),
    "HybridVectorEnv, 2 envs (one in this process, one in a BusyWaitWorker)": (HYBRID, True),
    "make_vec threads, 2 envs (ThreadedVectorEnv; Ant-v5: sync)": (THREADS, False),
}
MESA_DEFAULT = {"LP_NUM_THREADS": str(os.cpu_count() or 1)}  # what llvmpipe does with the variable unset
ROOT = Path(__file__).resolve().parents[1]


def _make(env_id: str, vector_kwargs: dict | None):
    """One environment (``vector_kwargs`` None) or ``make_vec`` with 2 async workers."""
    kwargs = ANT_KWARGS if env_id == ANT else {}
    env_id, _, profile = env_id.partition("@")
    if profile:
        kwargs = {"camera_profile": profile}
    if vector_kwargs is None:
        return gym.make(env_id, **kwargs)
    if vector_kwargs == THREADS:
        return gym.make_vec(env_id, 2, "sync", **kwargs) if env_id == ANT else ThreadedVectorEnv(env_id, 2, **kwargs)
    if vector_kwargs == HYBRID:
        return HybridVectorEnv(env_id, 2, **kwargs)
    return gym.make_vec(env_id, 2, "async", vector_kwargs=vector_kwargs, **kwargs)


def _random_actions(env, steps: int) -> list:
    """``steps`` random actions, drawn before a block is timed: Gymnasium's ``Box.sample``
    takes ~30 us, ~3 % of one of our steps, and is the benchmark's policy, not the env."""
    return [env.action_space.sample() for _ in range(steps)]


def _step(env, actions: list) -> None:
    """Step through ``actions``, rendering each step where the env renders; a single env is
    reset at the end of an episode (vector envs reset themselves)."""
    render = env.render_mode is not None
    for action in actions:
        _, _, terminated, truncated, _ = env.step(action)
        if render:
            env.render()
        if np.ndim(terminated) == 0 and (terminated or truncated):
            env.reset()


def serve_blocks(env_id: str, vector_kwargs: dict | None) -> None:
    """Print "ready" after a reset and one warm-up step, then, for each line read from stdin,
    the steps per second of one block of ``STEPS[env_id]`` random steps."""
    env = _make(env_id, vector_kwargs)
    env.action_space.seed(0)
    env.reset(seed=0)
    _step(env, _random_actions(env, 1))
    print("ready", flush=True)
    for _ in sys.stdin:
        actions = _random_actions(env, STEPS[env_id])
        start = time.perf_counter()
        _step(env, actions)
        print(STEPS[env_id] * getattr(env, "num_envs", 1) / (time.perf_counter() - start), flush=True)
    env.close()


def _released_share(steps: int = 300) -> float:
    """The share of one env's step time spent in C calls (MuJoCo, OpenCV, numpy, and the
    renderer's ``glReadPixels``, a ctypes call that cProfile counts as its caller
    ``_read_rgba``'s own time: they release the GIL), profiled: what threads can run in
    parallel. cProfile slows the Python code, so the share is a lower bound."""
    import cProfile
    import pstats

    import cv2

    env = gym.make(AIBO)
    env.action_space.seed(0)
    env.reset(seed=0)
    actions = _random_actions(env, steps)
    _step(env, actions[:20])
    profile = cProfile.Profile()
    profile.runcall(_step, env, actions)
    env.close()
    stats = pstats.Stats(profile).stats
    released = sum(
        total
        for (file, _, name), (_, _, total, _, _) in stats.items()
        if file == "~"
        and (
            name.startswith(("<built-in method mujoco.", "<method"))
            or name[1:-1].isidentifier()
            and hasattr(cv2, name[1:-1])
        )
        or file.endswith(os.path.join("aibo_sim", "render.py"))
        and name == "_read_rgba"
    )
    return released / sum(total for _, _, total, _, _ in stats.values())


def peak_rss_mib(env_id: str, camera: str | None) -> float:
    """Peak RSS (VmHWM, Linux) of this process after 100 random steps of one environment."""
    env = gym.make(env_id, **(ANT_KWARGS if env_id == ANT else {"camera": camera}))
    env.reset(seed=0)
    _step(env, _random_actions(env, 100))
    return int(re.search(r"VmHWM:\s*(\d+) kB", Path("/proc/self/status").read_text()).group(1)) / 1024


def _environment(env_id: str) -> dict:
    """Ant-v5 gets Mesa's default rasteriser threads (aibo_sim sets its own)."""
    return {**os.environ, **(MESA_DEFAULT if env_id == ANT else {})}


def _in_fresh_process(*args: str) -> float:
    """Run this module with ``args`` in a new Python process and return the number it prints."""
    result = subprocess.run(
        [sys.executable, "-m", "benchmarks.envs", *args],
        cwd=ROOT,
        env=_environment(args[1]),
        capture_output=True,
        text=True,
    )
    if result.returncode != 0:
        raise RuntimeError(f"benchmarks.envs {' '.join(args)} failed:\n{result.stderr}")
    return float(result.stdout.split()[-1])


def _alternating_best(*runs: tuple[str, str]) -> list[float]:
    """The best steps/s of each of ``runs`` ((env_id, setting) pairs) over ``ROUNDS`` blocks.

    Each runs in a fresh process of its own (``--serve``), started together; once all are
    ready, they step one block each, in turn, round after round.
    """
    children = []  # (process, its stderr)
    try:
        for env_id, setting in runs:
            log = tempfile.TemporaryFile("w+")
            children.append(
                (
                    subprocess.Popen(
                        [sys.executable, "-m", "benchmarks.envs", "--serve", env_id, setting],
                        cwd=ROOT,
                        env=_environment(env_id),
                        text=True,
                        stdin=subprocess.PIPE,
                        stdout=subprocess.PIPE,
                        stderr=log,
                    ),
                    log,
                )
            )
        for child in children:
            _read_line(*child)  # "ready"
        best = [0.0] * len(children)
        for _ in range(ROUNDS):
            for i, (process, log) in enumerate(children):
                process.stdin.write("block\n")
                process.stdin.flush()
                best[i] = max(best[i], float(_read_line(process, log)))
        return best
    finally:
        for process, log in children:
            process.stdin.close()
            process.wait()
            log.close()


def _read_line(process: subprocess.Popen, log) -> str:
    """The next line a ``--serve`` process prints; RuntimeError with its stderr if it ended."""
    line = process.stdout.readline()
    if not line:
        process.wait()
        log.seek(0)
        raise RuntimeError(f"python {' '.join(process.args[1:])} failed:\n{log.read()}")
    return line


def measure() -> list[dict]:
    """Steps/s (one env, 2 async workers of each kind) and peak RSS, each after the same for Ant-v5.

    The 40x target applies to one env, to 2 workers with the busy-wait worker and to
    ``HybridVectorEnv``, the ways to run these ~1 ms steps on several processes; Gymnasium's
    own worker is measured beside them.
    """
    vector_rate, single_rate = _alternating_best(("CartPole-v1", "make_vec async, 2 workers"), ("CartPole-v1", "1 env"))
    vector_step, two_steps = 2 / vector_rate, 2 / single_rate  # rates count env steps
    rows = [
        row(
            "time make_vec async adds to a step of 2 envs on 2 workers (CartPole-v1)",
            (vector_step - two_steps) * 1e3,
            "ms",
        )
    ]
    for setting, (_, targeted) in SETTINGS.items():
        if setting == "1 env":  # both camera profiles, beside each other and the reference
            aibo, ideal, ant = _alternating_best((AIBO, setting), (AIBO_IDEAL, setting), (ANT, setting))
        else:
            (aibo, ant), ideal = _alternating_best((AIBO, setting), (ANT, setting)), None
        reference = f"{ANT} steps/s with render_mode='rgb_array' 208x160, {setting}"
        rows.append(row(reference, ant, "steps/s"))
        if ideal is not None:
            rows.append(
                row(f"{AIBO} steps/s, camera profile 'ideal', {setting}", ideal, "steps/s", reference, ideal / ant)
            )
        rows.append(
            row(
                f"{AIBO} steps/s with camera observations (profile 'ers7'), {setting}",
                aibo,
                "steps/s",
                reference,
                aibo / ant,
                target=("ratio", ">=", 40) if targeted else None,
            )
        )
        if ideal is not None:
            rows.append(
                row(
                    f"cost of an ers7 step over an ideal one, {setting} (ratio < 1.3: target)",
                    ideal / aibo,
                    "x",
                    target=("value", "<=", 1.3),
                )
            )
    one = "1 env"
    threads, async_, hybrid = (
        next(name for name in SETTINGS if name.startswith(start))
        for start in ("make_vec threads", "make_vec async, 2 workers, B", "HybridVectorEnv")
    )
    single, threaded, processes, both = _alternating_best((AIBO, one), (AIBO, threads), (AIBO, async_), (AIBO, hybrid))
    reference = f"{AIBO} steps/s, 1 env (beside the 2-env rows below)"
    rows += [
        row(reference, single, "steps/s"),
        row(
            f"{AIBO} steps/s, 2 envs in threads of one process (ThreadedVectorEnv)",
            threaded,
            "steps/s",
            reference,
            threaded / single,
            target=("ratio", ">=", 1.7),
        ),
        row(
            f"{AIBO} steps/s, 2 envs in 2 processes (make_vec async, BusyWaitWorker)",
            processes,
            "steps/s",
            reference,
            processes / single,
        ),
        row(
            f"{AIBO} steps/s, 2 envs, one in this process, one in a worker (HybridVectorEnv)",
            both,
            "steps/s",
            reference,
            both / single,
        ),
        row(
            "share of a step's time in calls that release the GIL (MuJoCo, OpenCV, numpy; cProfile)",
            100 * _released_share(),
            "%",
        ),
    ]
    reference = f"{ANT} peak RSS, one env rendering 208x160"
    ant_rss = _in_fresh_process("--peak-rss", ANT, "")
    rows.append(row(reference, ant_rss, "MiB"))
    for camera in ("rgb", "openr"):  # openr: + the 64 MiB colour tables each way
        aibo_rss = _in_fresh_process("--peak-rss", AIBO, camera)
        rows.append(
            row(
                f"{AIBO} peak RSS, one env, camera={camera!r} (ratio < 1: smaller)",
                aibo_rss,
                "MiB",
                reference,
                aibo_rss / ant_rss,
                target=("value", "<=", 400e6 / 2**20),
            )
        )  # 400 MB
    return rows


if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="python -m benchmarks.envs", description=__doc__)
    parser.add_argument(
        "--serve",
        nargs=2,
        metavar=("ENV_ID", "SETTING"),
        help="print steps/s of one block of steps per line read from stdin",
    )
    parser.add_argument("--peak-rss", nargs=2, metavar=("ENV_ID", "CAMERA"), help="print the peak RSS in MiB")
    args = parser.parse_args()
    if args.serve and args.serve[1] not in SETTINGS:
        parser.error(f"--serve: unknown setting {args.serve[1]!r}; choose from {', '.join(map(repr, SETTINGS))}")
    if args.serve:
        serve_blocks(args.serve[0], SETTINGS[args.serve[1]][0])
    elif args.peak_rss:
        print(peak_rss_mib(args.peak_rss[0], args.peak_rss[1] or None))
    else:
        for measurement in measure():
            print(json.dumps(measurement))
