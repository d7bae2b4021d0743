"""The default field through the head camera as a real ERS-7 saw it (specs/ers7-camera.md
sections 4-6): the carpet, the goals, a pink beacon part and the white wall, each filling the
image centre, read through the ``ers7`` profile at FL / HIGH / FAST (rUNSWift 2005's settings)
within the spread of the per-robot centre-patch means that ten real robots measured."""

import csv
import math
from pathlib import Path

import mujoco
import numpy as np
import pytest

from aibo_sim.camera import CameraSettings, scene_light
from aibo_sim.camera.sensor import ROBOT_GAIN_SIGMA, ROBOT_OFFSET_SIGMA, ROBOT_PIVOT
from aibo_sim.config import CameraConfig
from aibo_sim.sim import Simulation
from aibo_sim.team import RobotSpec

ROOT = Path(__file__).resolve().parents[1]
ROBOT_MEANS = ROOT.parent / "shared" / "data" / "ers7-camera" / "runswift2005_day1_robot_means.csv"
CHANNELS = ("Y", "Cr", "Cb")
SEEDS = range(4)  # frames of different noise: the noise is zero-mean
HALF = 5  # an 11 x 11 centre patch, as rUNSWift measured

# Each target: the data's name, the robot's pose (x, y, yaw), the point the head aims at (a geom's
# centre, with an offset), the neck tilt (deg) and the visual geom the whole patch must show.
# The white target is the field's white wall (the beacons' white parts are the same paint in the
# same light and read the same); goals and beacon face the robot head-on.
VIEWS = {
    "carpet": ("green", (-1.0, -0.8, 0.0), ("field_carpet", (-0.65, -0.8, 0.0)), -30, "field_carpet"),
    "skyblue_goal": ("lightblue", (2.0, 0.0, 0.0), ("goal_skyblue_back", (-0.01, 0, 0)), -5, "goal_skyblue"),
    "yellow_goal": ("yellow", (-2.0, 0.0, math.pi), ("goal_yellow_back", (0.01, 0, 0)), -5, "goal_yellow"),
    "pink_beacon": (
        "pink",
        (1.35, 1.45, math.pi / 2),
        ("beacon_skyblue_left_middle", (0, -0.05, 0)),
        -5,
        "beacon_pink",
    ),
    "white_wall": ("white", (0.5, 1.4, math.pi / 2), ("wall_left", (0.5, -0.01, 0)), -5, "wall"),
}
# The team uniforms, on robots 35 cm in front of robot 1 and behind it, their left flank towards it.
UNIFORM_ROBOTS = (
    RobotSpec("red", 1, (0, 0, 0)),
    RobotSpec("red", 2, (0.35, 0, 90)),
    RobotSpec("blue", 1, (-0.35, 0, -90)),
)
UNIFORM_VIEWS = {
    "red_uniform": ("red", (0.0, 0.0, 0.0), ("robot2/uniform_left", (0, 0, 0)), -10, "robot2/uniform_left"),
    "blue_uniform": ("blue", (0.0, 0.0, math.pi), ("robot3/uniform_left", (0, 0, 0)), -10, "robot3/uniform_left"),
}


def look_at(sim: Simulation, point: np.ndarray, neck_deg: float) -> None:
    """Neck tilt as given, head pan and tilt turned until ``point`` is on the optical axis."""
    model, data = sim.model, sim.data
    adr = {name: model.joint(name).qposadr[0] for name in ("neck_tilt", "head_pan", "head_tilt")}
    data.qpos[adr["neck_tilt"]] = math.radians(neck_deg)
    camera = sim.camera.camera_id
    for _ in range(20):
        mujoco.mj_kinematics(model, data)
        mujoco.mj_camlight(model, data)
        # Camera frame: x right, y up, z backwards (MuJoCo).
        x, y, z = (point - data.cam_xpos[camera]) @ data.cam_xmat[camera].reshape(3, 3)
        data.qpos[adr["head_pan"]] -= math.atan2(x, -z)
        data.qpos[adr["head_tilt"]] += math.atan2(y, -z)
    mujoco.mj_forward(model, data)
    sim.camera.moved()


@pytest.fixture(scope="module")
def measured() -> dict[str, np.ndarray]:
    """Per view (the field's and the uniforms'): the mean Y, Cr, Cb of the 11 x 11 centre patch
    over frames of four noise seeds."""
    return centre_means({}, VIEWS) | centre_means({"robots": UNIFORM_ROBOTS}, UNIFORM_VIEWS)


