"""Motion files authored by aibo-sim: leg kinematics, a trot generator, sit/stand transitions.

The MTN files in ``models/motions/`` are what :func:`generate_motion_files` writes; a test
checks that they are up to date. Regenerate with ``python -m aibo_sim.motions``.

Leg geometry is the model's (``mjcf.py``, spec §A.2), in the body frame: X forward, Y left,
Z up, origin midway between the four J1 axes. Angles are radians with Sony's signs.
"""

from __future__ import annotations

import argparse
import math
import numbers
import os
from dataclasses import dataclass, replace
from pathlib import Path

import mujoco
import numpy as np

from .config import MAX_MAGNITUDE, CameraConfig, ParameterError, WorldConfig
from .ers7 import JOINT_BY_LOCATOR, JOINT_INDEX, JOINTS, LEGS, joint_indices
from .mjcf import HIP_OFFSET, KNEE_OFFSET, PAW_OFFSET, PAW_RADIUS, POSES
from .mtn import Motion, MotionPlayer, MtnError, another_robot, printable, read_mtn, write_mtn
from .placement import place
from .sim import FRAME_MS, Simulation, models_dir

KEYFRAME_MS = 16  # Sony's walks: pre-sampled 16 ms keyframes, numInterpolate 0
BLEND_MS = 512  # play_motion's blend from the current pose to a motion's first keyframe
# Sony names a motion a_<start posture>#<end posture>_<label>: the start postures with a keyframe
# of that name (models/ers7.xml) start there; the others (stand, walk, sleep, ...) from the stand.
START_KEYFRAMES = ("sit",)


# ----------------------------------------------------------------------------- kinematics


def _leg_geometry(leg: str) -> tuple[int, int, np.ndarray, np.ndarray, np.ndarray]:
    """(fb, side, hip, knee, paw): fb = +1 front / -1 hind, side = +1 left / -1 right."""
    _, side, front = LEGS[leg]
    fb = 1 if front else -1
    hip = np.array([fb * HIP_OFFSET[0], side * HIP_OFFSET[1], HIP_OFFSET[2]])
    knee = np.array([fb * KNEE_OFFSET[0], side * KNEE_OFFSET[1], KNEE_OFFSET[2]])
    return fb, side, hip, knee, np.array(PAW_OFFSET[front])


def _rot_y(angle: float, v: np.ndarray) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([c * v[0] + s * v[2], v[1], -s * v[0] + c * v[2]])


def _rot_x(angle: float, v: np.ndarray) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([v[0], c * v[1] - s * v[2], s * v[1] + c * v[2]])


def paw_position(leg: str, angles) -> np.ndarray:
    """Paw ball centre of ``leg`` ("lf", "lh", "rf", "rh") in the body frame for (J1, J2, J3).

    J1 turns about -Y (front) / +Y (hind), J2 about +X (left) / -X (right), J3 like J1."""
    fb, side, hip, knee, paw = _leg_geometry(leg)
    q1, q2, q3 = angles
    shin = knee + _rot_y(-fb * q3, paw)
    return hip + _rot_y(-fb * q1, _rot_x(side * q2, shin))


def leg_angles(leg: str, position) -> np.ndarray:
    """(J1, J2, J3) that put the paw ball centre of ``leg`` at ``position`` (body frame).

    Of the two knee solutions the one bent the Sony way (J3 beyond the straight leg) is
    returned. Raises ValueError when the point is out of reach."""
    fb, side, hip, knee, paw = _leg_geometry(leg)
    d = np.asarray(position, dtype=float) - hip
    unreachable = ValueError(f"{leg}: paw position ({', '.join(f'{v:.4f}' for v in d + hip)}) m is out of reach")
    # J3 sets the J2-to-paw distance: |knee + Ry(phi) paw| = |d|, phi = -fb * J3.
    a = knee[0] * paw[0] + knee[2] * paw[2]
    b = knee[0] * paw[2] - knee[2] * paw[0]
    c = (d @ d - knee @ knee - paw @ paw) / 2
    if abs(c) > math.hypot(a, b):
        raise unreachable
    alpha = math.atan2(b, a)
    phi = alpha - fb * math.acos(c / math.hypot(a, b))
    q3 = -fb * phi
    shin = knee + _rot_y(phi, paw)
    # J2 sets the lateral offset: Rx(side * J2) shin has y = d_y.
    r, gamma = math.hypot(shin[1], shin[2]), math.atan2(shin[2], shin[1])
    if abs(d[1]) > r:
        raise unreachable
    a2 = -gamma - math.acos(d[1] / r)
    w = _rot_x(a2, shin)
    # J1 turns the leg in the sagittal plane onto d.
    theta = math.atan2(d[0], d[2]) - math.atan2(w[0], w[2])
    q1 = -fb * math.remainder(theta, 2 * math.pi)
    return np.array([q1, side * a2, q3])


