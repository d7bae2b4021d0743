"""Frame dumps (issue 6): every format written, read back and checked; resume, shards, errors."""

import argparse
import errno
import json
import math
import shutil
import subprocess
from pathlib import Path

import cv2
import numpy as np
import pytest
from rename_support import watch_renames

import openr_bridge
from aibo_sim.camera import HEAD_CAMERA_GROUPS
from aibo_sim.config import CameraConfig, WorldConfig
from aibo_sim.dump import (
    FORMATS,
    DumpError,
    add_dump_parser,
    ball_in_image,
    dump,
    geom_classes,
    load_dump,
    yuv420_bytes,
    yuv444_bytes,
)
from aibo_sim.dump import formats as dump_formats
from aibo_sim.dump.formats import mp4_boxes, mp4_faststart
from aibo_sim.field import BALL_RADIUS, SEGMENTATION_CLASSES
from aibo_sim.render import Renderer
from aibo_sim.sim import Simulation, models_dir

ROOT = Path(__file__).resolve().parents[1]
TRACKER = ROOT / "controllers" / "ball_tracker.py"
W, H = 208, 160
YUV444_BOUND = 2  # |RGB -> 8-bit limited-range YCbCr -> RGB|: quantisation to 219/224 levels, at most 2 per channel
YUV420_FLAT_BOUND = 3  # the same through OpenCV's fixed-point I420 decoder, on 2x2 blocks of one colour
CENTROID_BOUND = 1.25  # px, projected centre to orange centroid; measured <= 1.14 (a sphere images off-centre)


@pytest.fixture(scope="module")
def full_dump(tmp_path_factory):
    out = tmp_path_factory.mktemp("dump") / "full"
    # The ideal picture: the checks below find the ball by colour and use a pinhole (the ers7
    # lens and sensor in dumps are checked in test_camera).
    summary = dump(out, controller=TRACKER, frames=30, formats=FORMATS, camera=CameraConfig("ideal"))
    return out, summary


def _frames(out, name):
    return sorted(p.name for p in (out / name).iterdir())


