"""The Webots-era controller API, sampling rules, MTN playback through it, both backends (issue 4)."""

import os
import re
import sys
import threading

import cv2
import numpy as np
import pytest

from aibo_sim import controller as api
from aibo_sim import ers7
from aibo_sim.mtn import Motion, read_mtn, write_mtn
from aibo_sim.robot import DeviceError, Robot, SimulationEnd
from aibo_sim.runner import motion_dirs
from aibo_sim.sim import Simulation, models_dir

CAMERA = "PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1"
HEAD_PAN = "PRM:/r1/c1/c2-Joint2:12"
LF_J1 = "PRM:/r2/c1-Joint2:21"


@pytest.fixture
def robot():
    robot = Robot(Simulation(), backend="sim")
    api.install(robot)
    yield robot
    api.install(None)
    robot.sim.close()


def test_mtn_get_error_is_each_robots_own_and_empty_before_any(robot):
    """Webots' is "" before any error (never NULL: a C controller printing it crashed); a
    controller's is its own (one module-wide text before: a match's robots, or an earlier run's)."""
    assert api.mtn_get_error() == ""
    assert api.mtn_new("missing.mtn") is None and api.mtn_get_error() == "File not found: missing.mtn"
    second = Robot(Simulation(), backend="sim")
    api.install(second)
    try:
        assert api.mtn_get_error() == ""
    finally:
        api.install(robot)
        second.sim.close()
    assert api.mtn_get_error() == "File not found: missing.mtn"


def test_unknown_device_lists_the_nearest_names(robot):
    with pytest.raises(DeviceError, match=r"nearest: PRM:/r2/c1-Joint2:21"):
        api.robot_get_device("PRM:/r2/c1-Joint2:2l")
    assert api.robot_get_device(LF_J1) == api.robot_get_device(LF_J1) > 0
    for nothing_like_a_locator in ("", None, "head"):  # no name near: what names look like
        with pytest.raises(DeviceError, match=r"; devices are OPEN-R locators, such as PRM:/r1/c1-Joint2:11$"):
            api.robot_get_device(nothing_like_a_locator)


def test_tags_are_checked(robot):
    pan = api.robot_get_device(HEAD_PAN)
    with pytest.raises(DeviceError, match="invalid device tag 99"):
        api.servo_set_position(99, 0.1)
    with pytest.raises(DeviceError, match="is a servo, not a camera"):
        api.camera_enable(pan, 32)


def test_reading_before_enable_or_first_sample_is_an_error(robot):
    pan = api.robot_get_device(HEAD_PAN)
    with pytest.raises(DeviceError, match="not enabled \\(call servo_enable_position first\\)"):
        api.servo_get_position(pan)
    with pytest.raises(DeviceError, match=r"PRM:/r1/c1/c2-Joint2:12: position must be a finite number"):
        api.servo_set_position(pan, float("nan"))
    api.servo_enable_position(pan, 32)
    with pytest.raises(DeviceError, match="no sample yet"):
        api.servo_get_position(pan)
    api.robot_step(32)
    assert api.servo_get_position(pan) == pytest.approx(0.0, abs=0.02)
    api.servo_disable_position(pan)
    with pytest.raises(DeviceError, match="not enabled"):
        api.servo_get_position(pan)


