"""The ERS-7 MJCF model and its scenes (issue 2)."""

import math

import mujoco
import numpy as np
import pytest

from aibo_sim import ers7, mjcf
from aibo_sim.sim import ModelError, Simulation, load_model, models_dir

SCENES = sorted(models_dir().glob("scene*.xml"))

# Sony hardware limits in degrees, typed in from the spec's table A.4 (not read from ers7.py).
SPEC_HW_LIMITS = {
    "neck_tilt": (-80, 3), "head_pan": (-93, 93), "head_tilt": (-20, 50), "mouth": (-60, 0),
    "ear_l": (0, 15), "ear_r": (0, 15), "tail_tilt": (0, 65), "tail_pan": (-60, 60),
    **{f"{leg}_j1": (-120, 135) for leg in ("lf", "rf")},
    **{f"{leg}_j1": (-135, 120) for leg in ("lh", "rh")},
    **{f"{leg}_j2": (-15, 93) for leg in ("lf", "lh", "rf", "rh")},
    **{f"{leg}_j3": (-30, 127) for leg in ("lf", "lh", "rf", "rh")},
}


@pytest.fixture(scope="module")
def model():
    return load_model()


def test_generated_files_are_committed():
    for name, text in mjcf.generated_files().items():
        assert (models_dir() / name).read_text() == text, f"models/{name} is stale: run python -m aibo_sim.mjcf"


@pytest.mark.parametrize("scene", SCENES, ids=[s.name for s in SCENES])
def test_every_scene_compiles_and_holds_the_robot(scene):
    model = mujoco.MjModel.from_xml_path(str(scene))
    assert model.nu == 20 and model.nkey >= 2
    assert {model.key(i).name for i in range(model.nkey)} >= {"stand", "sit"}


def test_joint_ranges_equal_the_spec(model):
    assert [model.joint(i + 1).name for i in range(20)] == [j.name for j in ers7.JOINTS]
    for name, (low, high) in SPEC_HW_LIMITS.items():
        np.testing.assert_allclose(np.degrees(model.joint(name).range), (low, high), atol=1e-9)
        np.testing.assert_allclose(np.degrees(model.actuator(name).ctrlrange), (low, high), atol=1e-9)
        assert model.actuator(name).forcerange[1] == pytest.approx(5.4542)


def test_locator_table_covers_sony_primitives():
    locators = ers7.all_locators()
    assert len(locators) == len(set(locators))
    assert "PRM:/r2/c1-Joint2:21" in locators and "PRM:/r5/c1/c2/c3-Joint2:53" in locators
    assert "PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1" in locators
    assert len(ers7.LEDS) == 26 and sum(s.kind == "touch" for s in ers7.SENSORS) == 9


def test_masses_follow_the_spec(model):
    body = model.body("body").id
    assert model.body_subtreemass[body] == pytest.approx(1.628, abs=1e-6)
    assert 1.5 <= model.body_subtreemass[body] <= 1.7
    assert model.body_mass[body] == pytest.approx(0.613)
    assert model.body_mass[model.body("lf_j2").id] == pytest.approx(0.073)


def test_visual_and_collision_geoms_are_separate(model):
    for g in range(model.ngeom):
        if model.geom_bodyid[g] == 0 or model.body_rootid[model.geom_bodyid[g]] != model.body("body").id:
            continue
        if model.geom_group[g] in (1, 2):  # visual; group 1 is hidden from the head camera
            assert model.geom_contype[g] == 0 and model.geom_conaffinity[g] == 0
        else:
            assert model.geom_group[g] == 3 and model.geom_contype[g] != 0
    assert model.geom_size[model.geom("lf_paw").id][0] == pytest.approx(0.01172)


@pytest.mark.parametrize("scene", SCENES, ids=[s.name for s in SCENES])
def test_pseudorandom_control_over_full_ranges_raises_no_warning(scene):
    """Menagerie's protocol: from qpos0, a new Halton-sequence control over each actuator's
    whole range every physics step, for 1 s; then from the stand keyframe with random controls
    held for one 8 ms joint frame."""
    model = mujoco.MjModel.from_xml_path(str(scene))
    centre, radius = model.actuator_ctrlrange.mean(axis=1), np.ptp(model.actuator_ctrlrange, axis=1) / 2
    data = mujoco.MjData(model)
    step = 0
    while data.time < 1.0:
        data.ctrl[:] = centre + radius * np.array([2 * mujoco.mju_Halton(step, j + 2) - 1 for j in range(model.nu)])
        mujoco.mj_step(model, data)
        step += 1
    mujoco.mj_resetDataKeyframe(model, data, model.key("stand").id)
    rng = np.random.default_rng(7)
    while data.time < 2.0:
        data.ctrl[:] = rng.uniform(centre - radius, centre + radius)
        mujoco.mj_step(model, data, nstep=2)  # one 8 ms joint frame
    assert [w.number for w in data.warning] == [0] * len(data.warning)
    assert np.isfinite(data.qpos).all()


