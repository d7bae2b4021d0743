"""The camera pipeline against bare MuJoCo, and the real-time factor, on the default scene.

- head-camera render alone (aibo_sim's Renderer, 208x160);
- the floor: bare MuJoCo doing what one camera frame needs, physics steps for 1/30 s
  plus ``mujoco.Renderer`` update, render and readback of the head camera at 208x160,
  shadows off (its default 2048^2 shadow map would make the floor ~10x slower here);
- the whole camera pipeline per backend: the controller API stepping 8 ms frames with
  the camera enabled, every 30 fps frame captured (sim: rendered RGB; openr: encoded,
  routed to the wrapper and decoded), in camera frames per second;
- real-time factor with the camera at 30 fps and without it.

    python -m benchmarks.pipeline
"""

import time

import mujoco

from aibo_sim.robot import Robot
from aibo_sim.sim import Simulation
from openr_bridge import FRAME_RATE_HZ, LAYER_SIZE, ofbkimageLAYER_H

from .common import best_mean_seconds, row

CAMERA = "PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1"
SIM_SECONDS = 3.0


def _floor_seconds_per_frame(sim: Simulation) -> float:
    model, data = sim.model, sim.data
    width, height = LAYER_SIZE[ofbkimageLAYER_H]
    renderer = mujoco.Renderer(model, height, width)
    renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False
    steps = round(1 / 30 / model.opt.timestep)

    def frame():
        mujoco.mj_step(model, data, nstep=steps)
        renderer.update_scene(data, camera="camera")
        renderer.render()

    seconds = best_mean_seconds(frame, 30)
    renderer.close()
    return seconds


def _run_seconds(backend: str, camera: bool) -> float:
    """Wall seconds to simulate SIM_SECONDS through the controller API."""
    robot = Robot(Simulation(), backend=backend)
    if camera:
        robot.get_device(CAMERA).enable(8)  # sampled every frame: every 30 fps picture is taken
    robot.step(80)  # warm-up: GL context, first frames
    start = time.perf_counter()
    robot.step(int(SIM_SECONDS * 1000))
    seconds = time.perf_counter() - start
    robot.sim.close()
    return seconds


def measure() -> list[dict]:
    sim = Simulation()
    sim.camera.frame()  # the camera's renderer exists from here on
    render_s = best_mean_seconds(lambda: sim.camera._render(sim.data, "rgb"), 50)
    width, height = sim.camera.render_size
    floor_s = _floor_seconds_per_frame(sim)
    sim.close()
    floor = "bare MuJoCo: steps for 1/30 s + Renderer 208x160 + readback"
    rows = [
        row(
            f"head-camera render alone, {width}x{height} (the ers7 lens renders wider, then remaps)",
            render_s * 1e3,
            "ms",
        ),
        row(floor, 1 / floor_s, "frames/s"),
    ]
    for backend in ("sim", "openr"):
        seconds = min(_run_seconds(backend, camera=True) for _ in range(3))
        fps = SIM_SECONDS * FRAME_RATE_HZ / seconds
        rows.append(
            row(
                f"camera pipeline, {backend} backend (physics + camera at 30 fps)",
                fps,
                "frames/s",
                floor,
                fps * floor_s,
                target=("ratio", ">=", 1 / 1.25),
            )
        )  # at most 1.25x the floor's cost
        rows.append(
            row(
                f"real-time factor, {backend} backend, camera at 30 fps",
                SIM_SECONDS / seconds,
                "x",
                target=("value", ">=", 15),
            )
        )
    blind = min(_run_seconds("sim", camera=False) for _ in range(3))
    rows.append(row("real-time factor, no camera", SIM_SECONDS / blind, "x", target=("value", ">=", 60)))
    return rows


if __name__ == "__main__":
    for r in measure():
        print(r)