def test_motor_force_feedback_is_the_actuators_torque_sampled_on_its_own_period(robot):
    pan, knee = api.robot_get_device(HEAD_PAN), api.robot_get_device("PRM:/r2/c1/c2/c3-Joint2:23")
    with pytest.raises(DeviceError, match=r"^PRM:/r1/c1/c2-Joint2:12: motor force feedback is not enabled "):
        api.servo_get_motor_force_feedback(pan)
    api.servo_enable_motor_force_feedback(knee, 64)
    api.servo_enable_position(knee, 32)
    api.servo_set_position(pan, 1.0)
    api.robot_step(64)
    actuator = robot.sim.servos.ctrl.start + ers7.JOINT_INDEX["lf_j3"]
    torque = robot.sim.data.actuator_force[actuator]
    assert api.servo_get_motor_force_feedback(knee) == torque != 0  # the knee holds the body up
    api.robot_step(32)  # between samples: the position is new, the torque not
    assert api.servo_get_motor_force_feedback(knee) == torque != robot.sim.data.actuator_force[actuator]
    api.servo_disable_motor_force_feedback(knee)
    assert api.servo_get_position(knee) != 0  # the position's sampling goes on
    with pytest.raises(DeviceError, match="call servo_enable_motor_force_feedback first"):
        api.servo_get_motor_force_feedback(knee)
    with pytest.raises(DeviceError, match="is a camera, not a servo"):
        api.servo_enable_motor_force_feedback(api.robot_get_device("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1"), 32)
    with pytest.raises(DeviceError, match=r"e5-Joint4:15: an ear \(Joint4\) has no motor force feedback"):
        api.servo_enable_motor_force_feedback(api.robot_get_device("PRM:/r1/c1/c2/c3/e5-Joint4:15"), 32)


def test_values_refresh_only_at_multiples_of_the_period(robot):
    pan = api.robot_get_device(HEAD_PAN)
    api.servo_enable_position(pan, 64)
    api.servo_set_position(pan, 1.0)
    api.robot_step(64)
    first = api.servo_get_position(pan)
    api.robot_step(32)  # t = 96: between samples
    assert api.servo_get_position(pan) == first
    api.robot_step(32)  # t = 128: a new sample
    assert api.servo_get_position(pan) > first + 0.1


def test_servo_speed_is_limited_to_the_set_velocity(robot):
    pan = api.robot_get_device(HEAD_PAN)
    api.servo_enable_position(pan, 8)
    api.servo_set_velocity(pan, 1.0)
    api.servo_set_position(pan, 1.5)
    api.robot_step(200)
    assert robot.sim.servos.command[1] == pytest.approx(0.2, abs=1e-9)  # 1 rad/s for 200 ms
    api.robot_step(1400)
    assert api.servo_get_position(pan) == pytest.approx(1.5, abs=0.03)
    api.servo_set_position(pan, 10.0)  # clipped to the hardware limit, 93 deg
    assert robot.sim.servos.target[1] == pytest.approx(np.radians(93))


def test_acceleration_limit_ramps_the_speed(robot):
    pan = api.robot_get_device(HEAD_PAN)
    api.servo_set_acceleration(pan, 10.0)
    api.servo_set_position(pan, 1.0)
    api.robot_step(96)
    # v = a t: after 96 ms at most 0.5 * 10 * 0.096^2 + a frame of slack
    assert robot.sim.servos.command[1] < 0.5 * 10 * 0.104**2 + 1e-9


def test_camera_delivers_at_most_30_frames_a_second(robot):
    camera = api.robot_get_device(CAMERA)
    with pytest.raises(DeviceError, match="not enabled"):
        api.camera_get_image(camera)
    api.camera_enable(camera, 8)
    pan = api.robot_get_device(HEAD_PAN)
    api.servo_set_position(pan, 1.0)  # the view changes every frame
    images = []
    for _ in range(125):  # 1 s
        api.robot_step(8)
        images.append(api.camera_get_image(camera).tobytes())
    changes = sum(a != b for a, b in zip(images, images[1:]))
    assert 25 <= changes <= 30
    assert len(images[0]) == 208 * 160 * 3
    assert api.camera_get_width(camera) == 208 and api.camera_get_height(camera) == 160
    assert api.camera_get_fov(camera) == pytest.approx(0.993092)