# ----------------------------------------------------------------------------- poses

LOCATORS = tuple(j.locator for j in JOINTS)  # posture changes drive all 20 joints, as Sony's do
_LEG_INDEX = {leg: [JOINT_INDEX[f"{leg}_j{i}"] for i in (1, 2, 3)] for leg in LEGS}
# Gaits drive the 12 leg joints only, so a controller can move the head while walking.
_GAIT_COLUMNS = sorted(i for columns in _LEG_INDEX.values() for i in columns)
GAIT_LOCATORS = tuple(JOINTS[i].locator for i in _GAIT_COLUMNS)


def pose_vector(pose: dict[str, float]) -> np.ndarray:
    """Joint angles (rad) in ``ers7.JOINTS`` order from a {name: degrees} pose; unlisted
    joints take their table default."""
    return np.radians([pose.get(j.name, j.default_deg) for j in JOINTS])


def paw_pose(paws: dict[str, tuple[float, float, float]], base: np.ndarray) -> np.ndarray:
    """``base`` (rad, ``ers7.JOINTS`` order) with each leg in ``paws`` set by inverse kinematics."""
    pose = np.array(base, dtype=float)
    for leg, position in paws.items():
        pose[_LEG_INDEX[leg]] = leg_angles(leg, position)
    return pose


def mirrored(front, hind) -> dict[str, tuple[float, float, float]]:
    """Paw positions of all four legs from the left front and left hind ones."""
    paws = {}
    for leg, (_, side, is_front) in LEGS.items():
        x, y, z = front if is_front else hind
        paws[leg] = (x, side * y, z)
    return paws


STAND_POSE, SIT_POSE = pose_vector(POSES["stand"]), pose_vector(POSES["sit"])
# Sit -> stand passes through a crouch: chest lowered onto folded front legs while the hind
# legs stay folded, which brings the centre of mass ahead of the hind paws before they push.
# (Unfolding straight from sit pushes the rump back and the robot rolls over backwards.)
CROUCH_POSE = paw_pose(mirrored((0.085, 0.07, -0.095), (-0.03, 0.07, -0.085)), STAND_POSE)


@dataclass(frozen=True)
class Gait:
    """A trot: legs ``lf``/``rh`` and ``rf``/``lh`` half a period apart. In stance (``duty`` of
    the period) a paw sweeps backward and turns about the body origin at constant speed; in
    swing it returns on a cosine ease with a sine lift. Paw positions: body frame, metres."""

    step_length: float = 0.0  # m the body advances per period
    turn_rate: float = 0.0  # deg/s, + = to the left
    step_height: float = 0.012  # m
    period_ms: int = 320  # multiple of 16 ms
    duty: float = 0.5  # stance fraction of the period
    # Left paws; the diagonals cross 17.5 mm ahead of the origin, under the centre of mass.
    front: tuple[float, float, float] = (0.09, 0.075, -0.115)
    hind: tuple[float, float, float] = (-0.055, 0.075, -0.12)


_PHASE = {"lf": 0.0, "rh": 0.0, "rf": 0.5, "lh": 0.5}


def paw_path(gait: Gait, leg: str, t: float) -> np.ndarray:
    """Paw position of ``leg`` at time ``t`` (fraction of the period), body frame."""
    phase = (t + _PHASE[leg]) % 1.0
    if phase < gait.duty:  # stance: u from +1/2 to -1/2
        u, lift = 0.5 - phase / gait.duty, 0.0
    else:  # swing: back to +1/2
        s = (phase - gait.duty) / (1 - gait.duty)
        u, lift = -0.5 + (1 - math.cos(math.pi * s)) / 2, gait.step_height * math.sin(math.pi * s)
    # A stance lasts duty * period and carries the body the whole way in that time.
    u *= gait.duty
    turn = u * math.radians(gait.turn_rate) * gait.period_ms / 1000
    x, y, z = mirrored(gait.front, gait.hind)[leg]
    c, s = math.cos(turn), math.sin(turn)
    return np.array([c * x - s * y + u * gait.step_length, s * x + c * y, z + lift])


