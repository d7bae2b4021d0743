"""A match's cost: the head camera per robot with 1, 4 and 8 robots, and a 4-against-4 run.

Camera: a world of N robots at the kickoff poses (the first N of red 1-4, blue 1-4), the ``ers7``
camera; after each camera tick every robot's frame is made (render, lens, sensor) by
``World.frames`` (the robots' frames in parallel threads, as a match's controllers and
``MatchEnv`` make them), timed, and divided by N: the time of one robot-frame. The reference is
one robot alone (red 1, with its uniform) in the same run; the goal is at most 1.2x with 8 robots.
With 8 robots the frames made one after another in one thread are timed too (the work itself,
without the parallelism). Best of ``REPEATS``, the worlds taking turns.

Match: ``run_match`` with ``controllers/ball_tracker.py`` on all 8 robots (frames not written),
its real-time factor against the same controller on one robot (``run_controller``).

Run: ``python -m benchmarks --only match``
"""

from __future__ import annotations

import time
from pathlib import Path

from aibo_sim.config import WorldConfig
from aibo_sim.match import run_match
from aibo_sim.runner import run_controller
from aibo_sim.sim import Simulation
from aibo_sim.team import RobotSpec, check_robots

from .common import REPEATS, row

ROOT = Path(__file__).resolve().parents[1]
TRACKER = ROOT / "controllers" / "ball_tracker.py"
KICKOFF = check_robots([RobotSpec(team, number) for team in ("red", "blue") for number in (1, 2, 3, 4)], "benchmark")
CAMERA_FRAMES = 30
MATCH_SECONDS = 5.0
BALL = (0.3, 0.2)


def camera_ms_per_robot_frame() -> dict:
    """Best mean wall time (ms) of one robot's camera frame, by (robots, parallel): 1, 4 and 8 robots
    with the frames made by ``World.frames``, and 8 made one after another. The worlds take turns
    in each repeat, so that the machine's noise falls on all of them alike."""
    cases = ((1, True), (4, True), (8, True), (8, False))
    worlds = {count: Simulation(robots=KICKOFF[:count], seed=1) for count in (1, 4, 8)}
    try:
        for sim in worlds.values():
            sim.world.frames()  # renderers made, numba compiled
        best = dict.fromkeys(cases, float("inf"))
        for _ in range(REPEATS):
            for count, parallel in cases:
                sim, spent = worlds[count], 0.0
                for _ in range(CAMERA_FRAMES):
                    sim.step_frames(sim.frames_to_camera_frame(), sensors=False)
                    start = time.perf_counter()
                    if parallel:
                        sim.world.frames()
                    else:
                        for camera in sim.world.cameras:
                            camera.frame()
                    spent += time.perf_counter() - start
                best[count, parallel] = min(best[count, parallel], spent / (CAMERA_FRAMES * count) * 1000)
        return best
    finally:
        for sim in worlds.values():
            sim.close()


def measure() -> list[dict]:
    timed = camera_ms_per_robot_frame()
    per_robot, one_thread = {count: timed[count, True] for count in (1, 4, 8)}, timed[8, False]
    alone = "ers7 camera frame, one robot alone (ms per robot-frame)"
    rows = [row(alone, per_robot[1], "ms")]
    for count in (4, 8):
        rows.append(
            row(
                f"ers7 camera frame per robot, {count} robots on the field (World.frames)",
                per_robot[count],
                "ms",
                alone,
                per_robot[1] / per_robot[count],
                target=("ratio", ">=", 1 / 1.2) if count == 8 else None,
            )
        )  # with 8 robots, at most 1.2x one robot's time
    rows.append(
        row(
            "ers7 camera frame per robot, 8 robots, made one after another",
            one_thread,
            "ms",
            alone,
            per_robot[1] / one_thread,
        )
    )
    single = max(
        run_controller(TRACKER, duration=MATCH_SECONDS, progress=False, world=WorldConfig(ball=BALL)).real_time_factor
        for _ in range(2)
    )
    robots = [RobotSpec(r.team, r.number, r.pose, str(TRACKER)) for r in KICKOFF]
    match = max(
        run_match(robots, duration=MATCH_SECONDS, progress=False, world=WorldConfig(ball=BALL))["real_time_factor"]
        for _ in range(2)
    )
    reference = "real-time factor, ball_tracker.py on one robot"
    rows.append(row(reference, single, "x"))
    rows.append(
        row("real-time factor, 4 against 4, ball_tracker.py on every robot", match, "x", reference, match / single)
    )
    return rows


if __name__ == "__main__":
    for r in measure():
        print(r)
