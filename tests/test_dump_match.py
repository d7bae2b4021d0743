"""A match's dump (issue 41): ``aibo-sim dump CONTROLLER --robots FILE`` (or ``--robot``) writes one
dump per robot (``robot1/``, ``robot2/``: the dump's shards), each robot's spec and the match in its
meta.json, its robots images' instance ids in the robots' order, one coco.json with the teams'
categories and no robot detecting itself; the same seed gives the same files; ``--resume``; the
options a match does not take refused with one line."""

import errno
import json
from pathlib import Path

import numpy as np
import pytest
from pycocotools.coco import COCO
from rename_support import watch_renames

from aibo_sim.cli import main
from aibo_sim.config import CameraConfig, WorldConfig
from aibo_sim.dump import DumpError, dump, load_dump
from aibo_sim.dump.formats import instance_teams
from aibo_sim.dump.running import PARAMETER_ORDER, recorded_parameters
from aibo_sim.field import COCO_CATEGORIES, LABEL_TEAMS, SEGMENTATION_CLASSES
from aibo_sim.team import RobotSpec

ROOT = Path(__file__).resolve().parents[1]
TRACKER = ROOT / "controllers" / "ball_tracker.py"
# Face to face across the centre spot: each sees the other whole.
ROBOTS_TOML = """\
[[robot]]
team = "red"
number = 1
pose = [0.0, 0.0, 0.0]

[[robot]]
team = "blue"
number = 1
pose = [1.0, 0.0, 180.0]
"""
SPECS = (RobotSpec("red", 1, (0.0, 0.0, 0.0)), RobotSpec("blue", 1, (1.0, 0.0, 180.0)))
FRAMES = 9  # 0.3 s at 30 fps
FORMATS = ("rgb", "seg", "robots", "coco")
OPTIONS = ["--camera-profile", "ideal", "--duration", "0.3", "--ball", "0.5", "0.3", "--seed", "3"]
ROBOT = SEGMENTATION_CLASSES.index("robot")


def rle_mask(rle: dict) -> np.ndarray:
    h, w = rle["size"]
    return np.repeat(np.arange(len(rle["counts"])) % 2 == 1, rle["counts"]).reshape((h, w), order="F")


