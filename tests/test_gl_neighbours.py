"""Good neighbours in one process (issue 15): our renderers leave the OpenGL context that was
current as they found it, so Gymnasium's MuJoCo renderer and mujoco.Renderer keep drawing."""

import numpy as np
import pytest

from aibo_sim.config import CameraConfig
from aibo_sim.sim import Simulation

pytestmark = pytest.mark.slow  # heavy: run by CI and by python -m pytest -m slow


def _ours_between(draw, interleave: bool) -> list:
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

        result = _ours_between(draw, interleave)
        env.close()
        return result

    alone, beside = frames(False), frames(True)
    assert alone[0].mean() > 20 and all(np.array_equal(a, b) for a, b in zip(alone, beside))


def test_mujoco_renderer_and_ours_draw_the_same_beside_each_other():
    import mujoco

    from aibo_sim.sim import load_model

    def frames(interleave):
        model = load_model()
        data = mujoco.MjData(model)
        renderer = mujoco.Renderer(model, 48, 64)

        def draw():
            mujoco.mj_step(model, data, nstep=5)
            renderer.update_scene(data, camera="camera")
            return renderer.render().copy()

        result = _ours_between(draw, interleave)
        renderer.close()
        return result

    alone, beside = frames(False), frames(True)
    assert alone[0].mean() > 20 and all(np.array_equal(a, b) for a, b in zip(alone, beside))
    # And ours, with a mujoco.Renderer made first and drawing between our frames.
    model = load_model()
    data = mujoco.MjData(model)
    renderer = mujoco.Renderer(model, 48, 64)
    ours = []
    for neighbour in (False, True):
        sim = Simulation(camera=CameraConfig("ideal"))
        pictures = []
        for _ in range(3):
            sim.step_frames(sim.frames_to_camera_frame())
            pictures.append(sim.camera.frame().rgb.copy())
            if neighbour:
                renderer.update_scene(data, camera="camera")
                renderer.render()
        sim.close()
        ours.append(pictures)
    renderer.close()
    assert all(np.array_equal(a, b) for a, b in zip(*ours))


@pytest.mark.skipif(
    not __import__("ctypes.util").util.find_library("OSMesa"), reason="needs libOSMesa (CI installs it)"
)
def test_the_same_holds_with_osmesa():
    """MUJOCO_GL=osmesa (read when MuJoCo is imported, hence another process): the tests above."""
    import os
    import subprocess
    import sys

    result = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", __file__, "-m", "", "-k", "not osmesa"],
        env={**os.environ, "MUJOCO_GL": "osmesa", "PYOPENGL_PLATFORM": "osmesa"},
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0 and "2 passed" in result.stdout, result.stdout[-2000:]