def test_camera_save_image_writes_the_last_picture_as_webots_did(robot, tmp_path, capsys):
    camera = api.robot_get_device(CAMERA)
    with pytest.raises(DeviceError, match="not enabled"):
        api.camera_save_image(camera, str(tmp_path / "a.png"), 0)
    api.camera_enable(camera, 32)
    api.robot_step(64)
    picture = api.camera_get_image(camera).reshape(160, 208, 3)
    assert api.camera_save_image(camera, str(tmp_path / "a.PNG"), 0) == 0  # quality: for JPEGs only
    assert np.array_equal(cv2.imread(str(tmp_path / "a.PNG"))[:, :, ::-1], picture)
    assert api.camera_save_image(camera, tmp_path / "b.jpeg", 100) == 0
    jpeg = (tmp_path / "b.jpeg").read_bytes()
    frame = jpeg.index(b"\xff\xc0")  # baseline; three components sampled 1x1, colour not subsampled (as a stick's)
    assert jpeg[:2] == b"\xff\xd8" and jpeg[frame + 5 : frame + 19] == bytes.fromhex("00a000d003011100021101031101")
    assert np.abs(cv2.imread(str(tmp_path / "b.jpeg"))[:, :, ::-1].astype(int) - picture).mean() < 4
    (tmp_path / "elsewhere").write_bytes(b"kept")
    (tmp_path / "link.png").symlink_to(tmp_path / "elsewhere")  # replaced, not written through
    assert api.camera_save_image(camera, str(tmp_path / "link.png"), 0) == 0
    assert (tmp_path / "elsewhere").read_bytes() == b"kept" and not (tmp_path / "link.png").is_symlink()
    capsys.readouterr()
    assert api.camera_save_image(camera, str(tmp_path / "no" / "c.png"), 0) == -1  # Webots' answer
    assert capsys.readouterr().err == (
        f"aibo-sim: {CAMERA}: camera_save_image('{tmp_path}/no/c.png', 0): cannot write {tmp_path}/no/c.png: "
        "No such file or directory\n"
    )
    for filename, quality, reason in [  # -1 too, as Webots answers an unknown ending
        ("a.gif", 0, "the file name must end in .png, .jpg or .jpeg"),
        ("png", 0, "the file name must end in .png, .jpg or .jpeg"),
        ("", 0, "not a file name"),
        ("a\0.png", 0, "not a file name"),  # a bare ValueError before
        ("\ud800.png", 0, "not a file name"),  # a UnicodeEncodeError
        ("a.jpg", 0, "a JPEG's quality must be a whole number 1-100"),
        ("a.jpg", 101, "a JPEG's quality must be a whole number 1-100"),
        ("a.jpg", 1.5, "a JPEG's quality must be a whole number 1-100"),
    ]:
        assert api.camera_save_image(camera, filename, quality) == -1
        assert (
            capsys.readouterr().err == f"aibo-sim: {CAMERA}: camera_save_image({filename!r}, {quality!r}): {reason}\n"
        )
    (tmp_path / "loop").symlink_to(tmp_path / "loop")  # a RuntimeError from Path.resolve before
    assert api.camera_save_image(camera, str(tmp_path / "loop" / "a.png"), 0) == -1
    assert capsys.readouterr().err.endswith(f"cannot write {tmp_path}/loop/a.png: Too many levels of symbolic links\n")
    for name in ["b" * 251 + ".png", ".png"]:  # a temporary name too long for the file system before; a dot-name
        assert api.camera_save_image(camera, str(tmp_path / name), True) == 0  # a PNG's quality is ignored
    with pytest.raises(DeviceError, match=re.escape(f"{CAMERA}: camera_save_image(None, 0): the file name must be")):
        api.camera_save_image(camera, None, 0)
    assert api.camera_save_image(camera, "c.png", 0, folder=str(tmp_path)) == 0  # the C binding's controller's
    names = ["a.PNG", "b" * 251 + ".png", "b.jpeg", "c.png", "elsewhere", "link.png", "loop", ".png"]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(names)
    (tmp_path / "outside").mkdir()
    (tmp_path / "sub").symlink_to(tmp_path / "outside")  # a folder link planted in the working folder
    capsys.readouterr()
    assert api.camera_save_image(camera, "sub/x.png", 0, folder=str(tmp_path)) == -1  # written through it before
    assert f"{tmp_path}/sub is a symbolic link: refusing to follow it" in capsys.readouterr().err
    assert not list((tmp_path / "outside").iterdir())
    assert api.camera_save_image(camera, str(tmp_path / "sub" / "x.png"), 0) == 0  # named whole: the caller's choice
    assert (tmp_path / "outside" / "x.png").exists()


