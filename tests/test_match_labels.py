"""Labels in a match (issue 41): every robot is class "robot" in the segmentation, each pixel's robot
instance and team, COCO detections of the other robots (named, per team, occlusion-aware), never the
observing robot's own body; a lone robot's labels as before matches."""

import hashlib
import json
import math

import mujoco
import numpy as np
import pytest
from pycocotools.coco import COCO

from aibo_sim.config import CameraConfig
from aibo_sim.dump.coco import Objects, coco_dataset
from aibo_sim.dump.formats import (
    DUMP_FORMAT,
    ball_in_image,
    geom_classes,
    geom_robots,
    instance_teams,
    is_match,
    robot_labels,
    robot_roots,
    robots_meta,
)
from aibo_sim.field import COCO_CATEGORIES, LABEL_TEAMS, SEGMENTATION_CLASSES, TEAM_CATEGORIES
from aibo_sim.sim import Simulation
from aibo_sim.team import TEAMS, RobotSpec

W, H = 208, 160
ROBOT = SEGMENTATION_CLASSES.index("robot")
# Robot 1 (red 1, the observer) at the centre spot facing +X; in its view blue 3 stands clear on the
# left, red 2 side-on on the right and blue 4 behind red 2, mostly hidden by it.
MATCH = (
    RobotSpec("red", 1, (0.0, 0.0, 0.0)),
    RobotSpec("blue", 3, (1.4, 0.3, 90.0)),
    RobotSpec("red", 2, (1.0, -0.2, 90.0)),
    RobotSpec("blue", 4, (1.7, -0.5, -90.0)),
)


def rle_mask(rle: dict) -> np.ndarray:
    """The (h, w) boolean mask of COCO's uncompressed run-length encoding (``coco.mask_rle``)."""
    h, w = rle["size"]
    values = np.arange(len(rle["counts"])) % 2 == 1  # runs of 0s first
    return np.repeat(values, rle["counts"]).reshape((h, w), order="F")


@pytest.fixture(scope="module")
def match():
    sim = Simulation(robots=MATCH)  # the ers7 profile: the distorted lens
    sim.place_ball(-2.0, 1.0)  # behind the observer
    yield sim
    sim.world.close()


@pytest.fixture(scope="module")
def seen(match):
    """Robot 1's detections by object name, its segmentation (geom ids) and robot labels."""
    detections = Objects(match).detect()
    ids = match.camera.segmentation()
    return {d["object"]: d for d in detections}, ids, *robot_labels(match, ids)


def test_every_robot_is_class_robot_with_its_instance_and_team(match):
    model = match.model
    roots = robot_roots(model)
    assert roots == {int(model.body_rootid[robot._body]): k + 1 for k, robot in enumerate(match.world.robots)}
    classes, instances = geom_classes(model), geom_robots(model)
    for robot in match.world.robots:
        mine = np.flatnonzero(model.body_rootid[model.geom_bodyid] == model.body_rootid[robot._body])
        assert (classes[mine] == ROBOT).all() and (instances[mine] == robot.index + 1).all()
        uniform = [model.geom(f"{robot.prefix}uniform_{side}").id for side in ("left", "right")]
        assert (classes[uniform] == ROBOT).all()
    assert (instances[classes != ROBOT] == 0).all() and instances[-1] == 0  # the background entry


def test_robot_labels_give_each_robot_pixel_its_instance_and_team(match, seen):
    detections, ids, instances, teams = seen
    assert instances.shape == teams.shape == (H, W) and instances.dtype == teams.dtype == np.uint8
    assert set(np.unique(instances).tolist()) == {0, 2, 3, 4}  # red 1 sees none of itself here
    assert ((geom_classes(match.model)[ids] == ROBOT) == (instances > 0)).all()
    for k, spec in enumerate(MATCH, start=1):
        assert (teams[instances == k] == LABEL_TEAMS.index(spec.team)).all()
        if k > 1:  # a robot's pixels are those of its detection's mask
            assert (rle_mask(detections[spec.name]["segmentation"]) == (instances == k)).all()
    assert (teams[instances == 0] == 0).all()
    meta = robots_meta(match.world.robot_specs, match.index + 1)
    assert meta["observer"] == 1 and meta["teams"] == [None, *TEAMS] and is_match(match.world.robot_specs)
    assert [(r["id"], r["team"], r["number"], r["name"]) for r in meta["instances"]] == [
        (k, s.team, s.number, s.name) for k, s in enumerate(MATCH, start=1)
    ]
    assert (instance_teams(json.loads(json.dumps(meta)))[instances] == teams).all()  # as a dump reads it back


