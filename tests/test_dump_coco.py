"""Detection labels in dumps (issue 18): COCO boxes from the camera's segmentation, checked
against the projection, occlusion, shards and resume."""

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from pycocotools.coco import COCO

from aibo_sim.cli import main
from aibo_sim.config import CameraConfig, WorldConfig
from aibo_sim.dump import dump, load_dump
from aibo_sim.dump.coco import Objects, coco_bytes, mask_rle
from aibo_sim.field import SEGMENTATION_CLASSES
from aibo_sim.sim import Simulation

ROOT = Path(__file__).resolve().parents[1]
TRACKER = ROOT / "controllers" / "ball_tracker.py"
W, H = 208, 160
CENTRE_BOUND = 2.0  # px, box centre to the projected ball centre (a sphere images off-centre; pixels are whole)
FORMATS = ("rgb", "coco")


@pytest.fixture(scope="module")
def coco_dump(tmp_path_factory):
    out = tmp_path_factory.mktemp("coco") / "dump"
    dump(out, controller=TRACKER, frames=30, formats=FORMATS + ("seg",))  # the ers7 lens: distorted
    return out


def test_coco_file_loads_and_the_ball_box_is_centred_on_its_projection(coco_dump):
    coco = COCO(str(coco_dump / "coco.json"))
    assert {c["name"]: c["id"] for c in coco.loadCats(coco.getCatIds())} == {
        name: SEGMENTATION_CLASSES.index(name) for name in ("ball", "goal", "beacon", "robot")
    }
    frames = load_dump(coco_dump)
    assert sorted(coco.getImgIds()) == list(range(1, 31))
    ball_id = SEGMENTATION_CLASSES.index("ball")
    centred = 0
    for image_id, frame in zip(range(1, 31), frames):
        image = coco.loadImgs(image_id)[0]
        assert (coco_dump / image["file_name"]).is_file() and (image["width"], image["height"]) == (W, H)
        annotations = coco.loadAnns(coco.getAnnIds(imgIds=image_id))
        for a in annotations:
            x, y, w, h = a["bbox"]
            assert 0 <= x < x + w <= W and 0 <= y < y + h <= H and 0 < a["area"] <= w * h
            assert 0 < a["visibility"] <= 1
        balls = [a for a in annotations if a["category_id"] == ball_id]
        assert len(balls) == 1 and balls[0]["object"] == "ball"  # the tracker keeps it in view
        x, y, w, h = balls[0]["bbox"]
        if balls[0]["visibility"] == 1 and 0 < x and x + w < W and 0 < y and y + h < H:
            assert math.dist((x + w / 2 - 0.5, y + h / 2 - 0.5), frame.meta["ball"]["pixel"]) <= CENTRE_BOUND
            centred += 1
    assert centred >= 20
    goals = [a for a in coco.dataset["annotations"] if a["object"] == "goal_skyblue"]
    assert goals and all(a["category_id"] == SEGMENTATION_CLASSES.index("goal") for a in goals)


def test_coco_masks_decode_to_the_pixels_of_each_box_and_the_ball_to_its_segmentation(coco_dump):
    """pycocotools decodes each mask (run-length, column-major) to ``area`` pixels filling
    ``bbox``; the ball's is the segmentation file's ball class, pixel for pixel."""
    coco = COCO(str(coco_dump / "coco.json"))
    ball_id = SEGMENTATION_CLASSES.index("ball")
    for image_id, frame in zip(range(1, 31), load_dump(coco_dump)):
        for a in coco.loadAnns(coco.getAnnIds(imgIds=image_id)):
            mask = coco.annToMask(a)
            ys, xs = np.nonzero(mask)
            assert mask.shape == (H, W) and mask.sum() == a["area"]
            assert [xs.min(), ys.min(), xs.max() - xs.min() + 1, ys.max() - ys.min() + 1] == a["bbox"]
            if a["category_id"] == ball_id:
                np.testing.assert_array_equal(mask, frame.seg == ball_id)


def test_goal_and_beacon_masks_are_the_segmentation_files_pixels_of_their_class(tmp_path):
    """Goals and beacons are drawn as merged meshes, labelled from their own geoms: their masks
    together are the seg file's pixels of their class, pixel for pixel (a few edge pixels
    differed, either way), each frame of a dump facing the sky-blue goal."""
    out = tmp_path / "dump"
    dump(
        out, controller=TRACKER, frames=30, formats=FORMATS + ("seg",), world=WorldConfig(pose=(0, 0, 0), ball=(2.3, 0))
    )
    coco = COCO(str(out / "coco.json"))
    seen = 0
    for image_id, frame in zip(range(1, 31), load_dump(out)):
        for category in ("goal", "beacon"):
            number = SEGMENTATION_CLASSES.index(category)
            masks = [coco.annToMask(a) for a in coco.loadAnns(coco.getAnnIds(imgIds=image_id, catIds=number))]
            union = np.sum(masks, axis=0) if masks else np.zeros((H, W))
            assert union.max() <= 1  # one object a pixel
            np.testing.assert_array_equal(union > 0, frame.seg == number, err_msg=f"frame {image_id - 1} {category}")
            seen += int(union.sum())
    assert seen > 30 * 1000  # the goal fills a good part of every frame