def gait_poses(gait: Gait) -> np.ndarray:
    """One period of ``gait`` as (N + 1, 20) poses (rad) at 16 ms keyframes, the last equal to
    the first; head and tail hold the stand pose."""
    if gait.period_ms % KEYFRAME_MS:
        raise ValueError(f"period {gait.period_ms} ms is not a multiple of {KEYFRAME_MS} ms")
    n = gait.period_ms // KEYFRAME_MS
    return np.array([paw_pose({leg: paw_path(gait, leg, k / n) for leg in LEGS}, STAND_POSE) for k in range(n + 1)])


def transition_poses(poses, segments: int) -> np.ndarray:
    """From each pose of ``poses`` to the next in ``segments`` steps on a cosine ease (at rest
    at every pose); (len(poses) - 1) * segments + 1 poses."""
    s = (1 - np.cos(np.linspace(0, math.pi, segments + 1)[1:])) / 2
    path = [np.asarray(poses[0], dtype=float)]
    for a, b in zip(poses[:-1], poses[1:]):
        path += [a + k * (b - a) for k in s]
    return np.array(path)


# ----------------------------------------------------------------------------- motion files

WALK = Gait(step_length=0.045)
TURN = Gait(turn_rate=30.0)
TRANSITION_SEGMENT_MS = 160  # numInterpolate 9: OPEN-R interpolates linearly in between


def _gait_motion(name: str, gait: Gait) -> Motion:
    return Motion.from_poses(name, GAIT_LOCATORS, gait_poses(gait)[:, _GAIT_COLUMNS], KEYFRAME_MS)


def motions() -> dict[str, Motion]:
    """File name -> motion, for every motion aibo-sim ships."""
    sit = transition_poses([STAND_POSE, SIT_POSE], 10)
    stand = transition_poses([SIT_POSE, CROUCH_POSE, STAND_POSE], 5)
    return {
        "WALKFWD.MTN": _gait_motion("a_walk#walk_fwd", WALK),
        "TURNL.MTN": _gait_motion("a_walk#walk_turn_l", TURN),
        "TURNR.MTN": _gait_motion("a_walk#walk_turn_r", replace(TURN, turn_rate=-TURN.turn_rate)),
        "SIT.MTN": Motion.from_poses("a_stand#sit_sitdown", LOCATORS, sit, TRANSITION_SEGMENT_MS),
        "STAND.MTN": Motion.from_poses("a_sit#stand_standup", LOCATORS, stand, TRANSITION_SEGMENT_MS),
    }