def test_coco_detections_name_the_other_robots_with_team_number_and_visibility(match, seen):
    detections = seen[0]
    robots = {name: d for name, d in detections.items() if d["category"] == "robot"}
    assert set(robots) == {"blue 3", "red 2", "blue 4"}  # never red 1, the observer
    for spec in MATCH[1:]:
        d = robots[spec.name]
        assert (d["team"], d["number"]) == (spec.team, spec.number)
        x, y, w, h = d["bbox"]
        assert 0 <= x < x + w <= W and 0 <= y < y + h <= H and 0 < d["area"] <= w * h
        # the robot's trunk centre projects inside its box
        (u, v), depth = (
            a[0] for a in match.camera.project(match.data.xpos[match.world.robots[MATCH.index(spec)]._body])
        )
        assert depth > 0 and x - 0.5 <= u <= x + w - 0.5 and y - 0.5 <= v <= y + h - 0.5
    clear, occluder, hidden = robots["blue 3"], robots["red 2"], robots["blue 4"]
    assert clear["visibility"] == 1.0 and occluder["visibility"] == 1.0
    x, y, w, h = clear["bbox"]
    assert 0 < x and x + w < W and 0 < y and y + h < H  # whole in the picture: nothing cut
    assert 0.05 < hidden["visibility"] < 0.8  # partly behind red 2
    assert hidden["area"] < occluder["area"] and hidden["area"] < clear["area"]
    hx, hy, hw, hh = hidden["bbox"]
    ox, oy, ow, oh = occluder["bbox"]
    assert ox < hx + hw and hx < ox + ow and oy < hy + hh and hy < oy + oh  # the boxes overlap
    assert "ball" not in detections and "goal_skyblue" in detections


def test_no_robot_labels_its_own_body(match):
    for robot in match.world.robots:
        names = {d["object"] for d in Objects(robot).detect()}
        assert robot.spec.name not in names
    # robot 1 looking down at its own front leg: its pixels are its instance, never a detection
    model, data = match.model, match.data
    saved = data.qpos.copy()
    try:
        for joint, degrees in (("neck_tilt", -80), ("head_tilt", -20), ("head_pan", 40)):
            data.qpos[model.joint(joint).qposadr[0]] = math.radians(degrees)
        mujoco.mj_forward(model, data)
        match._moved()
        objects = Objects(match)
        instances, teams = robot_labels(match)
        own = instances == 1
        assert own.sum() > 100 and (teams[own] == LABEL_TEAMS.index("red")).all()
        for d in objects.detect():
            assert d["object"] != "red 1" and not (rle_mask(d["segmentation"]) & own).any()
        assert Objects(match.model).detect(match) == objects.detect()  # a model: the robot detect is given
    finally:
        data.qpos[:] = saved
        mujoco.mj_forward(model, data)
        match._moved()


def test_a_ball_behind_another_robots_head_is_not_visible(match):
    model, data = match.model, match.data
    head = data.xpos[model.body("robot3/head").id].copy()  # red 2's head (group 1: hidden from its own camera only)
    camera = match.camera.frame().position
    position, velocity = match.ball_state()
    saved = position.copy(), velocity.copy()
    try:
        position[:3], velocity[:] = camera + 1.5 * (head - camera), 0  # in the air, on the line through the head
        mujoco.mj_forward(model, data)
        match._moved()
        ball = ball_in_image(match)
        assert ball["pixel"] is not None and not ball["visible"]
        assert "ball" not in {d["object"] for d in Objects(match).detect()}
    finally:
        position[:], velocity[:] = saved
        mujoco.mj_forward(model, data)
        match._moved()


def _dump_folder(folder, objects, robots=None):
    """A one-frame dump folder as ``coco_dataset`` reads it."""
    folder.mkdir()
    meta = {"format": DUMP_FORMAT, "parameters": {"frames": 1}, "camera": {"width": W, "height": H}}
    if robots is not None:
        meta["robots"] = robots
    (folder / "meta.json").write_text(json.dumps(meta))
    (folder / "frames.jsonl").write_text(json.dumps({"index": 0, "objects": objects}) + "\n")