def test_model_folder_has_menagerie_files():
    for name in ("README.md", "LICENSE", "CHANGELOG.md", "ers7.png"):
        assert (models_dir() / name).is_file(), name


def test_standing_for_10_s_drifts_less_than_5_mm():
    sim = Simulation()
    start = sim.data.qpos[2]
    heights = []
    while sim.time_ms < 10_000:
        sim.step_frame()
        heights.append(sim.data.qpos[2])
    assert max(abs(h - start) for h in heights[-125:]) < 0.005
    assert not sim.fallen()


def test_frames_step_like_plain_mujoco_with_sensors_read_at_the_end():
    """step_frame computes sensors only in a frame's last step, and in none with
    sensors=False (here 3 frames in 4, as the environments do): states are bit for bit those
    of mj_step run steps_per_frame times with every sensor on, and so are the readings
    after each frame computed with sensors."""
    sim = Simulation()
    sim.place_ball(0.3, 0.0)
    sim.data.qvel[sim.model.joint("ball").dofadr[0]] = -1.0  # rolls into the front paws
    plain = mujoco.MjData(sim.model)
    mujoco.mj_copyData(plain, sim.model, sim.data)
    assert sim.steps_per_frame > 1
    for frame in range(200):
        sim.servos.set_target(slice(None), sim.servos.low + (frame % 50) / 50 * (sim.servos.high - sim.servos.low))
        with_sensors = frame % 4 == 3
        sim.step_frame(sensors=with_sensors)
        plain.ctrl[:] = sim.data.ctrl
        mujoco.mj_step(sim.model, plain, nstep=sim.steps_per_frame)
        assert np.array_equal(sim.data.qpos, plain.qpos) and np.array_equal(sim.data.qvel, plain.qvel)
        assert np.array_equal(sim.data.sensordata, plain.sensordata) == with_sensors  # stale without
    assert not sim.model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_SENSOR  # restored after each frame


def test_servo_set_points_planned_for_several_frames_equal_frame_by_frame_ones():
    """advance_frames(n) returns, and leaves behind, bit for bit what n advance() calls do:
    joints arriving mid-way, at rest, stopped (velocity 0), slowed, and with an acceleration
    limit (planned frame by frame)."""
    rng = np.random.default_rng(7)
    batched, single = Simulation().servos, Simulation().servos
    for round_ in range(60):
        joints = rng.choice(len(ers7.JOINTS), rng.integers(0, 6), replace=False)
        targets = single.command[joints] + rng.uniform(-0.05, 0.05, len(joints))
        velocity = single.max_velocity * rng.choice([1.0, 0.3, 0.0], len(ers7.JOINTS), p=[0.6, 0.3, 0.1])
        acceleration = np.where(rng.random(len(ers7.JOINTS)) < 0.2, 30.0, np.inf) if round_ % 3 == 2 else np.inf
        for servos in (batched, single):
            servos.set_target(joints, targets)
            servos.velocity[:], servos.acceleration[:] = velocity, acceleration
        frames = int(rng.integers(1, 7))
        planned = batched.advance_frames(frames, 0.008)
        one_by_one = np.array([single.advance(0.008).copy() for _ in range(frames)])
        assert planned.shape == (frames, len(ers7.JOINTS)) and np.array_equal(planned, one_by_one)
        assert np.array_equal(batched.command, single.command) and np.array_equal(batched._speed, single._speed)


def test_several_frames_at_once_step_like_one_frame_at_a_time():
    """step_frames(n, before_frame): the states, sensor readings and frame count of n
    step_frame calls (sensors in the last only), before_frame called before each frame."""
    at_once, one_by_one = Simulation(), Simulation()
    calls = []
    for sim in (at_once, one_by_one):
        sim.servos.set_target(slice(None), sim.servos.low + 0.3 * (sim.servos.high - sim.servos.low))
    for frames in (4, 5, 1, 4, 5, 3):
        at_once.step_frames(frames, lambda: calls.append(at_once.frame))
        for frame in range(frames):
            one_by_one.step_frame(sensors=frame == frames - 1)
        assert calls[-frames:] == list(range(at_once.frame - frames, at_once.frame))
        assert at_once.frame == one_by_one.frame
        for field in ("qpos", "qvel", "ctrl", "sensordata"):
            assert np.array_equal(getattr(at_once.data, field), getattr(one_by_one.data, field)), field
    for bad in (0, -1, 2.5):
        with pytest.raises(ValueError, match="frames must be a whole number >= 1"):
            at_once.step_frames(bad)