def files(folder: Path) -> dict:
    return {p.relative_to(folder): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def match_dump(tmp_path_factory):
    folder = tmp_path_factory.mktemp("match")
    (folder / "robots.toml").write_text(ROBOTS_TOML)
    out = folder / "dump"
    arguments = [str(TRACKER), "--robots", str(folder / "robots.toml"), "--out", str(out)]
    assert main(["dump", *arguments, *OPTIONS, "--formats", ",".join(FORMATS)]) == 0
    return out


def test_a_match_dump_is_one_dump_per_robot_read_as_shards(match_dump):
    out = match_dump
    meta = json.loads((out / "meta.json").read_text())
    assert meta["shards"] == ["robot1", "robot2"]
    assert [r["team"] for r in meta["parameters"]["robots"]] == ["red", "blue"]
    assert {p.name for p in out.iterdir()} - {".dump.lock"} == {
        "meta.json",
        "coco.json",
        "controller_files",
        "robot1",
        "robot2",
    }
    frames = load_dump(out)
    assert len(frames) == 2 * FRAMES
    assert [(f.folder.name, f.meta["index"]) for f in frames] == [
        (f"robot{k}", i) for k in (1, 2) for i in range(FRAMES)
    ]
    for k in (1, 2):
        robot = load_dump(out / f"robot{k}")  # each robot's folder is a dump of its own
        assert len(robot) == FRAMES and {"rgb", "seg", "robots", "coco"} <= set(robot.meta["files"])
        assert sorted(p.name for p in (out / f"robot{k}" / "rgb").iterdir()) == [f"{i:06d}.png" for i in range(FRAMES)]
        assert set(robot[0].meta["joints"]) and robot[0].meta["ball"] is not None
        assert robot[0].rgb.shape == (160, 208, 3)
    assert not list(out.rglob(".tmp.*"))


def test_each_robots_meta_names_its_spec_and_the_match(match_dump):
    for k, spec in enumerate(SPECS, start=1):
        meta = json.loads((match_dump / f"robot{k}" / "meta.json").read_text())
        parameters = meta["parameters"]
        assert parameters["robot"] == {
            "team": spec.team,
            "number": spec.number,
            "pose": list(spec.pose),
            "controller": str(TRACKER),
        }
        assert parameters["controller"] == str(TRACKER) and parameters["pose"] == list(spec.pose)
        assert parameters["frames"] == FRAMES and parameters["seed"] == 3 and parameters["ball"] == [0.5, 0.3]
        assert meta["robots"]["observer"] == k
        assert [(r["id"], r["team"], r["number"], r["name"]) for r in meta["robots"]["instances"]] == [
            (1, "red", 1, "red 1"),
            (2, "blue", 1, "blue 1"),
        ]
        assert meta["camera"]["profile"] == "ideal"
        # One order for every dump's parameters: a match robot's keys in a single robot's order.
        assert list(parameters) == [key for key in PARAMETER_ORDER if key in parameters]
        assert "robots" not in parameters and list(parameters)[:2] == ["controller", "env"]
    with pytest.raises(KeyError, match="colour"):
        recorded_parameters({"frames": 1}, {"colour": "red"})


def test_robots_images_hold_the_other_robots_instance_id_in_the_specs_order(match_dump):
    for k, other in ((1, 2), (2, 1)):
        robot = load_dump(match_dump / f"robot{k}")
        teams = instance_teams(robot.meta["robots"])
        for frame in robot:
            instances, seg = frame.robots, frame.seg
            assert instances.dtype == np.uint8 and instances.shape == seg.shape
            assert set(np.unique(instances).tolist()) == {0, other}  # the other robot, none of itself here
            assert ((instances > 0) == (seg == ROBOT)).all()
            assert (teams[instances[instances > 0]] == LABEL_TEAMS.index(SPECS[other - 1].team)).all()
            seen = [d for d in frame.meta["objects"] if d["category"] == "robot"]
            assert [d["object"] for d in seen] == [SPECS[other - 1].name]  # never itself
            assert (rle_mask(seen[0]["segmentation"]) == (instances == other)).all()


def test_coco_json_lists_every_robots_frames_with_team_categories(match_dump):
    coco = COCO(str(match_dump / "coco.json"))
    names = {c["name"] for c in coco.loadCats(coco.getCatIds())}
    assert {"robot_red", "robot_blue"} <= names
    images = coco.loadImgs(coco.getImgIds())
    assert [i["file_name"] for i in images] == [f"robot{k}/rgb/{i:06d}.png" for k in (1, 2) for i in range(FRAMES)]
    for image in images:
        observer = SPECS[int(image["file_name"][5]) - 1]
        annotations = coco.loadAnns(coco.getAnnIds(imgIds=image["id"]))
        robots = [a for a in annotations if "team" in a]
        assert robots and all(a["object"] != observer.name for a in robots)
        for a in robots:
            assert COCO_CATEGORIES[a["category_id"]] == f"robot_{a['team']}"
            assert a["team"] != observer.team
    for k in (1, 2):  # each robot's own coco.json holds its frames
        own = json.loads((match_dump / f"robot{k}" / "coco.json").read_text())
        assert len(own["images"]) == FRAMES


def test_the_same_seed_gives_the_same_files_and_resume_completes_a_robots_dump(match_dump, tmp_path):
    out = tmp_path / "again"
    summary = dump(
        out,
        robots=SPECS,
        controller=TRACKER,
        frames=FRAMES,
        formats=FORMATS,
        world=WorldConfig(seed=3, ball=(0.5, 0.3)),
        camera=CameraConfig("ideal"),
    )
    assert (summary.frames, summary.new_frames) == (2 * FRAMES, 2 * FRAMES)
    before, again = files(match_dump), files(out)
    assert again.keys() == before.keys()
    for path in before:  # the robots' rgb files among them: the match is deterministic
        if path.name != ".dump.lock" and path.parent.name != "controller_files":
            assert again[path] == before[path], path
    # robot 2's last frames lost: --resume runs the match again and writes only them
    robot2 = out / "robot2"
    for index in range(6, FRAMES):
        for path in robot2.rglob(f"{index:06d}.*"):
            path.unlink()
    lines = (robot2 / "frames.jsonl").read_bytes().splitlines(keepends=True)
    (robot2 / "frames.jsonl").write_bytes(b"".join(lines[:6]))
    assert len(load_dump(out)) == 2 * FRAMES - 3
    arguments = ["dump", str(TRACKER), "--robots", str(match_dump.parent / "robots.toml"), "--out", str(out)]
    assert main([*arguments, *OPTIONS, "--formats", ",".join(FORMATS), "--resume"]) == 0
    resumed = files(out)
    for path in before:
        if path.name != ".dump.lock" and path.parent.name != "controller_files":
            assert resumed[path] == before[path], path
    with pytest.raises(DumpError, match=r"other parameters \(seed\)"):
        dump(
            out,
            robots=SPECS,
            controller=TRACKER,
            frames=FRAMES,
            formats=FORMATS,
            resume=True,
            world=WorldConfig(seed=4, ball=(0.5, 0.3)),
            camera=CameraConfig("ideal"),
        )


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        (["--robot", "green:1"], "--robot green:1: unknown team 'green'"),
        (["--robot", "red:1", "--robot", "red:1"], "red 1"),
        (["--robot", "red:1:0,0,0", "--robot", "blue:1:0.21,0,180"], "starts inside"),
        (["--robot", "red:1", "--robots", "robots.toml"], "--robots and --robot"),
        (["--robot", "red:1", "--env", "aibo_sim/HeadTrackBall-v0"], "--env"),
        (["--robot", "red:1", "--workers", "2"], "--workers 2 applies to a dump of one robot"),
        (["--robot", "red:1", "--pose", "0", "0", "0"], "--pose applies to a dump of one robot"),
        (["--robot", "red:1", "--backend", "openr"], "--backend applies to a dump of one robot"),
        (["--robot", "red:1", "--formats", "seg,coco"], "coco annotates the rgb files"),
        (["--robot", "red:1:0,0,0", "--ball", "0.1", "0.06"], "--ball 0.1 0.06: the ball would overlap red 1"),
        (["--robot", "red:1:2.95,0,0"], "--robot red:1:2.95,0,0: red 1 starts inside wall_skyblue"),
    ],
)
def test_a_bad_match_dump_is_refused_with_one_line(tmp_path, capsys, monkeypatch, arguments, message):
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "out"
    controller = [] if "--env" in arguments else [str(TRACKER)]
    assert main(["dump", *controller, *arguments, "--out", str(out), "--duration", "0.1"]) == 2
    error = capsys.readouterr().err
    assert error.startswith("aibo-sim: error: ") and error.count("\n") == 1 and message in error, error
    assert not out.exists()