def test_two_controllers_saving_one_name_at_once_both_write_it(robot, tmp_path, capsys):
    """A match's controllers share a working folder: each write had the temporary name .NAME.tmp,
    so one thread's rename took the other's file and the other's failed (-1 some 40 % of saves)."""
    api.camera_enable(api.robot_get_device(CAMERA), 32)
    api.robot_step(64)
    camera = robot.get_device(CAMERA)

    def save(answers):
        answers += [camera.save_image("shot.png", 0, str(tmp_path)) for _ in range(150)]

    answers = [[], []]
    threads = [threading.Thread(target=save, args=(a,)) for a in answers]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert answers == [[0] * 150] * 2 and capsys.readouterr().err == ""
    assert os.listdir(tmp_path) == ["shot.png"]  # the last writer's, no temporary file left


def test_sensors_read_in_their_units(robot):
    chest = api.robot_get_device("PRM:/p1-Sensor:p1")
    paw = api.robot_get_device("PRM:/r2/c1/c2/c3/c4-Sensor:24")
    head = api.robot_get_device("PRM:/r1/c1/c2/c3/t1-Sensor:t1")
    accel = api.robot_get_device("PRM:/a1-Sensor:a1")
    for tag, enable in (
        (chest, api.distance_sensor_enable),
        (paw, api.touch_sensor_enable),
        (head, api.touch_sensor_enable),
        (accel, api.accelerometer_enable),
    ):
        enable(tag, 16)
    api.robot_step(320)
    assert 100 <= api.distance_sensor_get_value(chest) <= 900
    assert api.touch_sensor_get_value(paw) == 1.0 and api.touch_sensor_get_value(head) == 0.0
    values = api.accelerometer_get_values(accel)
    assert api.accelerometer_value_z(values) == pytest.approx(9.81, abs=0.3)
    assert api.robot_get_device("PRM:/a3-Sensor:a3") == accel


def face_rgb(robot, spot: str) -> np.ndarray:
    return robot.sim.model.geom(f"led_face_{spot}").rgba[:3].copy()


def test_face_lights_sit_where_model_information_draws_them_and_blend_where_they_share_a_spot(robot):
    """A.2: A1 the bottom outer spot on the left, A13 a red pair on A9's and A10's spots (lit with
    A9, the left one adds up their light), A14 a pair above the outer ones; a reset puts all out."""
    off, white, red = np.array(ers7.LED_OFF_RGBA[:3]), np.ones(3), np.array([1.0, 0.1, 0.1])
    face = {n: api.robot_get_device(ers7.LED_BY_NAME[f"led_face_{n}"].locator) for n in (1, 9, 13, 14)}
    model = robot.sim.model
    left, right = (model.geom(f"led_face_bottom_outer_{s}").pos for s in "lr")
    assert left[1] > 0 and np.allclose(left * (1, -1, 1), right)  # the robot's left is +y
    api.led_set(face[1], 1)
    assert np.allclose(face_rgb(robot, "bottom_outer_l"), white) and np.allclose(face_rgb(robot, "bottom_outer_r"), off)
    api.led_set(face[13], 1)
    assert all(np.allclose(face_rgb(robot, f"upper_inner_{s}"), red) for s in "lr")
    api.led_set(face[9], 1)
    both = np.clip(white + red - off, 0, 1)  # (1, 0.95, 0.94)
    assert np.allclose(face_rgb(robot, "upper_inner_l"), both) and np.allclose(face_rgb(robot, "upper_inner_r"), red)
    api.led_set(face[13], 0)
    assert np.allclose(face_rgb(robot, "upper_inner_l"), white) and np.allclose(face_rgb(robot, "upper_inner_r"), off)
    api.led_set(face[14], 255)
    top, upper = model.geom("led_face_top_outer_l").pos, model.geom("led_face_upper_outer_l").pos
    assert np.allclose(face_rgb(robot, "top_outer_r"), red) and top[2] > upper[2] and top[1] == upper[1]
    robot.sim.reset()
    leds = [g for g in map(model.geom, range(model.ngeom)) if g.name.startswith("led_")]
    lit = [g.name for g in leds if not np.allclose(g.rgba[:3], off)]
    assert len(leds) == 30 and lit == []