@pytest.mark.slow
def test_every_format_holds_every_frame_at_its_size(full_dump):
    out, summary = full_dump
    assert summary.frames == summary.new_frames == 30
    frames = load_dump(out)
    assert len(frames) == 30 and [f.meta["index"] for f in frames] == list(range(30))
    sizes = {"yuv444": 3 * W * H, "yuv420": W * H * 3 // 2, "annex": 3 * W * H}
    for name, size in sizes.items():
        assert _frames(out, name) == [f"{i:06d}.yuv" for i in range(30)]
        assert {(out / name / f).stat().st_size for f in _frames(out, name)} == {size}
    band_sizes = {"H": 6 * 208 * 160, "M": 6 * 104 * 80, "L": 6 * 52 * 40, "C": 104 * 80}
    assert band_sizes["H"] == 199680
    for layer, size in band_sizes.items():
        assert {(out / "bands" / f"{i:06d}_{layer}.raw").stat().st_size for i in range(30)} == {size}
    for name in ("rgb", "openr", "luma", "depth", "seg"):
        assert len(_frames(out, name)) == 30
    assert not list(out.rglob(".tmp.*"))
    meta = json.loads((out / "meta.json").read_text())
    assert "BT.601 limited" in meta["files"]["yuv420"]["layout"] and meta["files"]["yuv420"]["bytes"] == 49920
    assert meta["segmentation_classes"] == list(SEGMENTATION_CLASSES)
    first = frames[0]
    assert first.rgb.shape == (H, W, 3) and first.luma.shape == (320, 416) and first.depth.dtype == np.float32


def test_video_has_every_frame(full_dump):
    out, _ = full_dump
    data = (out / "video.mp4").read_bytes()
    assert [box[0] for box in mp4_boxes(data, 0, len(data))] == [b"ftyp", b"free", b"moov", b"mdat"]  # faststart
    video = cv2.VideoCapture(str(out / "video.mp4"))
    assert video.isOpened()
    count = 0
    while video.read()[0]:
        count += 1
    assert count == 30 and video.get(cv2.CAP_PROP_FPS) == pytest.approx(30)
    if shutil.which("ffprobe"):
        probe = subprocess.run(
            [
                "ffprobe",
                "-v",
                "error",
                "-count_frames",
                "-select_streams",
                "v:0",
                "-show_entries",
                "stream=nb_read_frames,width,height",
                "-of",
                "json",
                str(out / "video.mp4"),
            ],
            capture_output=True,
            text=True,
            check=True,
        )
        stream = json.loads(probe.stdout)["streams"][0]
        assert (int(stream["nb_read_frames"]), stream["width"], stream["height"]) == (30, W, H)


def _bt601_limited_to_rgb(y, u, v):
    """The textbook inverse (ITU-R BT.601, limited range), independent of the writer's matrix."""
    y, u, v = (p.astype(np.float64) for p in (y, u, v))
    c, d, e = 255 / 219 * (y - 16), 255 / 224 * (u - 128), 255 / 224 * (v - 128)
    rgb = np.stack([c + 1.402 * e, c - 0.344136 * d - 0.714136 * e, c + 1.772 * d], axis=-1)
    return np.clip(np.floor(rgb + 0.5), 0, 255)


def test_yuv_files_decode_back_to_the_png(full_dump):
    out, _ = full_dump
    for frame in load_dump(out)[::7]:
        rgb = frame.rgb.astype(int)
        y444, u444, v444 = frame.yuv444
        assert np.abs(_bt601_limited_to_rgb(y444, u444, v444) - rgb).max() <= YUV444_BOUND
        y420, u420, v420 = frame.yuv420
        assert np.array_equal(y420, y444)
        block_mean = lambda p: p.astype(float).reshape(H // 2, 2, W // 2, 2).mean(axis=(1, 3))  # noqa: E731
        assert np.abs(u420 - block_mean(u444)).max() <= 1 and np.abs(v420 - block_mean(v444)).max() <= 1
        i420 = np.fromfile(frame.path("yuv420"), np.uint8).reshape(H * 3 // 2, W)
        decoded = cv2.cvtColor(i420, cv2.COLOR_YUV2RGB_I420).astype(int)
        blocks = rgb.reshape(H // 2, 2, W // 2, 2, 3)
        flat = (blocks == blocks[:, :1, :, :1]).all(axis=(1, 3, 4))
        flat = np.repeat(np.repeat(flat, 2, axis=0), 2, axis=1)
        assert flat.mean() > 0.5
        assert np.abs(decoded - rgb)[flat].max() <= YUV420_FLAT_BOUND


@pytest.mark.skipif(not shutil.which("ffmpeg"), reason="ffmpeg is not installed (.ci/run installs it)")
def test_ffmpeg_reads_the_yuv_files_as_their_layout_says(full_dump):
    """ffmpeg's own rawvideo reader and BT.601 conversion, given the pixel format and size that
    meta.json names, gives back the PNG's picture."""
    out, _ = full_dump
    frame = load_dump(out)[9]
    rgb = frame.rgb.astype(int)
    blocks = rgb.reshape(H // 2, 2, W // 2, 2, 3)
    flat = np.repeat(np.repeat((blocks == blocks[:, :1, :, :1]).all(axis=(1, 3, 4)), 2, axis=0), 2, axis=1)
    layouts = json.loads((out / "meta.json").read_text())["files"]
    for name, pixel_format, bound, where in (
        ("yuv444", "yuv444p", YUV444_BOUND, np.ones_like(flat)),
        ("yuv420", "yuv420p", YUV420_FLAT_BOUND, flat),
    ):
        assert f"{W}x{H}" in layouts[name]["layout"]
        decoded = subprocess.run(
            [
                "ffmpeg",
                "-v",
                "error",
                "-f",
                "rawvideo",
                "-pix_fmt",
                pixel_format,
                "-s",
                f"{W}x{H}",
                "-i",
                str(frame.path(name)),
                "-f",
                "rawvideo",
                "-pix_fmt",
                "rgb24",
                "-",
            ],
            capture_output=True,
            check=True,
        ).stdout
        assert len(decoded) == W * H * 3, name
        assert np.abs(np.frombuffer(decoded, np.uint8).reshape(H, W, 3) - rgb)[where].max() <= bound, name


def test_white_and_black_in_limited_range():
    for value, (y, c) in ((255, (235, 128)), (0, (16, 128))):
        image = np.full((2, 2, 3), value, np.uint8)
        assert list(yuv444_bytes(image)) == [y] * 4 + [c] * 8
        assert list(yuv420_bytes(image)) == [y] * 4 + [c, c]


def test_annex_file_matches_the_annex_port(full_dump):
    out, _ = full_dump
    frame = load_dump(out)[12]
    assert frame.annex.shape == (H, W, 3)
    rgb = frame.rgb.astype(int)
    for x, y in [(0, 0), (W - 1, H - 1), (W // 2, H // 2), (17, 101), (150, 33)]:
        r, g, b = (int(v) for v in rgb[y, x])
        luma = int(0.299 * r + 0.587 * g + 0.114 * b)  # the Annex's C expressions, scalar doubles
        expected = [luma, int(0.492 * (b - luma) + 128), int(0.5 * (r - luma) + 128)]
        assert list(frame.annex[y, x]) == expected


def test_openr_message_bands_and_luma_are_the_encoding_of_the_png(full_dump):
    out, _ = full_dump
    for frame in load_dump(out)[::10]:
        message = frame.message
        expected = openr_bridge.encode_frame(
            frame.rgb, frame_number=frame.meta["frame_number"], field_counter=frame.meta["field_counter"]
        )
        assert bytes(message) == bytes(expected)
        assert message.GetInfo(openr_bridge.ofbkimageLAYER_H).frameNumber == frame.meta["frame_number"]
        for layer in ("H", "M", "L", "C"):
            index = getattr(openr_bridge, f"ofbkimageLAYER_{layer}")
            assert frame.path("bands", layer).read_bytes() == message.GetData(index).tobytes()
            bands = frame.bands(layer)
            assert sorted(bands) == (
                [openr_bridge.ofbkimageBAND_CDT]
                if layer == "C"
                else sorted(b for b in range(7) if b != openr_bridge.ofbkimageBAND_CDT)
            )
            for band, array in bands.items():
                assert np.array_equal(array, message.band(index, band))
        assert np.array_equal(frame.luma, openr_bridge.reconstruct_luma(message))
    assert frame.bands(openr_bridge.ofbkimageLAYER_M).keys() == frame.bands("M").keys()
    for layer in ("X", 4):
        with pytest.raises(ValueError, match=rf"^bands\({layer!r}\): the layers are H, M, L, C or their numbers 0-3$"):
            frame.bands(layer)


def test_segmentation_depth_and_ball_pixel_agree_with_the_picture(full_dump):
    out, _ = full_dump
    frames = load_dump(out)
    ball_class, field_class = SEGMENTATION_CLASSES.index("ball"), SEGMENTATION_CLASSES.index("field")
    intrinsics = frames.meta["camera"]
    checked = 0
    for frame in frames:
        seg, ball = frame.seg, frame.meta["ball"]
        assert (seg == field_class).mean() > 0.3
        assert ball["visible"] and ball["pixel"] is not None  # the tracker keeps the ball in view
        u, v = ball["pixel"]
        assert seg[round(v), round(u)] == ball_class
        rgb = frame.rgb.astype(int)
        orange = (rgb[..., 0] > 100) & (rgb[..., 1] < 0.75 * rgb[..., 0]) & (rgb[..., 2] < 0.3 * rgb[..., 0])
        ys, xs = np.nonzero(orange)
        inside = xs.min() > 0 and ys.min() > 0 and xs.max() < W - 1 and ys.max() < H - 1
        if inside:
            assert math.dist((xs.mean(), ys.mean()), (u, v)) <= CENTROID_BOUND
            assert (orange & (seg == ball_class)).sum() >= 0.9 * orange.sum()
            checked += 1
        # Depth along the optical axis of the sphere's nearest point on the ray through the centre.
        cosine = 1 / math.hypot(1, (u - intrinsics["cx"]) / intrinsics["fx"], (v - intrinsics["cy"]) / intrinsics["fy"])
        expected = (ball["distance_m"] - BALL_RADIUS) * cosine
        assert frame.depth[round(v), round(u)] == pytest.approx(expected, abs=0.005)
    assert checked >= 20


@pytest.mark.parametrize("profile", ["ideal", "ers7"])
def test_a_frames_record_is_of_the_instant_its_frame_was_exposed(profile):
    """time_s, joints and the ball of a frames.jsonl record are those of the frame's exposure, as
    its camera pose, picture and labels are, though the record is written one or more joint
    frames later (a dump's frame 0 said 8 ms and the joints of then)."""
    sim = Simulation(camera=CameraConfig(profile))
    try:
        sim.servos.set_target(slice(None), sim.servos.high)  # every joint moves through the frames
        exposed = {0: (0.0, sim.joint_positions())}
        moved = 0
        for _ in range(20):
            sim.step_frame()
            exposed.setdefault(sim.camera_frame_index(), (sim.time_ms / 1000, sim.joint_positions()))
            record, frame = dump_formats.frame_metadata(sim, 0), sim.camera.frame()
            time_s, joints = exposed[frame.index]
            assert record["time_s"] == time_s and record["frame_number"] * 0.008 == pytest.approx(time_s)
            assert list(record["joints"].values()) == joints.tolist()
            assert record["camera"]["position"] == sim.camera.exposure_data().cam_xpos[sim.camera.camera_id].tolist()
            moved += not np.array_equal(joints, sim.joint_positions())
        assert moved >= 10  # most records are written after their exposure
    finally:
        sim.close()


@pytest.mark.parametrize("profile", ["ideal", "ers7"])
def test_ball_behind_a_beacon_is_not_visible(profile):
    sim = Simulation(camera=CameraConfig(profile))
    heading = math.atan2(1.95, 1.35)  # towards the sky-blue left beacon
    sim.place_robot(0, 0, heading)
    try:
        for distance, visible in ((2.2, True), (2.48, False)):
            sim.place_ball(distance * math.cos(heading), distance * math.sin(heading))
            ball = ball_in_image(sim)
            u, v = ball["pixel"]
            assert 0 <= u < W and 0 <= v < H and ball["visible"] == visible
            seg = geom_classes(sim.model)[sim.camera.segmentation()]
            assert (seg == SEGMENTATION_CLASSES.index("ball")).any() == visible
        sim.place_ball(-1.0, 0.0)
        assert ball_in_image(sim)["pixel"] is None
    finally:
        sim.close()


def test_segmentation_restores_the_scene_flags():
    sim = Simulation()
    renderer = Renderer(sim.model, W, H, groups=HEAD_CAMERA_GROUPS)
    try:
        before = renderer.render(sim.data, "camera")
        ids = renderer.render_segmentation(sim.data, "camera")
        assert ids.dtype == np.int32 and ids.min() >= -1 and sim.model.geom("field_carpet").id in ids
        assert np.array_equal(renderer.render(sim.data, "camera"), before)
    finally:
        renderer.close()
        sim.close()


def test_resume_after_an_interruption_is_byte_identical(full_dump, tmp_path):
    out, _ = full_dump
    resumed = tmp_path / "resumed"
    shutil.copytree(out, resumed)
    for index in range(26, 30):
        for path in resumed.rglob(f"{index:06d}*"):
            path.unlink()
    lines = (resumed / "frames.jsonl").read_bytes().splitlines(keepends=True)
    (resumed / "frames.jsonl").write_bytes(b"".join(lines[:25]) + lines[25][:40])  # frame 25 half-written
    (resumed / "video.mp4").unlink()
    (resumed / "rgb" / ".tmp.000026.png").write_bytes(b"partial")
    assert len(load_dump(resumed)) == 25
    summary = dump(resumed, controller=TRACKER, frames=30, formats=FORMATS, resume=True, camera=CameraConfig("ideal"))
    assert (summary.frames, summary.new_frames) == (30, 5)
    assert sorted(p.relative_to(resumed) for p in resumed.rglob("*")) == sorted(
        p.relative_to(out) for p in out.rglob("*")
    )
    for path in out.rglob("*"):
        if path.is_file():  # the video too: rebuilt from every frame, the encoder is deterministic
            assert (resumed / path.relative_to(out)).read_bytes() == path.read_bytes(), path


def test_an_existing_dump_is_kept_unless_resumed_with_the_same_parameters(full_dump):
    out, _ = full_dump
    with pytest.raises(DumpError, match="already holds a dump: pass --resume"):
        dump(out, controller=TRACKER, frames=30, formats=FORMATS, camera=CameraConfig("ideal"))
    with pytest.raises(DumpError, match=r"other parameters \(seed\)"):
        dump(
            out,
            controller=TRACKER,
            frames=30,
            formats=FORMATS,
            resume=True,
            world=WorldConfig(seed=1),
            camera=CameraConfig("ideal"),
        )


def test_unwritable_destination_is_one_clear_error(tmp_path):
    not_a_folder = tmp_path / "file"
    not_a_folder.write_text("")
    with pytest.raises(DumpError, match=f"cannot create the dump folder {not_a_folder / 'out'}: Not a directory"):
        dump(not_a_folder / "out", controller=TRACKER, frames=3)


def test_full_disk_leaves_only_complete_frames_and_resumes(tmp_path, monkeypatch):
    out = tmp_path / "out"
    full = OSError(errno.ENOSPC, "No space left on device")
    watch_renames(monkeypatch, lambda source, target: full if target.name == "000003.yuv" else None)
    with pytest.raises(
        DumpError,
        match=f"cannot write {out / 'yuv420' / '000003.yuv'}: No space left on device; "
        "free some space, then continue the dump with --resume$",
    ):
        dump(out, controller=TRACKER, frames=6)
    assert not list(out.rglob(".tmp.*")) and not (out / "video.mp4").exists()
    assert len(load_dump(out)) == 3 and (out / "rgb" / "000003.png").exists()  # written, but not complete
    monkeypatch.undo()
    assert dump(out, controller=TRACKER, frames=6, resume=True).new_frames == 3
    assert len(load_dump(out)) == 6


def test_a_shards_drawn_ball_lies_ahead_of_the_pose_and_is_checked_before_anything_is_written(tmp_path, capsys):
    """The balls were drawn ahead of the default start whatever --pose, and checked only by the
    shard: one on the robot failed the dump after its folders were made, at every --resume."""
    from aibo_sim.cli import main
    from aibo_sim.dump.shards import SHARD_BALL_X, SHARD_BALL_Y, shard_balls

    pose = (0.880639462230231, 0.3904636963259353, 90.0)
    balls = shard_balls(WorldConfig(pose=pose), 2)
    for bx, by in balls:  # ahead of the robot facing +y: x within SHARD_BALL_Y of it, y SHARD_BALL_X beyond
        assert SHARD_BALL_Y[0] <= bx - pose[0] <= SHARD_BALL_Y[1] and SHARD_BALL_X[0] <= by - pose[1] <= SHARD_BALL_X[1]
    assert shard_balls(WorldConfig(), 2) == [  # without a pose: the draws of before, unchanged
        [float(r.uniform(*SHARD_BALL_X)), float(r.uniform(*SHARD_BALL_Y))]
        for r in (np.random.default_rng(0), np.random.default_rng(1))
    ]
    out = tmp_path / "out"
    with pytest.raises(ValueError, match=r"^shard_0: none of 20 balls drawn from its seed 0 ahead of the robot "):
        dump(out, controller=TRACKER, frames=2, workers=2, world=WorldConfig(pose=(2.75, 0.0, 0.0)))
    command = ["dump", str(TRACKER), "--steps", "2", "--workers", "2", "--pose", "2.75", "0", "0", "--out", str(out)]
    assert main(command) == 2  # one line (a ParameterError without its parameter was a traceback, exit 1)
    assert capsys.readouterr().err == (
        "aibo-sim: error: shard_0: none of 20 balls drawn from its seed 0 ahead of the robot can be placed in the "
        "scene: give --ball\n"
    )
    assert not out.exists()


def test_a_dump_without_frames_has_no_video(tmp_path):
    """OpenCV's writer left a container without a stream, which players (and OpenCV) refuse."""
    quits = tmp_path / "quits.py"
    quits.write_text("from aibo_sim.controller import *\n\nrobot_get_time()\n")
    out = tmp_path / "out"
    assert dump(out, controller=quits, frames=30, formats=("rgb", "mp4")).frames == 0
    assert not (out / "video.mp4").exists() and not list(out.glob(".tmp.*")) and (out / "meta.json").is_file()
    assert load_dump(out).videos == []


@pytest.mark.slow
def test_workers_write_shards_with_their_own_seeds(tmp_path):
    out = tmp_path / "sharded"
    summary = dump(out, controller=TRACKER, frames=5, workers=2, formats=("rgb", "openr"))
    assert summary.frames == 5
    shards = [json.loads((out / f"shard_{k}" / "meta.json").read_text())["parameters"] for k in range(2)]
    assert [s["seed"] for s in shards] == [0, 1] and [s["frames"] for s in shards] == [3, 2]
    assert shards[0]["ball"] != shards[1]["ball"]
    frames = load_dump(out)
    assert len(frames) == 5 and [f.meta["index"] for f in frames] == [0, 1, 2, 0, 1]
    assert [f.folder.name for f in frames] == ["shard_0"] * 3 + ["shard_1"] * 2
    assert not np.array_equal(frames[0].rgb, frames[3].rgb)  # the balls lie elsewhere
    lens = json.loads((out / "shard_1" / "meta.json").read_text())["camera"]
    assert frames[4].camera == lens and lens["width"] == 208 and lens["fx"] > 0  # the top meta.json has none


def test_command_line_env_dump(tmp_path):
    gymnasium = pytest.importorskip("gymnasium")
    try:
        import aibo_sim.envs  # noqa: F401

        gymnasium.make("aibo_sim/HeadTrackBall-v0").close()
    except Exception as exc:  # the environments are another issue's work
        pytest.skip(f"HeadTrackBall-v0 is not available: {exc}")
    parser = argparse.ArgumentParser()
    add_dump_parser(parser.add_subparsers())
    args = parser.parse_args(
        [
            "dump",
            "--env",
            "aibo_sim/HeadTrackBall-v0",
            "--policy",
            "random",
            "--steps",
            "10",
            "--out",
            str(tmp_path / "env"),
            "--formats",
            "rgb,openr,seg",
        ]
    )
    assert args.handler(args) == 0
    frames = load_dump(tmp_path / "env")
    assert len(frames) == 11  # the reset frame and one per step
    assert frames[0].meta["action"] is None and len(frames[1].meta["action"]) == 3
    assert [f.meta["field_counter"] for f in frames] == list(range(11))
    assert frames[10].message.GetInfo(0).frameNumber == frames[10].meta["frame_number"]


def test_a_scene_without_a_ball_dumps_every_format_with_no_ball_record(tmp_path):
    scene = tmp_path / "no_ball.xml"
    scene.write_text(f"""<mujoco>
  <include file="{models_dir() / "ers7.xml"}"/>
  <worldbody><geom name="floor" type="plane" size="2 2 0.1" rgba="0.3 0.5 0.3 1"/></worldbody>
</mujoco>""")
    summary = dump(tmp_path / "out", controller=TRACKER, frames=3, formats=FORMATS, world=WorldConfig(scene=scene))
    assert summary.frames == 3
    assert [frame.meta["ball"] for frame in load_dump(tmp_path / "out")] == [None] * 3


def test_faststart_moves_the_index_ahead_and_every_frame_decodes_the_same(tmp_path):
    """OpenCV's writer puts moov after mdat; moved ahead, with its chunk offsets shifted by its
    size, the file decodes (through FFmpeg's demuxer in OpenCV) to the same frames, bit for bit."""
    rng = np.random.default_rng(3)
    path = tmp_path / "written.mp4"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), 30, (208, 160))
    for k in range(40):  # noise and flat frames: chunks of very different sizes
        writer.write(
            rng.integers(0, 256, (160, 208, 3), np.uint8) if k % 2 else np.full((160, 208, 3), 5 * k, np.uint8)
        )
    writer.release()
    moved = tmp_path / "moved.mp4"
    shutil.copy(path, moved)
    mp4_faststart(moved)
    before, after = path.read_bytes(), moved.read_bytes()
    kinds = [[box[0] for box in mp4_boxes(data, 0, len(data))] for data in (before, after)]
    assert kinds == [[b"ftyp", b"free", b"mdat", b"moov"], [b"ftyp", b"free", b"moov", b"mdat"]]
    assert len(after) == len(before) and after != before

    def frames(file):
        video, decoded = cv2.VideoCapture(str(file)), []
        while (read := video.read())[0]:
            decoded.append(read[1])
        return decoded

    original, faststarted = frames(path), frames(moved)
    assert len(original) == len(faststarted) == 40
    assert all(np.array_equal(a, b) for a, b in zip(original, faststarted))
    mp4_faststart(moved)  # already ahead: left as it is
    assert moved.read_bytes() == after


def _box(kind: bytes, payload: bytes, large: bool = False) -> bytes:
    """An MP4 box: 32-bit size, or (``large``) size 1 and a 64-bit size after the type."""
    if large:
        return (1).to_bytes(4, "big") + kind + (16 + len(payload)).to_bytes(8, "big") + payload
    return (8 + len(payload)).to_bytes(4, "big") + kind + payload


def _chunk_offsets(data: bytes) -> list[int]:
    found = []

    def walk(start, end):
        for kind, box_start, box_end, header in mp4_boxes(data, start, end):
            if kind in (b"moov", b"trak", b"mdia", b"minf", b"stbl"):
                walk(box_start + header, box_end)
            elif kind in (b"stco", b"co64"):
                width, at = (4 if kind == b"stco" else 8), box_start + header + 8
                count = int.from_bytes(data[at - 4 : at], "big")
                found.extend(int.from_bytes(data[at + k * width : at + (k + 1) * width], "big") for k in range(count))

    walk(0, len(data))
    return found


@pytest.mark.parametrize(
    "table, large_moov, large_stbl",
    [(b"stco", False, False), (b"co64", False, False), (b"stco", True, False), (b"stco", False, True)],
)
def test_faststart_shifts_each_kind_of_chunk_table_behind_any_box_header(
    tmp_path, monkeypatch, table, large_moov, large_stbl
):
    monkeypatch.setattr(dump_formats, "_MOVE_BLOCK", 7)  # many overlapping blocks
    ftyp, frames = _box(b"ftyp", b"isom\0\0\0\0isom"), bytes(range(200))
    offsets = [len(ftyp) + 8, len(ftyp) + 8 + 150]
    width = 4 if table == b"stco" else 8
    chunks = _box(
        table, bytes(4) + len(offsets).to_bytes(4, "big") + b"".join(o.to_bytes(width, "big") for o in offsets)
    )
    moov = _box(b"moov", _box(b"trak", _box(b"mdia", _box(b"minf", _box(b"stbl", chunks, large_stbl)))), large_moov)
    path = tmp_path / "synthetic.mp4"
    before = ftyp + _box(b"mdat", frames) + moov
    path.write_bytes(before)
    assert mp4_faststart(path)
    after = path.read_bytes()
    assert [box[0] for box in mp4_boxes(after, 0, len(after))] == [b"ftyp", b"moov", b"mdat"] and len(after) == len(
        before
    )
    moved = _chunk_offsets(after)
    assert moved == [o + len(moov) for o in offsets]
    assert all(after[new : new + 20] == before[old : old + 20] for new, old in zip(moved, offsets))


def test_faststart_leaves_a_file_it_cannot_move_as_it_was(tmp_path):
    ftyp = _box(b"ftyp", b"isom\0\0\0\0isom")
    chunks = _box(b"stco", bytes(4) + (1).to_bytes(4, "big") + (len(ftyp) + 8).to_bytes(4, "big"))
    moov = _box(b"moov", _box(b"trak", _box(b"mdia", _box(b"minf", _box(b"stbl", chunks)))))
    for name, data in {
        "index first": ftyp + moov + _box(b"mdat", bytes(64)),
        "truncated": (ftyp + _box(b"mdat", bytes(64)) + moov)[:-3],
    }.items():
        path = tmp_path / f"{name}.mp4"
        path.write_bytes(data)
        assert not mp4_faststart(path), name
        assert path.read_bytes() == data, name
    # A chunk at 0xFFFFFFF0 of a ~4 GiB file (sparse: no disk used) would pass 32 bits once moved.
    mdat_size = 0xFFFFFFF8 - len(ftyp)
    chunks = _box(b"stco", bytes(4) + (1).to_bytes(4, "big") + (0xFFFFFFF0).to_bytes(4, "big"))
    moov = _box(b"moov", _box(b"trak", _box(b"mdia", _box(b"minf", _box(b"stbl", chunks)))))
    path = tmp_path / "large.mp4"
    with open(path, "wb") as file:
        file.write(ftyp + mdat_size.to_bytes(4, "big") + b"mdat")
        file.seek(len(ftyp) + mdat_size)
        file.write(moov)
    assert not mp4_faststart(path)
    with open(path, "rb") as file:
        file.seek(len(ftyp) + mdat_size)
        assert file.read() == moov
