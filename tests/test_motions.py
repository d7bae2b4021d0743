"""aibo-sim's own motions: leg kinematics, the gait generator, the shipped MTN files."""

import math

import mujoco
import numpy as np
import pytest

from aibo_sim import ers7, motions
from aibo_sim.mtn import Motion, read_mtn, serialize_mtn
from aibo_sim.sim import Simulation, load_model, models_dir

MOTION_DIR = models_dir() / "motions"
SHIPPED = {  # file: (name, keyframes, length_ms, numInterpolate)
    "WALKFWD.MTN": ("a_walk#walk_fwd", 21, 320, 0),
    "TURNL.MTN": ("a_walk#walk_turn_l", 21, 320, 0),
    "TURNR.MTN": ("a_walk#walk_turn_r", 21, 320, 0),
    "SIT.MTN": ("a_stand#sit_sitdown", 11, 1600, 9),
    "STAND.MTN": ("a_sit#stand_standup", 11, 1600, 9),
}
# Loops of a 320 ms gait that fit in 10 s with the blend; Webots' mtn_step takes 16 ms more a
# loop (it commands the closing keyframe, then the first again).
TEN_SECONDS = {"openr": (10_000 - motions.BLEND_MS) // 320, "webots": (10_000 - motions.BLEND_MS) // 336}


def leg_joints(leg):
    return [f"{leg}_j{i}" for i in (1, 2, 3)]


def test_paw_positions_match_mujoco_forward_kinematics():
    model = load_model()
    data = mujoco.MjData(model)
    rng = np.random.default_rng(7)
    body = model.body("body").id
    for _ in range(10):
        for j in ers7.JOINTS:
            data.qpos[model.joint(j.name).qposadr[0]] = rng.uniform(*j.range)
        mujoco.mj_kinematics(model, data)
        rotation = data.xmat[body].reshape(3, 3)
        for leg in ers7.LEGS:
            angles = [data.qpos[model.joint(n).qposadr[0]] for n in leg_joints(leg)]
            in_body = rotation.T @ (data.geom_xpos[model.geom(f"{leg}_paw").id] - data.xpos[body])
            assert np.abs(motions.paw_position(leg, angles) - in_body).max() < 1e-4


def test_inverse_kinematics_round_trip():
    rng = np.random.default_rng(3)
    for leg in ers7.LEGS:
        for _ in range(50):
            # The working range: knee bent beyond the straight leg, as in Sony's walks.
            angles = np.radians([rng.uniform(-60, 60), rng.uniform(-10, 60), rng.uniform(30, 120)])
            paw = motions.paw_position(leg, angles)
            np.testing.assert_allclose(motions.leg_angles(leg, paw), angles, atol=1e-9)
        with pytest.raises(ValueError, match="out of reach"):
            motions.leg_angles(leg, (0.0, 0.0, -0.3))


def test_shipped_files_are_what_the_generator_writes(tmp_path):
    written = motions.generate_motion_files(tmp_path)
    assert sorted(p.name for p in written) == sorted(SHIPPED)
    assert sorted(p.name for p in MOTION_DIR.glob("*.MTN")) == sorted(SHIPPED)
    for name, motion in motions.motions().items():
        data = serialize_mtn(motion)
        assert (tmp_path / name).read_bytes() == data
        assert (MOTION_DIR / name).read_bytes() == data, (
            f"models/motions/{name} is stale: run python -m aibo_sim.motions"
        )


def test_the_generators_help_writes_nothing(capsys, monkeypatch):
    monkeypatch.setattr(motions, "generate_motion_files", lambda folder: pytest.fail(f"wrote into {folder}"))
    with pytest.raises(SystemExit) as exited:
        motions.main(["--help"])
    assert exited.value.code == 0 and "Write the bundled motion files" in capsys.readouterr().out


@pytest.mark.parametrize("file", sorted(SHIPPED))
def test_shipped_files_parse(file):
    name, keyframes, length_ms, interpolate = SHIPPED[file]
    motion = read_mtn(MOTION_DIR / file)
    assert (motion.name, motion.num_keyframes, motion.length_ms) == (name, keyframes, length_ms)
    assert motion.design == "DRX-1000" and motion.frame_time_ms == 16
    joints = [j for j in ers7.JOINTS if not file.startswith(("WALK", "TURN")) or j.name[:2] in ers7.LEGS]
    assert motion.locators == tuple(j.locator for j in joints)  # gaits leave the head free
    assert (motion.interpolate == interpolate).all()
    poses = motion.positions_rad()
    low, high = (np.radians([j.sw_range_deg[i] for j in joints]) for i in (0, 1))
    assert ((poses > low - 1e-5) & (poses < high + 1e-5)).all(), "outside Sony's software limits"
    if file in ("WALKFWD.MTN", "TURNL.MTN", "TURNR.MTN"):
        np.testing.assert_array_equal(motion.keyframes[0], motion.keyframes[-1])  # one whole cycle


@pytest.mark.parametrize("mode", ["openr", "webots"])
def test_forward_walk_covers_half_a_metre_in_ten_seconds(mode):
    result = motions.play_motion(MOTION_DIR / "WALKFWD.MTN", repeat=TEN_SECONDS[mode], mode=mode)
    assert 9.5 < result["duration_s"] + motions.BLEND_MS / 1000 <= 10.0  # the walk, after the blend
    assert not result["fell"]
    forward, left = result["displacement_m"]
    assert forward >= 0.5
    assert abs(left) < 0.15 and abs(result["heading_change_deg"]) < 20


@pytest.mark.parametrize("turn_rate", [None, -30.0])
def test_turn_in_place(turn_rate):
    """The shipped left turn turns left (+ yaw); the generator's right turn turns right."""
    if turn_rate is None:
        motion, sign = MOTION_DIR / "TURNL.MTN", 1
    else:
        poses = motions.gait_poses(motions.Gait(turn_rate=turn_rate))
        motion, sign = Motion.from_poses("a_walk#walk_turn_r", motions.LOCATORS, poses, 16), -1
    result = motions.play_motion(motion, repeat=TEN_SECONDS["openr"])
    assert not result["fell"]
    assert sign * result["heading_change_deg"] >= 45
    assert result["distance_m"] < 0.3


def test_sit_then_stand_reach_the_keyframe_poses():
    sim = Simulation()
    sat = motions.play_motion(MOTION_DIR / "SIT.MTN", sim=sim)
    assert not sat["fell"] and sat["duration_s"] == pytest.approx(1.608)  # no blend: it starts at stand
    assert np.degrees(np.abs(sim.joint_positions() - motions.SIT_POSE)).max() < 3
    assert math.degrees(sim.body_pose()[2]) > 25  # sitting: nose up
    stood = motions.play_motion(MOTION_DIR / "STAND.MTN", sim=sim)
    assert not stood["fell"]
    assert np.degrees(np.abs(sim.joint_positions() - motions.STAND_POSE)).max() < 3
    assert math.degrees(sim.body_pose()[2]) < 5


def test_a_motion_named_to_start_sitting_starts_from_the_sit_keyframe():
    """Sony's names, a_<start posture>#<end posture>_<label>: STAND.MTN (a_sit#stand_standup)
    starts sitting; SIT.MTN (a_stand#sit_sitdown) and a sleep motion (no such keyframe) standing."""
    result = motions.play_motion(MOTION_DIR / "STAND.MTN")
    assert not result["fell"] and result["start_keyframe"] == "sit"
    assert result["duration_s"] == pytest.approx((1600 + 8) / 1000)  # the motion's own, after the blend
    assert motions.play_motion(MOTION_DIR / "SIT.MTN")["start_keyframe"] == "stand"
    model = load_model(models_dir() / "scene.xml")
    sleep = Motion.from_poses("a_sleep#sleep_x", None, [motions.STAND_POSE], 16)
    assert motions.start_keyframe(sleep, model) == "stand"
    sit = Motion.from_poses("a_sit#sit_x", None, [motions.SIT_POSE], 16)
    assert motions.start_keyframe(sit, model) == "sit"


def test_play_motion_rejects_bad_arguments():
    motion = read_mtn(MOTION_DIR / "SIT.MTN")
    with pytest.raises(ValueError, match="mode"):
        motions.play_motion(motion, mode="fast")
    with pytest.raises(ValueError, match="step_ms"):
        motions.play_motion(motion, mode="webots", step_ms=12)
    stray = Motion.from_poses("x", ["PRM:/r9/c1-Joint2:91"], [[0.0]], 16)
    with pytest.raises(ValueError, match="locator"):
        motions.play_motion(stray)


def test_a_fall_ends_the_report_s_kinematic_distance_too():
    """SIT.MTN played over and over jumps from sitting back to its first pose and tips the robot
    over: the kinematic distance is the motion's kinematics over what was played, not over
    every repeat asked for."""
    sit = models_dir() / "motions" / "SIT.MTN"
    played = motions.play_motion(sit, repeat=50)
    assert played["fell"] and played["duration_s"] < 50 * read_mtn(sit).length_ms / 1000
    assert played["kinematic_distance_m"] == pytest.approx(
        motions.kinematic_speed(read_mtn(sit)) * played["duration_s"]
    )