def test_sit_keyframe_rests_nose_up_on_its_paws_and_rump():
    sim = Simulation(keyframe="sit")
    start = sim.data.qpos[2]
    for _ in range(250):  # 2 s
        sim.step_frame()
    _, _, tilt = sim.body_pose()
    pitch_up = -2 * math.asin(sim.data.qpos[5])  # quaternion y component: negative = nose up
    assert 25 < math.degrees(pitch_up) < 45 and math.degrees(tilt) < 45
    assert abs(sim.data.qpos[2] - start) < 0.005
    for leg in ers7.LEGS:
        assert sim.touched(f"touch_paw_{leg}", 0.1)


def test_camera_fields_of_view_measured_by_projecting_points(tmp_path):
    """Markers at known angles off the optical axis land where 56.9 x 45.2 deg predicts."""
    from aibo_sim.render import Renderer

    spec = mujoco.MjSpec.from_file(str(models_dir() / "ers7.xml"))
    angles = [(-25.0, 0.0), (25.0, 0.0), (0.0, -20.0), (0.0, 20.0), (0.0, 0.0)]
    for i in range(len(angles)):
        body = spec.worldbody.add_body(name=f"marker{i}", mocap=True)
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.01, 0, 0], rgba=[1, 1, 1, 1], contype=0, conaffinity=0)
    spec.visual.headlight.ambient = [1, 1, 1]
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("stand").id)
    mujoco.mj_forward(model, data)
    cam = model.camera("camera").id
    pos, rot = data.cam_xpos[cam], data.cam_xmat[cam].reshape(3, 3)
    for i, (h, v) in enumerate(angles):  # camera frame: x right, y up, -z forward
        direction = rot @ np.array([math.tan(math.radians(h)), math.tan(math.radians(v)), -1.0])
        data.mocap_pos[i] = pos + 2.0 * direction
    mujoco.mj_forward(model, data)
    renderer = Renderer(model, 416, 320)
    image = renderer.render(data, "camera").max(axis=2)
    renderer.close()
    centres = _blob_centres(image > 200)
    assert len(centres) == len(angles)

    def nearest(x, y):
        return min(centres, key=lambda c: (c[0] - x) ** 2 + (c[1] - y) ** 2)

    left, right = nearest(0, 160), nearest(416, 160)
    top, bottom = nearest(208, 0), nearest(208, 320)
    fx = (right[0] - left[0]) / (2 * math.tan(math.radians(25)))
    fy = (bottom[1] - top[1]) / (2 * math.tan(math.radians(20)))
    assert math.degrees(2 * math.atan(208 / fx)) == pytest.approx(56.9, abs=0.2)
    assert math.degrees(2 * math.atan(160 / fy)) == pytest.approx(45.2, abs=0.2)
    centre = nearest(208, 160)
    assert centre == pytest.approx((207.5, 159.5), abs=0.6)


def _blob_centres(mask: np.ndarray) -> list[tuple[float, float]]:
    import cv2

    count, _, stats, centroids = cv2.connectedComponentsWithStats(mask.astype(np.uint8))
    return [tuple(c) for c, s in zip(centroids[1:], stats[1:]) if s[cv2.CC_STAT_AREA] >= 4]


def test_sensors_read_plausible_values_when_standing():
    sim = Simulation()
    for _ in range(125):  # 1 s to settle
        sim.step_frame()
    data, model = sim.data, sim.model
    site = model.site("ir_chest").id
    origin, axis = data.site_xpos[site], data.site_xmat[site].reshape(3, 3)[:, 2]
    assert axis[2] < -0.4  # aimed about 30 deg below the body's horizontal
    expected = origin[2] / -axis[2]  # where the ray meets the floor
    assert sim.sensor("ir_chest")[0] == pytest.approx(expected, abs=1e-4)
    assert 100 < sim.distance_mm("ir_chest") < 900
    for leg in ers7.LEGS:
        assert sim.touched(f"touch_paw_{leg}", 0.1)
    for name in ("touch_head", "touch_chin", "touch_back_front", "touch_back_middle", "touch_back_rear"):
        assert not sim.touched(name, 0.1)
    accel = sim.acceleration()
    assert np.linalg.norm(accel) == pytest.approx(9.81, abs=0.1)
    assert accel[2] > 9.5
    np.testing.assert_allclose(sim.joint_positions(), sim.servos.command, atol=0.05)


def test_sensor_arrays_equal_the_per_sensor_readings():
    """The environments read all IR and touch sensors at once; the controller API one by one.
    Same noise draws in the same order, so the same numbers, bit for bit."""
    batch, single = Simulation(seed=7), Simulation(seed=7)
    for sim in (batch, single):
        sim.place_ball(0.25, 0.0)  # something in front of the head IRs
        for _ in range(60):
            sim.step_frame()
    names = [s.name for s in ers7.DISTANCE_SENSORS]
    for _ in range(5):  # noise differs from draw to draw
        one_by_one = [single.distance_mm(name) for name in names]
        assert batch.distances_mm() == one_by_one
    assert any(50 < mm < 1500 for mm in one_by_one)  # some mid-range reading, where noise applies
    assert batch.touches().tolist() == [single.touched(s.name, s.threshold) for s in ers7.TOUCH_SENSORS]
    assert batch.touches().sum() == 4  # the paws