def test_a_robot_without_controller_is_refused(tmp_path, capsys):
    toml = tmp_path / "robots.toml"
    toml.write_text('[[robot]]\nteam = "red"\nnumber = 2\n')
    assert main(["dump", "--robots", str(toml), "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert "red 2 has no controller" in error and error.count("\n") == 1
    toml.write_text('[[robot]]\nteam = "red"\nnumber = 5\n')
    assert main(["dump", str(TRACKER), "--robots", str(toml), "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert f"{toml}:1" in error and error.count("\n") == 1
    assert not (tmp_path / "out").exists()


def test_a_lone_robots_dump_may_hold_robots_images_and_its_meta_stays_as_it_was(tmp_path):
    out = tmp_path / "lone"
    dump(out, controller=TRACKER, frames=2, formats=("rgb", "seg", "robots"), camera=CameraConfig("ideal"))
    meta = json.loads((out / "meta.json").read_text())
    assert "robots" not in meta and "robot" not in meta["parameters"]
    for frame in load_dump(out):
        assert set(np.unique(frame.robots).tolist()) <= {0, 1}
        assert ((frame.robots == 1) == (frame.seg == ROBOT)).all()


def test_a_write_that_fails_stops_every_robot_and_is_the_error(tmp_path, monkeypatch):
    out = tmp_path / "full"
    full = OSError(errno.ENOSPC, "No space left on device")
    watch_renames(
        monkeypatch,
        lambda source, target: full if (target.parent.parent.name, target.name) == ("robot2", "000003.png") else None,
    )
    with pytest.raises(DumpError, match=f"cannot write {out / 'robot2' / 'rgb' / '000003.png'}: No space left"):
        dump(out, robots=SPECS, controller=TRACKER, frames=30, formats=("rgb",), camera=CameraConfig("ideal"))
    assert not list(out.rglob(".tmp.*"))
    assert len(load_dump(out / "robot2")) == 3 and len(load_dump(out / "robot1")) < 30  # robot 1 stopped too


def test_a_match_envs_dump_names_every_robot_for_its_robot_images(tmp_path):
    out = tmp_path / "env"
    assert main(["dump", "--env", "aibo_sim/MatchVsScripted-v0", "--steps", "3", "--formats", "robots",
                 "--out", str(out)]) == 0  # fmt: skip
    dump = load_dump(out)
    teams = instance_teams(dump.meta["robots"])
    observer = dump.meta["robots"]["observer"]
    assert len(dump.meta["robots"]["instances"]) == 8 and teams[observer] == LABEL_TEAMS.index("red")
    seen = set()
    for frame in dump:
        seen |= set(np.unique(frame.robots).tolist()) - {0}
    assert seen and observer not in seen and all(teams[i] in (1, 2) for i in seen)  # every id has its team


def test_a_match_dump_resumed_as_a_one_robot_dump_names_what_differs(tmp_path, capsys):
    out = tmp_path / "dump"
    common = [str(TRACKER), "--out", str(out), "--steps", "2", "--formats", "rgb", "--camera-profile", "ideal"]
    assert main(["dump", *common, "--robot", "red:1", "--robot", "blue:1"]) == 0
    capsys.readouterr()
    assert main(["dump", *common, "--resume"]) == 2
    err = capsys.readouterr().err  # not "the controller file changed": a match's meta records no one hash
    assert "cannot resume, the dump was made with other parameters (" in err and "robots" in err, err
