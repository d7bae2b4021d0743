"""ThreadedVectorEnv (aibo-sim's environments in threads of one process) and HybridVectorEnv
(the first in this process, the others in worker processes) step them as Gymnasium's
SyncVectorEnv does, bit for bit."""

import signal
import time

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.envs.registration import EnvSpec

import aibo_sim  # noqa: F401  (registers the environments)
from aibo_sim.envs.threaded import ThreadedVectorEnv
from aibo_sim.envs.vector import HybridVectorEnv

HEAD_TRACK = "aibo_sim/HeadTrackBall-v0"


def run(envs, actions, seed, reset_mask_at=None):
    obs, info = envs.reset(seed=seed)
    steps = [(obs, np.zeros(envs.num_envs), np.zeros(envs.num_envs, bool), np.zeros(envs.num_envs, bool), info)]
    for k, action in enumerate(actions):
        if k == reset_mask_at:
            mask = np.array([False, True, False])
            obs, info = envs.reset(seed=[None, 11, None], options={"reset_mask": mask})
            steps.append((obs, None, None, None, info))
        steps.append(envs.step(action))
    return steps


def assert_same(a, b):
    if isinstance(a, dict):
        assert a.keys() == b.keys()
        for key in a:
            assert_same(a[key], b[key])
    elif a is not None:
        np.testing.assert_array_equal(a, b)
        assert np.asarray(a).dtype == np.asarray(b).dtype


@pytest.mark.parametrize(
    ("make_envs", "kind"),
    [
        (lambda: ThreadedVectorEnv(HEAD_TRACK, 3, max_episode_steps=4), ThreadedVectorEnv),
        (lambda: gym.make_vec(HEAD_TRACK, 3, max_episode_steps=4), HybridVectorEnv),  # make_vec's default
    ],
    ids=["threads", "hybrid"],
)
@pytest.mark.slow
def test_vector_envs_step_as_sync_bit_for_bit_through_autoreset_and_reset_mask(make_envs, kind):
    # 3 envs, episodes of 4 steps: each autoresets twice within the 12 steps.
    threaded = make_envs()
    sync = gym.make_vec(HEAD_TRACK, 3, "sync", max_episode_steps=4)
    assert type(threaded.unwrapped) is kind
    assert threaded.observation_space == sync.observation_space and threaded.action_space == sync.action_space
    threaded.action_space.seed(3)
    actions = [threaded.action_space.sample() for _ in range(12)]
    try:
        runs = [run(envs, actions, seed=5, reset_mask_at=6) for envs in (threaded, sync)]
        for step_threaded, step_sync in zip(*runs, strict=True):
            for part_threaded, part_sync in zip(step_threaded, step_sync, strict=True):
                assert_same(part_threaded, part_sync)
        truncated = np.array([step[3] for step in runs[0] if step[3] is not None])
        assert truncated.any(axis=0).all()  # every env reached its time limit
        images = runs[0][-1][0]["image"]
        assert not np.array_equal(images[0], images[1])
        assert threaded.get_attr("camera_layer") == ("H", "H", "H")
    finally:
        threaded.close()
        sync.close()


def test_errors_reach_the_caller_and_a_closed_env_refuses():
    envs = ThreadedVectorEnv(HEAD_TRACK, 2)
    envs.reset(seed=0)
    with pytest.raises(ValueError, match="environment 0.s action is not finite"):  # checked before any thread steps
        envs.step(np.full(envs.action_space.shape, np.nan, np.float32))
    with pytest.raises(ValueError, match="reset_mask"):
        envs.reset(options={"reset_mask": np.zeros(2, bool)})
    for rows in (1, 3):  # one row short, one too many: neither dropped nor an IndexError from a thread
        with pytest.raises(ValueError, match=rf"actions of shape \({rows}, 3\): want \(2, 3\)"):
            envs.step(np.zeros((rows, 3), np.float32))
    envs.close()
    assert all(not thread.is_alive() for thread in envs.unwrapped._threads)
    with pytest.raises(gym.error.ClosedEnvironmentError, match="closed"):
        envs.step(envs.action_space.sample())
    with pytest.raises(TypeError):
        ThreadedVectorEnv(HEAD_TRACK, 2, camera_bogus=1)  # the environment's own error, from its thread


def test_an_interrupted_call_needs_a_reset_and_its_late_results_are_dropped():
    threaded = ThreadedVectorEnv(HEAD_TRACK, np.int64(2))  # numpy's integers count, as for "sync"
    sync = gym.make_vec(HEAD_TRACK, 2, "sync")
    actions = [threaded.action_space.sample() for _ in range(3)]

    def interrupt(*_):
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGALRM, interrupt)
    try:
        threaded.reset(seed=1)
        signal.setitimer(signal.ITIMER_REAL, 0.05)
        with pytest.raises(KeyboardInterrupt):
            threaded.unwrapped.call_each(lambda env: time.sleep(0.3) or "late")
        with pytest.raises(gym.error.ResetNeeded, match="interrupted"):
            threaded.step(actions[0])
        assert threaded.get_attr("camera") == ("rgb", "rgb")  # not the interrupted call's "late"
        for envs in (threaded, sync):
            envs.reset(seed=1)
        for action in actions:
            for part_threaded, part_sync in zip(threaded.step(action), sync.step(action), strict=True):
                assert_same(part_threaded, part_sync)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
        threaded.close()
        sync.close()


def test_make_vec_makes_a_hybrid_env_for_every_id_by_default():
    """Also from the spec read back from its JSON (a dataset's record of it: the vector entry
    point a "module:function" string, which a callable could not be)."""
    for env_id in aibo_sim.envs.ENV_SPECS:
        restored = EnvSpec.from_json(gym.spec(env_id).to_json())
        assert restored == gym.spec(env_id) and isinstance(restored.vector_entry_point, str)
        for made_from, mode in ((env_id, None), (env_id, "vector_entry_point"), (restored, None)):
            envs = gym.make_vec(made_from, 1, mode, camera_layer="L")  # 1 env: no worker process
            try:
                assert type(envs) is HybridVectorEnv and envs.get_attr("camera_layer") == ("L",)
                assert envs.get_attr("spec")[0].id == env_id
                assert envs.get_attr("spec")[0].max_episode_steps == gym.spec(env_id).max_episode_steps
            finally:
                envs.close()