def test_records_without_masks_still_give_boxes(coco_dump, tmp_path):
    """A dump recorded before masks were (its frames.jsonl has none) still gets its coco.json."""
    old = tmp_path / "old"
    old.mkdir()
    shutil.copy(coco_dump / "meta.json", old)
    records = [json.loads(line) for line in (coco_dump / "frames.jsonl").read_text().splitlines()]
    for record in records:
        for item in record["objects"]:
            del item["segmentation"]
    (old / "frames.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records))
    boxes = json.loads(coco_bytes(old, [old]))["annotations"]
    masked = json.loads((coco_dump / "coco.json").read_bytes())["annotations"]
    assert boxes == [{k: v for k, v in a.items() if k != "segmentation"} for a in masked] and boxes


@pytest.mark.parametrize(
    "mask, counts",
    [
        ([[0, 1], [0, 1], [0, 0]], [3, 2, 1]),  # column-major: down the first column, then the second
        ([[1, 0], [1, 0], [0, 1]], [0, 2, 3, 1]),  # set at (0, 0): a first run of no zeros
        ([[1, 1]], [0, 2]),
        ([[0, 0]], [2]),
    ],
)
def test_mask_rle_counts_runs_down_the_columns_from_zeros(mask, counts):
    mask = np.array(mask, bool)
    assert mask_rle(mask) == {"size": list(mask.shape), "counts": counts}


@pytest.mark.parametrize("profile", ["ideal", "ers7"])
def test_a_ball_behind_a_beacon_loses_visibility_then_its_box(profile):
    sim = Simulation(camera=CameraConfig(profile))
    objects = Objects(sim.model)
    heading = math.atan2(1.95, 1.35)  # towards the sky-blue left beacon
    sim.place_robot(0, 0, heading)

    def detect(distance):
        sim.place_ball(distance * math.cos(heading), distance * math.sin(heading))
        return {d["object"]: d for d in objects.detect(sim)}

    try:
        seen, partly, hidden = detect(2.2), detect(2.35), detect(2.48)
    finally:
        sim.close()
    assert seen["ball"]["visibility"] == 1.0 and seen["beacon_skyblue_left"]["visibility"] < 1  # the ball in front
    assert 0 < partly["ball"]["visibility"] < 1 and partly["ball"]["area"] < seen["ball"]["area"]
    assert "ball" not in hidden and hidden["beacon_skyblue_left"]["visibility"] == 1.0
    assert hidden["beacon_skyblue_left"]["category"] == "beacon" and set(hidden) == {"beacon_skyblue_left"}


def _interrupt(folder: Path, keep: int) -> None:
    """As a killed dump leaves a folder: frames after ``keep`` gone, no coco.json."""
    lines = (folder / "frames.jsonl").read_bytes().splitlines(keepends=True)
    (folder / "frames.jsonl").write_bytes(b"".join(lines[:keep]))
    for index in range(keep, len(lines)):
        (folder / "rgb" / f"{index:06d}.png").unlink()
    (folder / "coco.json").unlink()


@pytest.mark.slow
def test_sharded_coco_lists_every_shard_and_a_resume_gives_the_same_bytes(tmp_path):
    out = tmp_path / "sharded"
    dump(out, controller=TRACKER, frames=6, workers=2, formats=FORMATS)
    dataset = json.loads((out / "coco.json").read_bytes())
    names = [f"shard_{k}/rgb/{i:06d}.png" for k in (0, 1) for i in range(3)]
    assert [i["file_name"] for i in dataset["images"]] == names
    shard_1 = json.loads((out / "shard_1" / "coco.json").read_bytes())["annotations"]
    assert [a["bbox"] for a in dataset["annotations"] if a["image_id"] > 3] == [a["bbox"] for a in shard_1]
    resumed = tmp_path / "resumed"
    shutil.copytree(out, resumed)
    _interrupt(resumed / "shard_1", keep=1)
    (resumed / "coco.json").unlink()
    assert dump(resumed, controller=TRACKER, frames=6, workers=2, formats=FORMATS, resume=True).new_frames == 2
    for path in out.rglob("*.json"):
        assert (resumed / path.relative_to(out)).read_bytes() == path.read_bytes(), path


def test_coco_without_rgb_is_refused_in_one_line(tmp_path, capsys):
    assert main(["dump", str(TRACKER), "--out", str(tmp_path / "d"), "--steps", "2", "--formats", "coco"]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and ": coco annotates the rgb files; add rgb" in error and "--formats " in error
    assert not (tmp_path / "d").exists()
