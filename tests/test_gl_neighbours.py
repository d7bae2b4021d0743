"""Good neighbours in one process (issue 15): our renderers leave the OpenGL context that was
current as they found it, so Gymnasium's MuJoCo renderer keeps drawing."""

import numpy as np
import pytest

from aibo_sim.sim import Simulation


def _ours_between(frames: list, draw, interleave: bool) -> list:
    sim = Simulation() if interleave else None
    out = []
    for _ in range(3):
        out.append(draw())
        if sim is not None:
            sim.step_frames(sim.frames_to_camera_frame())
            sim.camera.frame()
    if sim is not None:
        sim.close()
    return out


def test_gymnasium_mujoco_env_renders_the_same_beside_ours():
    gym = pytest.importorskip("gymnasium")
    pytest.importorskip("imageio")  # gymnasium[mujoco]

    def frames(interleave):
        env = gym.make("Ant-v5", render_mode="rgb_array", width=64, height=48)
        env.reset(seed=0)

        def draw():
            env.step(np.zeros(env.action_space.shape))
            return env.render().copy()

        result = _ours_between([], draw, interleave)
        env.close()
        return result

    alone, beside = frames(False), frames(True)
    assert alone[0].mean() > 20 and all(np.array_equal(a, b) for a, b in zip(alone, beside))