def test_a_face_lights_b_face_has_its_own_colour_and_for_3_4_13_14_its_own_spots(robot):
    """Model Information 3.1.1: B3 sits where B13's left does, apart from A3; B14 is a blue pair."""
    sim, off = robot.sim, np.array(ers7.LED_OFF_RGBA[:3])
    sim.set_led("led_face_3", 1.0, face_b=True)
    green = np.array(ers7.LED_BY_NAME["led_face_3"].colour_b)
    assert np.allclose(face_rgb(robot, "bottom_inner_l"), green) and np.allclose(face_rgb(robot, "middle_outer_l"), off)
    sim.set_led("led_face_3", 1.0)  # back on the A face: the B spot goes out
    assert np.allclose(face_rgb(robot, "middle_outer_l"), 1) and np.allclose(face_rgb(robot, "bottom_inner_l"), off)
    sim.set_led("led_face_14", 0.5, face_b=True)
    blue = off + 0.5 * (np.array(ers7.LED_BY_NAME["led_face_14"].colour_b) - off)
    assert all(np.allclose(face_rgb(robot, f"lowest_outer_{s}"), blue) for s in "lr")


def test_led_set_colours_the_geom(robot):
    led = api.robot_get_device("PRM:/lu-LED3:lu")
    geom = robot.sim.model.geom("led_back_front_colour").id
    off = robot.sim.model.geom_rgba[geom].copy()
    api.led_set(led, 1)
    assert robot.sim.model.geom_rgba[geom][2] > 0.9  # blue
    api.led_set(led, 0)
    np.testing.assert_allclose(robot.sim.model.geom_rgba[geom], off)


def test_step_must_be_whole_joint_frames(robot):
    with pytest.raises(ValueError, match="multiple of the 8 ms"):
        api.robot_step(10)


def test_run_ends_with_simulation_end(robot):
    robot.end_ms = 64
    calls = []

    def run(ms):
        calls.append(api.robot_get_time())
        return 32

    with pytest.raises(SimulationEnd):
        api.robot_run(run)
    assert calls == [0.0, 0.032, 0.064]


def _two_keyframe_motion(tmp_path, name="TEST.MTN", locators=(LF_J1,)):
    motion = Motion.from_poses("a_stand#stand_test", list(locators), np.radians([[0.0], [20.0]]), [48])
    write_mtn(motion, tmp_path / name)
    return tmp_path / name