@pytest.mark.parametrize("content", [None, "<mujoco><worldbody><body></mujoco>", "not xml at all"])
def test_bad_model_file_names_the_file(tmp_path, content):
    path = tmp_path / "broken_scene.xml"
    if content is not None:
        path.write_text(content)
    with pytest.raises(ModelError, match="broken_scene.xml"):
        load_model(path)


def test_culling_geoms_out_of_view_changes_no_pixel():
    """Random robot poses and head angles on the field, the ball near the robot, and two head
    poses that see the front legs: RGB, depth and segmentation from the culling renderer
    equal those drawn with every geom."""
    from aibo_sim.render import Renderer
    from aibo_sim.camera import HEAD_CAMERA_GROUPS

    sim = Simulation()
    sim.place_ball(0.35, 0.05)
    culling = Renderer(sim.model, 208, 160, groups=HEAD_CAMERA_GROUPS)
    drawing_all = Renderer(sim.model, 208, 160, groups=HEAD_CAMERA_GROUPS, cull=False)
    rng = np.random.default_rng(7)
    drawn, total, robot_seen = [], [], False
    robot_geoms = {g for g in range(sim.model.ngeom) if sim.model.geom_group[g] == 2}
    head_poses = [(-1.3, -0.8, -0.3), (-1.3, 0.8, -0.3)]  # neck tilt, pan, head tilt: legs in view
    head_poses += rng.uniform((-1.3, -1.5, -0.3), (0.05, 1.5, 0.7), (40, 3)).tolist()
    for head_pose in head_poses:
        sim.place_robot(*rng.uniform(-2.0, 2.0, 2), rng.uniform(-math.pi, math.pi))
        for name, angle in zip(("neck_tilt", "head_pan", "head_tilt"), head_pose):
            sim.data.qpos[sim.model.joint(name).qposadr[0]] = angle
        mujoco.mj_forward(sim.model, sim.data)
        for method in ("render", "render_depth", "render_segmentation"):
            culled, full = getattr(culling, method)(sim.data, "camera"), getattr(drawing_all, method)(sim.data, "camera")
            assert np.array_equal(culled, full), method
        drawn.append(culling.scene.ngeom)
        total.append(drawing_all.scene.ngeom)
        robot_seen |= bool(robot_geoms & set(np.unique(full).tolist()))
    culling.close()
    drawing_all.close()
    assert robot_seen  # some poses look at the robot's own legs: partly visible geoms were kept
    assert sum(drawn) < 0.5 * sum(total)


def test_renderers_taking_turns_each_draw_in_their_own_context():
    """Renderers skip making their OpenGL context current when it already is: interleaved
    with another renderer (another size, scene and camera), each one's frames equal those it
    draws alone."""
    from aibo_sim.render import Renderer
    from aibo_sim.camera import HEAD_CAMERA_GROUPS

    sim, other = Simulation(), Simulation(models_dir() / "scene_webots.xml")
    head = Renderer(sim.model, 208, 160, groups=HEAD_CAMERA_GROUPS)
    alone = [head.render(sim.data, "camera") for _ in range(2)]
    third_person = Renderer(other.model, 320, 240)
    view = third_person.render(other.data, "tracking")
    for _ in range(2):
        assert np.array_equal(head.render(sim.data, "camera"), alone[0])
        assert np.array_equal(third_person.render(other.data, "tracking"), view)
    assert np.array_equal(alone[0], alone[1]) and view.shape == (240, 320, 3)
    head.close()
    third_person.close()


def test_culling_with_a_free_camera_changes_no_pixel():
    """A third-person free camera close to the robot, so that some geoms fall outside the
    picture and others cross its edges."""
    from aibo_sim.render import Renderer

    sim = Simulation()
    culling, drawing_all = Renderer(sim.model, 160, 120), Renderer(sim.model, 160, 120, cull=False)
    camera = mujoco.MjvCamera()
    camera.type, camera.distance = mujoco.mjtCamera.mjCAMERA_FREE, 0.4
    for azimuth in range(0, 360, 45):
        camera.lookat[:], camera.azimuth, camera.elevation = (0.1, 0.0, 0.1), azimuth, -25
        assert np.array_equal(culling.render(sim.data, camera), drawing_all.render(sim.data, camera)), azimuth
        assert culling.scene.ngeom < drawing_all.scene.ngeom
    culling.close()
    drawing_all.close()