def generate_motion_files(directory: str | os.PathLike) -> list[Path]:
    """Write every motion of :func:`motions` into ``directory``; returns the paths."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, motion in motions().items():
        write_mtn(motion, directory / name)
        paths.append(directory / name)
    return paths


# ----------------------------------------------------------------------------- playback


def _openr_frames(player: MotionPlayer, repeat: int):
    """Targets (rad) for each 8 ms frame. A loop does not send the last keyframe, as MTN.cc
    does not; the very end does, so the motion ends on it."""
    for r in range(repeat):
        for i in range(player.num_frames if r == repeat - 1 else player.num_frames - 1):
            yield player.frame(i) / 1e6


def _webots_frames(player: MotionPlayer, repeat: int, step_ms: int):
    """Targets (rad) or None for each 8 ms frame: ``mtn_step(step_ms)`` every control step,
    ``mtn_play`` again once over."""
    for _ in range(repeat):
        player.play()
        while not player.is_over:
            commands = player.step(step_ms)
            yield None if commands is None else np.array([commands[loc] for loc in player.motion.locators])
            yield from [None] * (step_ms // FRAME_MS - 1)


def kinematic_speed(motion: Motion) -> float:
    """Forward speed (m/s, + = forward) at which a gait's paws push the body if they do not slip:
    while a paw is in its stance (its lowest quarter of height), minus its ball's body-frame x
    velocity, plus its rolling (the ball's radius times the lower leg's pitch rate, J1 + J3;
    J2's tilt and the body's pitch left out), averaged over the legs. It reads a gait, whose
    stances are its lowest paws; of a posture change (sit, stand) it says nothing."""
    keyframes = motion.positions_rad()
    if len(keyframes) < 2:
        return 0.0
    names = [JOINT_BY_LOCATOR[loc].name for loc in motion.locators]
    dt = motion.frame_time_ms * (motion.interpolate + 1) / 1000  # each segment's duration
    speeds = []
    for leg in LEGS:
        if not all(f"{leg}_j{i}" in names for i in (1, 2, 3)):
            continue
        columns = [names.index(f"{leg}_j{i}") for i in (1, 2, 3)]
        paws = np.array([paw_position(leg, angles) for angles in keyframes[:, columns]])
        front = 1 if LEGS[leg][2] else -1
        pitch = -front * (keyframes[:, columns[0]] + keyframes[:, columns[2]])  # the lower leg's, about +Y
        z = paws[:, 2]
        low = z <= z.min() + 0.25 * (z.max() - z.min())
        stance = low[:-1] & low[1:]  # segments that start and end in stance
        if stance.any():
            pushed = -np.diff(paws[:, 0]) + PAW_RADIUS * np.diff(pitch)
            speeds.append(np.sum(pushed[stance]) / np.sum(dt[stance]))
    return float(np.mean(speeds)) if speeds else 0.0


class GaitMeter:
    """Frame by frame: the peak speed of the leg joints and the ground contact force of the legs,
    in total and on the paws (``paw_share``: the share of the stance the paws carry)."""

    def __init__(self, sim: Simulation):
        m, p = sim.model, sim.prefix  # this robot's (a match's robot 2 was measured as robot 1)
        self._dofs = [m.joint(p + j.name).dofadr[0] for j in JOINTS if j.name[:2] in LEGS]
        robot = m.body_rootid[m.geom_bodyid] == m.body(p + "body").id
        leg_bodies = [m.body(f"{p}{leg}_j{i}").id for leg in LEGS for i in (1, 2, 3)]
        self._leg = np.isin(m.geom_bodyid, leg_bodies)
        self._paw = np.zeros(m.ngeom, dtype=bool)
        self._paw[[m.geom(f"{p}{leg}_paw").id for leg in LEGS]] = True
        self._robot = robot
        self._force = np.zeros(6)
        self.peak_speed = self.leg_force = self.paw_force = 0.0

    def __call__(self, sim: Simulation) -> None:
        m, d = sim.model, sim.data
        self.peak_speed = max(self.peak_speed, float(np.abs(d.qvel[self._dofs]).max()))
        for i, (g1, g2) in enumerate(d.contact.geom[: d.ncon]):
            leg = g1 if self._leg[g1] and not self._robot[g2] else g2 if self._leg[g2] and not self._robot[g1] else -1
            if leg >= 0:
                mujoco.mj_contactForce(m, d, i, self._force)
                self.leg_force += self._force[0]
                self.paw_force += self._force[0] if self._paw[leg] else 0.0

    @property
    def paw_share(self) -> float | None:
        """The share of the legs' ground contact force the paws carried; None before any contact."""
        return self.paw_force / self.leg_force if self.leg_force > 0 else None


def start_keyframe(motion: Motion, model: mujoco.MjModel) -> str:
    """The keyframe a new robot plays ``motion`` from: its name's start posture where ``model``
    has that keyframe (``sit`` for Sony's ``a_sit#...`` dances), else ``stand``."""
    posture = motion.name[2:].split("#", 1)[0] if motion.name.startswith("a_") and "#" in motion.name else ""
    if posture in START_KEYFRAMES and mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, posture) >= 0:
        return posture
    return "stand"