def test_mtn_through_the_api_follows_openr_interpolation(robot, tmp_path):
    robot.search_dirs = (tmp_path,)
    motion = api.mtn_new(_two_keyframe_motion(tmp_path).name)
    assert api.mtn_get_length(motion) == 48 and api.mtn_get_name(motion) == "a_stand#stand_test"
    api.mtn_play(motion)
    assert not api.mtn_is_over(motion)
    commands = []
    for _ in range(7):
        api.robot_step(8)
        commands.append(robot.sim.servos.command[6])
    # 6 sub-frames of 8 ms stepping by the integer micro-radian (v1 - v0) / 6, then the last keyframe.
    end = round(np.radians(20) * 1e6)
    np.testing.assert_allclose(np.array(commands) * 1e6, [i * (end // 6) for i in range(6)] + [end], atol=1e-6)
    api.robot_step(8)
    assert api.mtn_is_over(motion)


def test_mtn_new_looks_in_the_controllers_folder_then_the_working_folder_then_the_bundled_motions(
    robot, tmp_path, monkeypatch
):
    """Each folder's exact name first, then ignoring case; the shell's folder never hides the
    controller's file (in Webots the two are one folder)."""
    controller, working = tmp_path / "controller", tmp_path / "working"
    for folder, names in ((controller, ("sit.mtn", "OWN.MTN")), (working, ("SIT.MTN", "OWN.MTN", "MINE.MTN"))):
        folder.mkdir()
        for name in names:
            motion = Motion.from_poses(f"{folder.name}#{name}", [LF_J1], np.zeros((2, 1)), [48])
            write_mtn(motion, folder / name)
    monkeypatch.chdir(working)
    robot.search_dirs = motion_dirs(controller / "pick.py")
    names = {name: api.mtn_get_name(api.mtn_new(name)) for name in ("SIT.MTN", "own.mtn", "mine.mtn", "WALKFWD.MTN")}
    assert names == {
        "SIT.MTN": "controller#sit.mtn",  # the controller's, in another case, before the working folder's
        "own.mtn": "controller#OWN.MTN",
        "mine.mtn": "working#MINE.MTN",  # a file the controller wrote where it runs (--out)
        "WALKFWD.MTN": read_mtn(models_dir() / "motions" / "WALKFWD.MTN").name,
    }
    # a memory stick's path finds the name; any other absolute path is that file or none
    assert api.mtn_get_name(api.mtn_new("/MS/OPEN-R/MW/DATA/P/MINE.MTN")) == "working#MINE.MTN"
    assert api.mtn_new(str(tmp_path / "typo" / "MINE.MTN")) is None and "File not found" in api.mtn_get_error()


def test_mtn_fprint_and_grey(robot, tmp_path, capsys):
    robot.search_dirs = (tmp_path,)
    motion = api.mtn_new(_two_keyframe_motion(tmp_path).name)
    api.mtn_fprint(sys.stdout, motion)
    out = capsys.readouterr().out
    assert "a_stand#stand_test" in out and "48 ms" in out and LF_J1 in out
    image = np.array([30, 60, 91], np.uint8)
    assert api.camera_image_get_grey(image, 1, 0, 0) == api.camera_image_get_gray(image, 1, 0, 0) == 60


def test_mtn_new_failures_set_the_webots_error(robot, tmp_path):
    path = _two_keyframe_motion(tmp_path, "BAD.MTN", locators=("PRM:/r9/c1-Joint2:91",))
    assert api.mtn_new(str(path)) is None
    assert api.mtn_get_error() == "Missing device in model: PRM:/r9/c1-Joint2:91"
    assert api.mtn_new("NOSUCH.MTN") is None and "NOSUCH.MTN" in api.mtn_get_error()
    with pytest.raises(ValueError, match="mtn_new failed"):
        api.mtn_play(None)


def test_webots_mode_steps_one_keyframe_per_control_step(tmp_path):
    robot = Robot(Simulation(), mtn_mode="webots")
    api.install(robot)
    try:
        motion = Motion.from_poses("a#b_c", [LF_J1], np.radians([[0.0], [10.0], [20.0], [30.0]]), [16, 16, 16])
        api.mtn_play(motion)
        targets = []
        for _ in range(5):
            api.robot_step(64)
            targets.append(round(float(np.degrees(robot.sim.servos.target[6])), 3))
        # One keyframe per 64 ms call (Webots' quirk), not 16 ms apart.
        assert targets[:4] == [0.0, 10.0, 20.0, 30.0]
        assert api.mtn_is_over(motion)
    finally:
        api.install(None)
        robot.sim.close()