def test_coco_json_has_a_category_per_team_and_the_robots_team_and_number(match, seen, tmp_path):
    assert COCO_CATEGORIES[: len(SEGMENTATION_CLASSES)] == SEGMENTATION_CLASSES
    assert set(TEAM_CATEGORIES) == set(TEAMS) and set(LABEL_TEAMS[1:]) == set(TEAMS)
    _dump_folder(tmp_path / "match", list(seen[0].values()))
    (tmp_path / "match" / "coco.json").write_text(json.dumps(coco_dataset(tmp_path / "match", [tmp_path / "match"])))
    coco = COCO(str(tmp_path / "match" / "coco.json"))
    categories = {c["name"]: c["id"] for c in coco.loadCats(coco.getCatIds())}
    assert categories == {
        **{name: SEGMENTATION_CLASSES.index(name) for name in ("ball", "goal", "beacon", "robot")},
        "robot_red": len(SEGMENTATION_CLASSES),
        "robot_blue": len(SEGMENTATION_CLASSES) + 1,
    }
    robots = {a["object"]: a for a in coco.dataset["annotations"] if "team" in a}
    assert {name: (a["category_id"], a["team"], a["number"]) for name, a in robots.items()} == {
        "blue 3": (categories["robot_blue"], "blue", 3),
        "red 2": (categories["robot_red"], "red", 2),
        "blue 4": (categories["robot_blue"], "blue", 4),
    }
    for name, a in robots.items():
        assert a["bbox"] == seen[0][name]["bbox"] and a["visibility"] == seen[0][name]["visibility"]
        k = next(i for i, s in enumerate(MATCH, start=1) if s.name == name)
        assert (coco.annToMask(a).astype(bool) == (seen[2] == k)).all()
    # a match dump that never saw another robot lists the teams' categories too (meta.json's "robots")
    _dump_folder(tmp_path / "empty", [], robots_meta(MATCH, 1))
    dataset = coco_dataset(tmp_path / "empty", [tmp_path / "empty"])
    assert [c["name"] for c in dataset["categories"]] == ["ball", "goal", "beacon", "robot", "robot_red", "robot_blue"]
    # a lone robot's dump: the categories as before
    _dump_folder(tmp_path / "alone", [seen[0]["goal_skyblue"]])
    dataset = coco_dataset(tmp_path / "alone", [tmp_path / "alone"])
    assert dataset["categories"] == [
        {"id": SEGMENTATION_CLASSES.index(n), "name": n} for n in ("ball", "goal", "beacon", "robot")
    ]
    assert set(dataset["annotations"][0]) == {
        "id",
        "image_id",
        "category_id",
        "bbox",
        "area",
        "iscrowd",
        "visibility",
        "object",
        "segmentation",
    }


# A lone robot's detections at two known poses (ers7 profile), made by the code before matches
# (the tree at 72a6158), with the robot then 0.1 mm lower (its paws sunk as they rest, mjcf.PAW_SINK,
# remade so): sha256 of their JSON (masks included), and the fields without the masks.
LONE_ROBOT = {
    "goal": (
        (1.6, 0.2, 0.0, 2.2, 0.0),
        "448c0621d2515aa39366c09341332a52cb6db70f2c34a1ec6ddbd5a9d01f889b",
        [
            {"category": "goal", "object": "goal_skyblue", "bbox": [55, 0, 153, 72], "area": 9347, "visibility": 1.0},
            {"category": "ball", "object": "ball", "bbox": [172, 82, 36, 38], "area": 1123, "visibility": 1.0},
        ],
        {"pixel": [191.02655183321866, 100.06010202014293], "visible": True, "distance_m": 0.4878698161530265},
    ),
    "beacon": (
        (
            0.0,
            0.0,
            math.atan2(1.95, 1.35),
            2.35 * math.cos(math.atan2(1.95, 1.35)),
            2.35 * math.sin(math.atan2(1.95, 1.35)),
        ),
        "8ba4caa1793371ed63a40fc1dd369f6f350866b741bb1382d51a7413ab48d548",
        [
            {
                "category": "beacon",
                "object": "beacon_skyblue_left",
                "bbox": [98, 7, 10, 41],
                "area": 336,
                "visibility": 0.8984,
            },
            {"category": "ball", "object": "ball", "bbox": [99, 41, 8, 6], "area": 38, "visibility": 0.7917},
        ],
        {"pixel": [102.69014082411618, 42.89488838920831], "visible": True, "distance_m": 2.172604822887163},
    ),
}
# The geom classes of that robot, remade when its 14 face-light geoms became 18 spots (Model
# Information A.2): every other geom's class the same, the new spots LEDs as the old ones were.
LONE_CLASSES_SHA256 = "45079ff9c44ca5e6b4ec45f61b55a85b7c704bf797e7b20b1228b6ad62300a5b"


def test_a_lone_robots_labels_are_those_before_matches():
    sim = Simulation(camera=CameraConfig("ers7"))
    try:
        assert hashlib.sha256(geom_classes(sim.model).tobytes()).hexdigest() == LONE_CLASSES_SHA256
        assert robot_roots(sim.model) == {sim._body: 1} and not is_match(sim.world.robot_specs)
        by_sim, by_model = Objects(sim), Objects(sim.model)
        for (x, y, yaw, bx, by), digest, fields, ball in LONE_ROBOT.values():
            sim.reset()
            sim.place_robot(x, y, yaw)
            sim.place_ball(bx, by)
            detections = by_sim.detect()
            assert by_model.detect(sim) == detections
            assert [{k: v for k, v in d.items() if k != "segmentation"} for d in detections] == fields
            assert hashlib.sha256(json.dumps(detections).encode()).hexdigest() == digest
            seen = ball_in_image(sim)  # floats from MuJoCo's arithmetic: the last bit may differ by CPU
            assert seen["visible"] == ball["visible"]
            assert seen["pixel"] == pytest.approx(ball["pixel"], rel=1e-12, abs=1e-9)
            assert seen["distance_m"] == pytest.approx(ball["distance_m"], rel=1e-12)
            instances, teams = robot_labels(sim)
            assert not instances.any() and not teams.any()
    finally:
        sim.close()