def play_motion(
    motion_or_path,
    repeat: int = 1,
    sim: Simulation | None = None,
    mode: str = "openr",
    step_ms: int = 16,
    *,
    world: WorldConfig | None = None,
    camera: CameraConfig | None = None,
) -> dict:
    """Play a motion (or MTN file) ``repeat`` times on ``sim`` (default: a new robot in ``world``'s
    scene, the RoboCup field by default, with its seed and ``camera``, which ``mtn play`` takes
    like every ``aibo-sim`` command, in the keyframe its name starts from: ``start_keyframe``)
    and say where it went. ``world.pose`` (x, y in
    metres, yaw in degrees) places the robot first; ``world.ball`` (x, y) places the ball, and
    without it a new robot's scene has no ball (a walk measured into a ball measures the ball).

    The set-points first blend from their current values to the motion's first keyframe over
    ``BLEND_MS`` when they differ. ``mode="openr"``: every 8 ms frame the player's targets are
    written straight to the set-points, as OPEN-R joint command frames. ``mode="webots"``:
    Webots' ``mtn_step(step_ms)`` per control step, commands through ``servos.set_target``
    (velocity limits apply). Playback stops if the robot falls. Displacement, heading change
    and duration are the motion's, from its first keyframe on (after the blend): the
    displacement in the heading there (x forward, y left), the heading change unwrapped (+ = left).
    Also reported: the distance the paws' kinematics give (``kinematic_distance_m``), the peak
    leg joint speed and the share of the legs' ground contact force that the paws carry."""
    if isinstance(repeat, bool) or not isinstance(repeat, numbers.Integral) or not 1 <= repeat <= MAX_MAGNITUDE:
        raise ParameterError.at("repeat", repeat, f"must be a whole number from 1 to {MAX_MAGNITUDE:.0f}")
    motion = motion_or_path if isinstance(motion_or_path, Motion) else read_mtn(motion_or_path)
    player = MotionPlayer(motion, mode)
    if step_ms <= 0 or step_ms % FRAME_MS:
        raise ValueError(f"step_ms must be a positive multiple of {FRAME_MS} ms")
    unknown = [loc for loc in motion.locators if loc not in JOINT_BY_LOCATOR]
    if unknown:
        other = another_robot(motion)
        if other:
            count = f"{len(unknown)} of its {len(motion.locators)} locators, such as {printable(unknown[0])}"
            raise MtnError(motion.source, None, f"{other}: no ERS-7 joint for {count}")
        raise MtnError(motion.source, None, f"no joint for locator(s) {', '.join(map(printable, unknown))}")
    world = world or WorldConfig()
    if sim is not None:
        if world.scene is not None:
            raise ValueError("play_motion: give a scene or a simulation, not both")
        place(sim, world.pose, world.ball)
        return _play(sim, motion, player, repeat, mode, step_ms)
    sim = Simulation(
        world.scene, seed=world.seed, camera=camera, ball=world.ball is not None, ball_type=world.ball_type
    )
    try:
        keyframe = start_keyframe(motion, sim.model)
        if keyframe != sim.keyframe:
            sim.reset(keyframe=keyframe)
        place(sim, world.pose, world.ball)
        return {**_play(sim, motion, player, repeat, mode, step_ms), "start_keyframe": keyframe}
    finally:
        sim.close()


def _play(sim: Simulation, motion: Motion, player: MotionPlayer, repeat: int, mode: str, step_ms: int) -> dict:
    """``play_motion`` on ``sim``, its arguments checked."""
    idx = joint_indices(motion.locators)

    start = sim.servos.command[idx].copy()
    first = motion.positions_rad()[0]
    n = BLEND_MS // FRAME_MS if np.abs(first - start).max() > 1e-3 else 0
    blend = (start + (first - start) * (1 - math.cos(math.pi * i / n)) / 2 for i in range(1, n + 1))
    frames = _openr_frames(player, repeat) if mode == "openr" else _webots_frames(player, repeat, step_ms)

    def command(targets) -> None:
        if mode == "openr":
            sim.servos.target[idx] = sim.servos.command[idx] = targets
        elif targets is not None:
            sim.servos.set_target(idx, targets)

    fell = False
    for targets in blend:
        command(targets)
        sim.step_frame()
        if fell := sim.fallen():
            break
    position, yaw, _ = sim.body_pose()
    start_frame, yaw0, turned = sim.frame, yaw, 0.0
    meter = GaitMeter(sim)
    for targets in () if fell else frames:
        command(targets)
        sim.step_frame()
        meter(sim)
        new_yaw = sim.body_pose()[1]
        turned += math.remainder(new_yaw - yaw, 2 * math.pi)
        yaw = new_yaw
        if fell := sim.fallen():
            break
    end, yaw_end, _ = sim.body_pose()
    dx, dy = end[:2] - position[:2]
    c, s = math.cos(yaw0), math.sin(yaw0)
    forward, left = float(c * dx + s * dy), float(-s * dx + c * dy)
    played_s = (sim.frame - start_frame) * FRAME_MS / 1000
    return {
        "displacement_m": [forward, left],
        "distance_m": math.hypot(forward, left),
        "heading_change_deg": math.degrees(turned),
        "fell": fell,
        "duration_s": played_s,
        "kinematic_distance_m": kinematic_speed(motion) * min(repeat * motion.length_ms / 1000, played_s),  # to a fall
        "peak_leg_joint_speed_rad_s": meter.peak_speed,
        "paw_stance_share": meter.paw_share,
        # On the field, as ``--pose`` takes them: x, y (m), yaw (deg).
        "start_pose": [float(position[0]), float(position[1]), math.degrees(yaw0)],
        "end_pose": [float(end[0]), float(end[1]), math.degrees(yaw_end)],
    }


def main(argv=None) -> None:
    """Write the bundled motion files into the models folder's ``motions/``."""
    folder = models_dir() / "motions"
    argparse.ArgumentParser(
        prog="python -m aibo_sim.motions",
        description=f"Write the bundled motion files (WALKFWD.MTN, STAND.MTN, ...) into {folder}, replacing them.",
    ).parse_args(argv)
    for path in generate_motion_files(folder):
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