def centre_means(world: dict, views: dict) -> dict[str, np.ndarray]:
    sim = Simulation(camera=CameraConfig("ers7", settings=CameraSettings("fl", "high", "fast")), **world)
    try:
        means = {}
        for view, (_, pose, (geom, offset), neck, shown) in views.items():
            patches = []
            for seed in SEEDS:
                sim.reset(seed)
                sim.place_robot(*pose)
                look_at(sim, sim.data.geom_xpos[sim.model.geom(geom).id] + offset, neck)
                frame = sim.camera.frame().ycrcb.astype(float)
                h, w = frame.shape[:2]
                patches.append(frame[h // 2 - HALF : h // 2 + HALF + 1, w // 2 - HALF : w // 2 + HALF + 1])
            ids = sim.camera.segmentation()[h // 2 - HALF : h // 2 + HALF + 1, w // 2 - HALF : w // 2 + HALF + 1]
            assert np.all(ids == sim.model.geom(shown).id), f"{view}: the centre patch is not all {shown}"
            means[view] = np.mean(patches, axis=(0, 1, 2))
        return means
    finally:
        sim.close()


def robot_means() -> dict[str, dict[str, list[float]]]:
    """The data's centre-patch means, robot -> target -> [Y, Cr, Cb] (a row missing one is left out)."""
    if not ROBOT_MEANS.exists():
        pytest.skip(f"{ROBOT_MEANS} is not here")
    by_robot: dict[str, dict[str, list[float]]] = {}
    with ROBOT_MEANS.open(newline="", encoding="utf-8-sig") as f:
        for row in csv.DictReader(f):
            values = [(row.get(f"{c}_mean") or "").strip() for c in CHANNELS]
            if all(values):
                by_robot.setdefault(row["robot"], {})[row["target"]] = [float(v) for v in values]
    return by_robot


def test_robot_colour_spread_is_the_robots_linear_maps():
    """``RobotColour``'s sigmas are those of the per-robot lines (gain about the pivot, offset)
    that map the robots' average of each target to that robot's means, fitted per channel (over
    the targets every robot measured)."""
    by_robot = robot_means()
    targets = sorted(set.intersection(*(set(robot) for robot in by_robot.values())))
    means = np.array([[robot[t] for t in targets] for robot in by_robot.values()])  # robots, targets, channels
    average = means.mean(axis=0)
    for c, channel in enumerate(CHANNELS):
        x = average[:, c] - ROBOT_PIVOT[c]
        fits = [np.polyfit(x, robot[:, c] - ROBOT_PIVOT[c], 1) for robot in means]
        gain_sigma, offset_sigma = np.std(fits, axis=0, ddof=1)
        assert gain_sigma == pytest.approx(ROBOT_GAIN_SIGMA[c], rel=0.05), channel
        assert offset_sigma == pytest.approx(ROBOT_OFFSET_SIGMA[c], rel=0.05), channel


def robot_spread() -> dict[str, list[tuple[float, float]]]:
    """Per target of the data: (low, high) per channel, the mean over the robots +- 2 sample
    standard deviations of the robots' means."""
    by_robot = robot_means()
    spread = {}
    for target in {t for robot in by_robot.values() for t in robot}:
        values = np.array([robot[target] for robot in by_robot.values() if target in robot])
        mean, sigma = values.mean(axis=0), values.std(axis=0, ddof=1)
        spread[target] = list(zip(mean - 2 * sigma, mean + 2 * sigma))
    return spread


@pytest.mark.parametrize(
    "view, channel", [(view, channel) for view in {**VIEWS, **UNIFORM_VIEWS} for channel in CHANNELS]
)
def test_field_colours_within_the_spread_of_real_robots(measured, view, channel):
    low, high = robot_spread()[{**VIEWS, **UNIFORM_VIEWS}[view][0]][CHANNELS.index(channel)]
    value = measured[view][CHANNELS.index(channel)]
    assert low <= value <= high, f"{view} {channel} {value:.1f} outside the robots' {low:.1f}..{high:.1f}"


def test_field_colours_in_the_order_any_real_field_has(measured):
    """What must hold whatever the robot and the data: the carpet dark and green, the goals' and
    beacons' colours on their side of neutral, the white the brightest, warm under the venue's
    warm light at FL white balance (spec section 6: Cr up, Cb down)."""
    carpet, skyblue, yellow, pink, white = (measured[v] for v in VIEWS)
    y = {view: measured[view][0] for view in VIEWS}
    assert sorted(y, key=y.get) == ["carpet", "skyblue_goal", "pink_beacon", "yellow_goal", "white_wall"]
    assert carpet[0] < 70 and carpet[1] < 118 and carpet[2] < 128  # dark, green: red and blue below neutral
    assert skyblue[1] < 110 and skyblue[2] > 140
    assert yellow[2] < 80 and yellow[1] > 140 and yellow[0] > carpet[0] + 50
    assert pink[1] > 180 and pink[1] == max(m[1] for m in measured.values())
    assert white[1] > 133 and white[2] < 115  # the venue's warm cast


def test_the_default_field_is_lit_warm():
    sim = Simulation(camera=CameraConfig("ideal"))
    try:
        assert 2800 <= scene_light(sim.model).temperature_k <= 3600  # tungsten-halogen
    finally:
        sim.close()
