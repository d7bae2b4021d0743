"""Motion files authored by aibo-sim: leg kinematics, a trot generator, sit/stand transitions.

The MTN files in ``models/motions/`` are what :func:`generate_motion_files` writes; a test
checks that they are up to date. Regenerate with ``python -m aibo_sim.motions``.

Leg geometry is the model's (``mjcf.py``, spec §A.2), in the body frame: X forward, Y left,
Z up, origin midway between the four J1 axes. Angles are radians with Sony's signs.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .ers7 import JOINT_BY_LOCATOR, JOINT_BY_NAME, JOINTS, LEGS
from .mjcf import PAW_OFFSET, POSES
from .mtn import Motion, MotionPlayer, read_mtn, write_mtn
from .sim import FRAME_MS, Simulation, models_dir

HIP = (0.065, 0.0625, 0.0)  # J1 axis from the body origin (x: front +, hind -; y: left +)
KNEE = (0.009, 0.0047, -0.0695)  # J3 axis from J1/J2 at zero (x: front +, hind -; y: outward)
KEYFRAME_MS = 16  # Sony's walks: pre-sampled 16 ms keyframes, numInterpolate 0
BLEND_MS = 512  # play_motion's blend from the current pose to a motion's first keyframe


# ----------------------------------------------------------------------------- kinematics


def _leg_geometry(leg: str) -> tuple[int, int, np.ndarray, np.ndarray, np.ndarray]:
    """(fb, side, hip, knee, paw): fb = +1 front / -1 hind, side = +1 left / -1 right."""
    _, side, front = LEGS[leg]
    fb = 1 if front else -1
    hip = np.array([fb * HIP[0], side * HIP[1], HIP[2]])
    knee = np.array([fb * KNEE[0], side * KNEE[1], KNEE[2]])
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
    # J3 sets the J2-to-paw distance: |knee + Ry(phi) paw| = |d|, phi = -fb * J3.
    a = knee[0] * paw[0] + knee[2] * paw[2]
    b = knee[0] * paw[2] - knee[2] * paw[0]
    c = (d @ d - knee @ knee - paw @ paw) / 2
    if abs(c) > math.hypot(a, b):
        raise ValueError(f"{leg}: paw position {tuple(position)} out of reach")
    alpha = math.atan2(b, a)
    phi = alpha - fb * math.acos(c / math.hypot(a, b))
    q3 = -fb * phi
    shin = knee + _rot_y(phi, paw)
    # J2 sets the lateral offset: Rx(side * J2) shin has y = d_y.
    r, gamma = math.hypot(shin[1], shin[2]), math.atan2(shin[2], shin[1])
    if abs(d[1]) > r:
        raise ValueError(f"{leg}: paw position {tuple(position)} out of reach")
    a2 = -gamma - math.acos(d[1] / r)
    w = _rot_x(a2, shin)
    # J1 turns the leg in the sagittal plane onto d.
    theta = math.atan2(d[0], d[2]) - math.atan2(w[0], w[2])
    q1 = -fb * math.remainder(theta, 2 * math.pi)
    return np.array([q1, side * a2, q3])


# ----------------------------------------------------------------------------- poses


def pose_vector(pose: dict[str, float]) -> np.ndarray:
    """Joint angles (rad) in ``ers7.JOINTS`` order from a {name: degrees} pose; unlisted
    joints take their table default."""
    return np.radians([pose.get(j.name, j.default_deg) for j in JOINTS])


_LEG_INDEX = {leg: [JOINTS.index(JOINT_BY_NAME[f"{leg}_j{i}"]) for i in (1, 2, 3)] for leg in LEGS}


@dataclass(frozen=True)
class Gait:
    """A periodic gait. Paws move on a box-with-rounded-top path: in stance (``duty`` of the
    period) a paw sweeps backward and turns about the body origin at constant speed, in swing
    it returns with a sine lift. Legs ``lf``/``rh`` and ``rf``/``lh`` are half a period apart
    (a trot). Nominal paw positions are in the body frame, metres."""

    step_length: float = 0.0  # m the body advances per period
    turn_rate: float = 0.0  # deg/s, + = to the left
    step_height: float = 0.02  # m
    period_ms: int = 480  # multiple of 16 ms
    duty: float = 0.5  # stance fraction of the period
    front: tuple[float, float, float] = (0.075, 0.075, -0.115)  # left front paw
    hind: tuple[float, float, float] = (-0.075, 0.075, -0.12)  # left hind paw


_PHASE = {"lf": 0.0, "rh": 0.0, "rf": 0.5, "lh": 0.5}


def _paw_path(gait: Gait, leg: str, t: float) -> np.ndarray:
    """Paw position of ``leg`` at time fraction ``t`` of the period."""
    _, side, front = LEGS[leg]
    x0, y0, z0 = gait.front if front else gait.hind
    phase = (t + _PHASE[leg]) % 1.0
    if phase < gait.duty:  # stance: u from +1/2 to -1/2
        u, lift = 0.5 - phase / gait.duty, 0.0
    else:  # swing: back to +1/2 with a smooth start and stop
        s = (phase - gait.duty) / (1 - gait.duty)
        u, lift = -0.5 + (1 - math.cos(math.pi * s)) / 2, gait.step_height * math.sin(math.pi * s)
    # In stance the paw sweeps step_length * duty: the body advances that much per half
    # period while one diagonal pair carries it, a whole step_length per period.
    u *= gait.duty
    turn = math.radians(gait.turn_rate) * gait.period_ms / 1000
    c, s_ = math.cos(u * turn), math.sin(u * turn)
    y0 *= side
    return np.array([c * x0 - s_ * y0 + u * gait.step_length, s_ * x0 + c * y0, z0 + lift])


def gait_poses(gait: Gait) -> np.ndarray:
    """One period of ``gait`` as (N + 1, 20) joint poses at 16 ms keyframes, the last equal to
    the first; head and tail hold the stand pose."""
    if gait.period_ms % KEYFRAME_MS:
        raise ValueError(f"period {gait.period_ms} ms is not a multiple of {KEYFRAME_MS} ms")
    n = gait.period_ms // KEYFRAME_MS
    poses = np.tile(pose_vector(POSES["stand"]), (n + 1, 1))
    for k in range(n + 1):
        for leg, idx in _LEG_INDEX.items():
            poses[k, idx] = leg_angles(leg, _paw_path(gait, leg, (k % n) / n))
    return poses


def transition_poses(start: dict[str, float], end: dict[str, float], keyframes: int) -> np.ndarray:
    """``keyframes`` poses from ``start`` to ``end`` (degree dicts) on a cosine ease."""
    a, b = pose_vector(start), pose_vector(end)
    s = (1 - np.cos(np.linspace(0, math.pi, keyframes))) / 2
    return a + s[:, None] * (b - a)


# ----------------------------------------------------------------------------- motion files

WALK = Gait(step_length=0.06)
TURN = Gait(turn_rate=30.0)
LOCATORS = tuple(j.locator for j in JOINTS)


def motions() -> dict[str, Motion]:
    """File name -> motion, for every motion aibo-sim ships."""
    ease = 11  # keyframes; 10 segments of 160 ms (numInterpolate 9) = 1.6 s
    return {
        "WALKFWD.MTN": Motion.from_poses("a_walk#walk_fwd", LOCATORS, gait_poses(WALK), KEYFRAME_MS),
        "TURNL.MTN": Motion.from_poses("a_walk#walk_turn_l", LOCATORS, gait_poses(TURN), KEYFRAME_MS),
        "SIT.MTN": Motion.from_poses("a_stand#sit_sitdown", LOCATORS, transition_poses(POSES["stand"], POSES["sit"], ease), 160),
        "STAND.MTN": Motion.from_poses("a_sit#stand_standup", LOCATORS, transition_poses(POSES["sit"], POSES["stand"], ease), 160),
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


def play_motion(motion_or_path, repeat: int = 1, sim: Simulation | None = None, mode: str = "openr", step_ms: int = 16) -> dict:
    """Play a motion ``repeat`` times on ``sim`` (default: a new robot standing on the field).

    The servo set-points first blend from their current values to the motion's first
    keyframe over ``BLEND_MS`` when they differ. ``mode="openr"``: every 8 ms frame the
    player's targets are written straight to the set-points (as OPEN-R joint command frames);
    a loop sends the last keyframe only at the very end, like ``MTN.cc``. ``mode="webots"``:
    ``mtn_step(step_ms)`` each ``step_ms`` control step, commands through
    ``servos.set_target`` (velocity limits apply), ``mtn_play`` again when over. Playback stops
    early if the robot falls. Displacement is in the start heading's frame (x forward, y left);
    the heading change is unwrapped (+ = left)."""
    motion = motion_or_path if isinstance(motion_or_path, Motion) else read_mtn(motion_or_path)
    if mode not in ("openr", "webots"):
        raise ValueError(f"mode must be 'openr' or 'webots', not {mode!r}")
    if step_ms <= 0 or step_ms % FRAME_MS:
        raise ValueError(f"step_ms must be a positive multiple of {FRAME_MS} ms")
    unknown = [loc for loc in motion.locators if loc not in JOINT_BY_LOCATOR]
    if unknown:
        raise ValueError(f"{motion.name}: locators without a joint: {', '.join(unknown)}")
    sim = sim or Simulation()
    idx = np.array([JOINTS.index(JOINT_BY_LOCATOR[loc]) for loc in motion.locators])
    position, yaw0, _ = sim.body_pose()
    start_frame, state = sim.frame, {"yaw": yaw0, "turned": 0.0, "fell": False}

    def advance() -> bool:
        sim.step_frame()
        yaw = sim.body_pose()[1]
        state["turned"] += math.remainder(yaw - state["yaw"], 2 * math.pi)
        state["yaw"] = yaw
        state["fell"] = sim.fallen()
        return not state["fell"]

    def command(targets: np.ndarray) -> None:
        if mode == "openr":
            sim.servos.target[idx] = sim.servos.command[idx] = targets
        else:
            sim.servos.set_target(idx, targets)

    first = motion.positions_rad()[0]
    current = sim.servos.command[idx].copy()
    ok = True
    if np.abs(first - current).max() > 1e-3:
        n = BLEND_MS // FRAME_MS
        for i in range(1, n + 1):
            command(current + (first - current) * (1 - math.cos(math.pi * i / n)) / 2)
            if not (ok := advance()):
                break
    if mode == "openr":
        player = MotionPlayer(motion)
        for r in range(repeat if ok else 0):
            frames = player.num_frames if r == repeat - 1 else player.num_frames - 1
            for i in range(frames):
                command(player.frame(i) / 1e6)
                if not (ok := advance()):
                    break
            if not ok:
                break
    else:
        player = MotionPlayer(motion, "webots")
        for r in range(repeat if ok else 0):
            player.play()
            while ok and not player.is_over:
                commands = player.step(step_ms)
                if commands:
                    command(np.array([commands[loc] for loc in motion.locators]))
                for _ in range(step_ms // FRAME_MS):
                    if not (ok := advance()):
                        break
            if not ok:
                break
    dx, dy = sim.body_pose()[0][:2] - position[:2]
    c, s = math.cos(yaw0), math.sin(yaw0)
    forward, left = c * dx + s * dy, -s * dx + c * dy
    return {
        "displacement_m": [forward, left],
        "distance_m": math.hypot(forward, left),
        "heading_change_deg": math.degrees(state["turned"]),
        "fell": state["fell"],
        "duration_s": (sim.frame - start_frame) * FRAME_MS / 1000,
    }


def main() -> None:
    for path in generate_motion_files(models_dir() / "motions"):
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
