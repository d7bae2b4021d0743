"""Generates the MJCF files in ``models/`` from the tables in ``ers7.py`` and ``field.py``.

The XML files are committed so that MuJoCo users can load them as they are; a test checks
that they equal what this module generates. Regenerate with ``python -m aibo_sim.mjcf``.
"""

from __future__ import annotations

import argparse
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from xml.sax.saxutils import escape

import numpy as np

from openr_bridge import FULL_HEIGHT, FULL_WIDTH, HORIZONTAL_FOV_DEG, VERTICAL_FOV_DEG

from . import field as F
from .ers7 import (
    FACE_SPOT_PITCH,
    FACE_SPOTS,
    HEAD_CAMERA,
    JOINT_BY_NAME,
    JOINTS,
    LED_OFF_RGBA,
    LEGS,
    MAX_TORQUE,
    SENSORS,
    face_spot_geoms,
)
from .sim import models_dir

CAMERA_FOCAL = 0.00327  # m (Sony: f = 3.27 mm)
PAW_RADIUS = 0.01172  # Tekkotsu BallOfFootRadius; Webots uses 0.017 (see models/README.md)
# How far the paws sink into the carpet under the standing robot's weight (MuJoCo's soft contacts):
# the keyframes start them there, so that the contacts carry the robot from the start (a robot at
# rest reads 1 g at t = 0, not a free fall).
PAW_SINK = 0.0001
PAW_TOUCH_RADIUS = 0.015  # Webots touch sphere
SHIN_COLLISION_REACH, SHIN_COLLISION_RADIUS = 0.7, 0.0145  # shin capsule: knee to 70 % of the way to the paw
TIMESTEP = 0.002  # s: four physics steps per 8 ms OPEN-R joint frame (models/README.md, "Conventions": the timestep)
LIMIT_TIME_CONSTANT = 2 * TIMESTEP  # s: joint stops as stiff as is stable (MuJoCo's 20 ms let the tail and ears pass)

# The servos: a DC motor behind a gearbox, driven by Sony's PID through a PWM stage that
# saturates at +-255 (models/README.md, "Servos"). The position actuator is the controller: its
# stiffness follows Sony's P register (the legs' J1/J3 0x1C -> 20 N m/rad; the rest in
# proportion) and its output saturates at the stall torque. The motor's back-EMF is a passive
# damping, stall torque / no-load speed, taking Sony's recommended maximum speed as the speed
# of maximum power, half the no-load speed.
KP_PER_SONY_P = 20.0 / 0x1C  # N m/rad per unit of Sony's P gain
SERVO_ARMATURE = 0.004  # kg m^2: reflected rotor inertia of a geared servo

# Sony's stand (first keyframe of SWSDK.MTN) and sit (SITDANCE.MTN) poses, in degrees,
# with the Webots default head. Unlisted joints take their table default.
POSES = {
    "stand": {
        "neck_tilt": -30,
        "head_tilt": 15,
        "mouth": -3,
        "tail_tilt": 10,
        **{f"{leg}_j{i}": v for leg in ("lf", "rf") for i, v in zip((1, 2, 3), (-10, 0, 30))},
        **{f"{leg}_j{i}": v for leg in ("lh", "rh") for i, v in zip((1, 2, 3), (0, 0, 25))},
    },
    "sit": {
        "neck_tilt": -40,
        "head_tilt": 5,
        "mouth": -5,
        "tail_tilt": 5,
        **{f"{leg}_j{i}": v for leg in ("lf", "rf") for i, v in zip((1, 2, 3), (-25, -4, 20))},
        **{f"{leg}_j{i}": v for leg in ("lh", "rh") for i, v in zip((1, 2, 3), (-78, 20, 110))},
    },
}


def _fmt(value) -> str:
    if isinstance(value, str):
        return value
    values = np.atleast_1d(np.asarray(value, dtype=float))
    return " ".join(f"{v:.9g}" if abs(v) > 1e-12 else "0" for v in values)


def E(tag: str, *children: ET.Element, **attrs) -> ET.Element:
    """An XML element; attribute values may be numbers or sequences of numbers."""
    element = ET.Element(tag, {k.rstrip("_"): _fmt(v) for k, v in attrs.items() if v is not None})
    element.extend(children)
    return element


def box_inertia(mass: float, size: tuple[float, float, float]) -> list[float]:
    """Diagonal inertia of a solid box of full edge lengths ``size``."""
    x, y, z = size
    return [mass * (y * y + z * z) / 12, mass * (x * x + z * z) / 12, mass * (x * x + y * y) / 12]


def inertial(mass: float, pos, size) -> ET.Element:
    """The ``<inertial>`` of a solid box of ``mass`` and full edge lengths ``size`` centred at ``pos``."""
    return E("inertial", pos=pos, mass=mass, diaginertia=box_inertia(mass, size))


def servo_stiffness(j) -> float:
    """Position gain (N m/rad) of joint ``j``'s servo: Sony's P register, scaled."""
    return KP_PER_SONY_P * j.gains[0]


def motor_damping(j) -> float:
    """Back-EMF damping (N m s/rad) of joint ``j``'s motor: stall torque / no-load speed."""
    return MAX_TORQUE / (2 * j.max_speed)


def joint(name: str, axis) -> ET.Element:
    j = JOINT_BY_NAME[name]
    return E("joint", name=name, axis=axis, range=j.range, damping=motor_damping(j))


def visual(**attrs) -> ET.Element:
    return E("geom", **{"class_": "visual", **attrs})


def hidden_visual(**attrs) -> ET.Element:
    """A visual geom the head camera can never see (behind its lens): group 1, see Renderer."""
    return E("geom", **{"class_": "behind_camera", **attrs})


def collision(**attrs) -> ET.Element:
    return E("geom", **{"class_": "collision", **attrs})


def led(name: str, **attrs) -> ET.Element:
    return E("geom", name=name, class_="led", **attrs)


def touch_site(name: str, pos, radius: float) -> ET.Element:
    return E("site", name=name, class_="touch", pos=pos, size=radius)


# ----------------------------------------------------------------------------- robot


def _defaults() -> ET.Element:
    return E(
        "default",
        E(
            "default",
            E("joint", armature=SERVO_ARMATURE, solreflimit=(LIMIT_TIME_CONSTANT, 1)),
            E("position", inheritrange=1, forcerange=(-MAX_TORQUE, MAX_TORQUE)),
            E("site", group=4, rgba=(0.9, 0.2, 0.2, 0.4)),
            E(
                "default",
                E("geom", group=2, contype=0, conaffinity=0, density=0, material="shell"),
                E("default", E("geom", group=1), class_="behind_camera"),
                class_="visual",
            ),
            E(
                "default",
                E(
                    "geom",
                    group=3,
                    contype=2,
                    conaffinity=1,
                    density=0,
                    friction=(0.99, 0.005, 0.0001),
                    rgba=(0.5, 0.5, 0.9, 0.4),
                ),
                E("default", E("geom", type="sphere", size=PAW_RADIUS, condim=3, priority=1), class_="paw"),
                class_="collision",
            ),
            E(
                "default",
                E("geom", type="sphere", size=0.0025, group=1, contype=0, conaffinity=0, density=0, rgba=LED_OFF_RGBA),
                class_="led",
            ),
            E("default", E("site", type="sphere", group=5), class_="touch"),
            class_="ers7",
        ),
    )


def _assets() -> ET.Element:
    materials = {
        "shell": dict(rgba=(0.93, 0.93, 0.91, 1), specular=0.4, shininess=0.5),
        "visor": dict(rgba=(0.04, 0.04, 0.05, 1), specular=0.9, shininess=0.9, reflectance=0.1),
        "dark": dict(rgba=(0.22, 0.22, 0.24, 1), specular=0.3),
        "paw": dict(rgba=(0.35, 0.35, 0.37, 1), specular=0.2),
        "lens": dict(rgba=(0.1, 0.1, 0.15, 1), specular=1.0, shininess=1.0),
    }
    return E("asset", *(E("material", name=n, **a) for n, a in materials.items()))


def _camera() -> ET.Element:
    # Both Sony fields of view hold exactly: sensor size = 2 f tan(fov / 2) on each axis.
    sensor = [2 * CAMERA_FOCAL * math.tan(math.radians(f) / 2) for f in (HORIZONTAL_FOV_DEG, VERTICAL_FOV_DEG)]
    return E(
        "camera",
        name=HEAD_CAMERA,
        pos=(0.08106, 0, -0.0146),
        xyaxes=(0, -1, 0, 0, 0, 1),
        focal=(CAMERA_FOCAL, CAMERA_FOCAL),
        sensorsize=sensor,
        resolution=(FULL_WIDTH, FULL_HEIGHT),
    )


VISOR_POS, VISOR_SIZE = (0.046, 0.0, 0.002), (0.03, 0.03, 0.022)  # the face panel, an ellipsoid
FACE_SPOTS_Z = 0.008  # the middle of the face lights' grid, in the head's frame (4 mm clear of the lens)
FACE_SPOT_RADIUS = 0.0018


def _face_spots() -> list[ET.Element]:
    """The face lights' spots (``ers7.FACE_SPOTS``), each a sphere centred on the visor's surface."""
    spots = []
    for spot, (across, up) in FACE_SPOTS.items():
        for geom, side in zip(face_spot_geoms(spot), (1, -1)):
            y, z = side * across * FACE_SPOT_PITCH, FACE_SPOTS_Z + up * FACE_SPOT_PITCH
            depth = 1 - (y / VISOR_SIZE[1]) ** 2 - ((z - VISOR_POS[2]) / VISOR_SIZE[2]) ** 2
            spots.append(led(geom, pos=(VISOR_POS[0] + VISOR_SIZE[0] * math.sqrt(depth), y, z), size=FACE_SPOT_RADIUS))
    return spots


def _head() -> ET.Element:
    ears = []
    for side, sign in (("l", 1), ("r", -1)):
        ears.append(
            E(
                "body",
                inertial(0.005, (0, 0, -0.015), (0.012, 0.004, 0.03)),
                joint(f"ear_{side}", (sign, 0, 0)),
                hidden_visual(type="box", size=(0.011, 0.002, 0.017), pos=(0, 0, -0.016), material="dark"),
                name=f"ear_{side}",
                pos=(-0.011, sign * 0.042, 0.0145),
            )
        )
    head_leds = [
        led("led_head_colour", pos=(0.045, 0, 0.036), size=0.004),
        led("led_head_white", pos=(0.038, 0, 0.039), size=0.003),
        led("led_mode_r", pos=(0.03, 0.012, 0.042)),
        led("led_mode_g", pos=(0.03, 0.0, 0.043)),
        led("led_mode_b", pos=(0.03, -0.012, 0.042)),
        led("led_wireless", pos=(-0.005, 0.0, 0.043)),
    ]
    mouth = E(
        "body",
        inertial(0.01, (0.015, 0, -0.006), (0.04, 0.03, 0.015)),
        joint("mouth", (0, -1, 0)),
        hidden_visual(type="ellipsoid", size=(0.022, 0.019, 0.008), pos=(0.013, 0, -0.007), material="dark"),
        collision(type="capsule", fromto=(0.0, 0, -0.007, 0.028, 0, -0.009), size=0.008),
        touch_site("touch_chin", (0.015, 0, -0.015), 0.012),
        name="mouth",
        pos=(0.04, 0, -0.0175),
    )
    return E(
        "body",
        inertial(0.18, (0.04, 0, 0), (0.1, 0.07, 0.07)),
        joint("head_tilt", (0, -1, 0)),
        hidden_visual(type="ellipsoid", size=(0.054, 0.036, 0.036), pos=(0.018, 0, 0.008)),
        hidden_visual(type="ellipsoid", size=VISOR_SIZE, pos=VISOR_POS, material="visor"),
        hidden_visual(
            type="cylinder", size=(0.0045, 0.004), pos=(0.0765, 0, -0.0146), zaxis=(1, 0, 0), material="lens"
        ),
        collision(type="sphere", size=0.033),
        # the head's ellipsoid as a capsule: it reached 1.4 cm below it, over the jaw, whose chin switch
        # then never felt a press from below (the mouth's capsule is the lowest part of the head now)
        collision(type="capsule", fromto=(-0.002, 0, 0.008, 0.038, 0, 0.008), size=0.034),
        _camera(),
        E("site", name="ir_near", pos=(0.0769, -0.00325, 0), zaxis=(1, 0, 0)),
        E("site", name="ir_far", pos=(0.0769, 0.00695, 0), zaxis=(1, 0, 0)),
        touch_site("touch_head", (0.01, 0, 0.045), 0.02),
        *_face_spots(),
        *head_leds,
        mouth,
        *ears,
        name="head",
        pos=(0, 0, 0),
    )


def _neck() -> ET.Element:
    pan = E(
        "body",
        inertial(0.010, (0, 0, 0), (0.03, 0.03, 0.03)),
        joint("head_pan", (0, 0, 1)),
        hidden_visual(type="sphere", size=0.03, material="dark"),
        _head(),
        name="head_pan_link",
        pos=(0, 0, 0.080),
    )
    return E(
        "body",
        inertial(0.015, (0, 0, 0.04), (0.023, 0.023, 0.08)),
        joint("neck_tilt", (0, -1, 0)),
        hidden_visual(type="cylinder", fromto=(0, 0, 0, 0, 0, 0.08), size=0.0117, material="dark"),
        collision(type="cylinder", fromto=(0, 0, 0, 0, 0, 0.08), size=0.0117),
        pan,
        name="neck",
        pos=(0.0675, 0, 0.0195),
    )


HIP_OFFSET = (0.065, 0.0625, 0.0)  # J1 axis from the body origin (x: front +, hind -; y: left +)
KNEE_OFFSET = (0.009, 0.0047, -0.0695)  # J3 axis from J1/J2 (x: front +, hind -; y: outward)
PAW_OFFSET = {True: (-0.0055, 0.0, -0.0658), False: (0.01409, 0.0, -0.0676)}  # from J3, at J3 = 0


def _leg(leg: str) -> ET.Element:
    _, side, front = LEGS[leg]
    fb = 1 if front else -1  # front legs: + swings forward; hind legs mirrored
    paw = np.array(PAW_OFFSET[front])
    knee = (fb * KNEE_OFFSET[0], side * KNEE_OFFSET[1], KNEE_OFFSET[2])
    shin = E(
        "body",
        inertial(0.073, 0.6 * paw, (0.035, 0.037, 0.07)),
        joint(f"{leg}_j3", (0, -fb, 0)),
        visual(type="capsule", fromto=(0, 0, 0, *(0.8 * paw)), size=0.0145),
        visual(type="sphere", pos=paw, size=PAW_RADIUS, material="paw"),
        collision(type="box", size=(0.013, 0.0165, 0.02)),
        collision(type="capsule", fromto=(0, 0, 0, *(SHIN_COLLISION_REACH * paw)), size=SHIN_COLLISION_RADIUS),
        collision(name=f"{leg}_paw", class_="paw", pos=paw),
        touch_site(f"touch_paw_{leg}", paw, PAW_TOUCH_RADIUS),
        name=f"{leg}_j3",
        pos=knee,
    )
    thigh = E(
        "body",
        inertial(0.073, (0, 0, -0.04), (0.033, 0.028, 0.065)),
        joint(f"{leg}_j2", (side, 0, 0)),
        visual(type="capsule", fromto=(0, 0, 0, *knee), size=0.017),
        collision(type="box", size=(0.0165, 0.014, 0.0325), pos=(0, 0, -0.021)),
        shin,
        name=f"{leg}_j2",
        pos=(0, 0, 0),
    )
    disc_y = side * (0.049 - HIP_OFFSET[1])
    return E(
        "body",
        inertial(0.05, (0, disc_y, 0), (0.064, 0.01, 0.064)),
        joint(f"{leg}_j1", (0, -fb, 0)),
        visual(type="sphere", size=0.024),
        collision(type="cylinder", fromto=(0, disc_y - 0.005, 0, 0, disc_y + 0.005, 0), size=0.032),
        thigh,
        name=f"{leg}_j1",
        pos=(fb * HIP_OFFSET[0], side * HIP_OFFSET[1], HIP_OFFSET[2]),
    )


def _tail() -> ET.Element:
    tail_dir = np.array([-math.cos(math.radians(20)), 0, math.sin(math.radians(20))])
    tail = E(
        "body",
        inertial(0.005, 0.03 * tail_dir, (0.06, 0.012, 0.012)),
        joint("tail_pan", (1, 0, 0)),
        hidden_visual(type="capsule", fromto=(0, 0, 0, *(0.06 * tail_dir)), size=0.006, material="dark"),
        name="tail",
        pos=(0, 0, 0),
    )
    return E(
        "body",
        E("inertial", pos=(0, 0, 0), mass=0.001, diaginertia=(1e-7, 1e-7, 1e-7)),
        joint("tail_tilt", (0, 1, 0)),
        hidden_visual(type="sphere", size=0.008, material="dark"),
        tail,
        name="tail_base",
        pos=(-0.102, 0, 0.033),
    )


def _torso() -> ET.Element:
    back_leds = [
        led(name, pos=(x, dy, 0.063), size=0.005 if "colour" in name else 0.003)
        for name, x, dy in (
            ("led_back_front_colour", 0.03, 0.0),
            ("led_back_front_white", 0.03, 0.01),
            ("led_back_middle_colour", 0.0, 0.0),
            ("led_back_middle_white", 0.0, 0.01),
            ("led_back_rear_colour", -0.03, 0.0),
            ("led_back_rear_white", -0.03, 0.01),
        )
    ]
    return E(
        "body",
        E("freejoint", name="root"),
        inertial(0.613, (0, 0, -0.02), (0.2, 0.1, 0.1)),
        visual(type="ellipsoid", size=(0.112, 0.05, 0.05), pos=(0, 0, 0.012)),
        visual(type="ellipsoid", size=(0.05, 0.045, 0.045), pos=(0.075, 0, -0.002)),
        visual(type="box", size=(0.05, 0.012, 0.003), pos=(0.0, 0, 0.0615), material="dark"),
        collision(type="capsule", fromto=(-0.05, 0, 0, 0.05, 0, 0), size=0.045),
        collision(type="sphere", size=0.064, pos=(0.058, 0, 0.005)),
        collision(type="sphere", size=0.062, pos=(-0.061, 0, 0.002)),
        E("site", name="imu", pos=(0, 0, 0)),
        E(
            "camera",
            name="tracking",
            mode="trackcom",
            pos=(-0.35, -0.55, 0.3),
            xyaxes=(0.84, -0.54, 0, 0.2, 0.31, 0.93),
        ),
        E("site", name="ir_chest", pos=(0.10864, 0, -0.00425), zaxis=(0.866025, 0, -0.5)),
        touch_site("touch_back_front", (0.035, 0, 0.06), 0.03),
        touch_site("touch_back_middle", (0.0, 0, 0.06), 0.03),
        touch_site("touch_back_rear", (-0.035, 0, 0.06), 0.03),
        *back_leds,
        _neck(),
        *(_leg(leg) for leg in LEGS),
        _tail(),
        name="body",
        pos=(0, 0, 0.16),
        childclass="ers7",
    )


def _actuators() -> ET.Element:
    return E(
        "actuator", *(E("position", name=j.name, joint=j.name, class_="ers7", kp=servo_stiffness(j)) for j in JOINTS)
    )


def _sensors() -> ET.Element:
    elements = [E("jointpos", name=j.name, joint=j.name) for j in JOINTS]
    for s in SENSORS:
        if s.kind == "distance":
            elements.append(E("rangefinder", name=s.name, site=s.name))
        elif s.kind == "touch":
            elements.append(E("touch", name=s.name, site=s.name))
        elif s.kind == "accelerometer":
            elements.append(E("accelerometer", name=s.name, site="imu"))
    return E("sensor", *elements)


def _pose_qpos(model, pose: dict[str, float]) -> np.ndarray:
    """qpos for ``pose`` with the body pitched and lifted so all four paws touch z = 0, sunk by ``PAW_SINK``."""
    import mujoco

    data = mujoco.MjData(model)
    qpos = model.qpos0.copy()
    for name, j in JOINT_BY_NAME.items():
        qpos[model.joint(name).qposadr[0]] = math.radians(pose.get(name, j.default_deg))
    paws = [model.geom(f"{leg}_paw").id for leg in LEGS]
    qpos[:3], qpos[3:7] = 0, (1, 0, 0, 0)
    data.qpos[:] = qpos
    mujoco.mj_kinematics(model, data)
    p = data.geom_xpos[paws]
    front, hind = p[[0, 2]].mean(axis=0), p[[1, 3]].mean(axis=0)
    # Rotating by q about +Y maps z to z cos q - x sin q: equal paw heights need tan q = dz / dx.
    pitch = math.atan2(front[2] - hind[2], front[0] - hind[0])  # > 0 tips the nose down
    qpos[3:7] = (math.cos(pitch / 2), 0, math.sin(pitch / 2), 0)
    data.qpos[:] = qpos
    mujoco.mj_kinematics(model, data)
    qpos[2] = PAW_RADIUS - PAW_SINK - data.geom_xpos[paws][:, 2].min()
    return qpos


def robot_xml() -> ET.Element:
    root = E(
        "mujoco",
        E("compiler", angle="radian", autolimits="true"),
        E("option", timestep=TIMESTEP, integrator="implicitfast", cone="elliptic"),
        _defaults(),
        _assets(),
        E("worldbody", _torso()),
        _actuators(),
        _sensors(),
        model="ers7",
    )
    return root


def _with_keyframes(root: ET.Element) -> ET.Element:
    import mujoco

    model = mujoco.MjModel.from_xml_string(ET.tostring(root, encoding="unicode"))
    keys = []
    for name, pose in {"home": POSES["stand"], **POSES}.items():  # home: Menagerie's name for the start pose
        qpos = _pose_qpos(model, pose)
        ctrl = [qpos[model.joint(j.name).qposadr[0]] for j in JOINTS]
        keys.append(E("key", name=name, qpos=qpos, ctrl=ctrl))
    root.append(E("keyframe", *keys))
    return root


# ----------------------------------------------------------------------------- scenes


def _line_mesh(ring_segments: int = 48) -> ET.Element:
    """All field lines as one flat mesh (one draw call instead of dozens of boxes)."""
    half, z = F.LINE_WIDTH / 2, 0.001
    vertices, faces = [], []

    def quad(corners):  # counter-clockwise seen from above: normals point up
        base = len(vertices)
        vertices.extend((x, y, z) for x, y in corners)
        faces.extend([(base, base + 1, base + 2), (base, base + 2, base + 3)])

    for x0, y0, x1, y1 in F.LINE_SEGMENTS:
        length = math.hypot(x1 - x0, y1 - y0)
        ux, uy = (x1 - x0) / length, (y1 - y0) / length
        ax, ay, bx, by = x0 - ux * half, y0 - uy * half, x1 + ux * half, y1 + uy * half
        quad(
            [
                (ax + uy * half, ay - ux * half),
                (bx + uy * half, by - ux * half),
                (bx - uy * half, by + ux * half),
                (ax - uy * half, ay + ux * half),
            ]
        )
    r = F.CENTRE_CIRCLE_RADIUS
    for i in range(ring_segments):
        a0, a1 = (2 * math.pi * k / ring_segments for k in (i, i + 1))
        quad(
            [
                ((r - half) * math.cos(a0), (r - half) * math.sin(a0)),
                ((r + half) * math.cos(a0), (r + half) * math.sin(a0)),
                ((r + half) * math.cos(a1), (r + half) * math.sin(a1)),
                ((r - half) * math.cos(a1), (r - half) * math.sin(a1)),
            ]
        )
    return E(
        "mesh", name="field_lines", vertex=np.array(vertices).ravel(), face=np.array(faces).ravel(), inertia="shell"
    )


@dataclass(frozen=True)
class StaticPart:
    """A fixed box or cylinder of a scene. Parts with the same ``mesh`` are drawn as one mesh
    geom of that name (software OpenGL pays per drawn geom; the name's prefix is its
    segmentation class); ``name`` is its collision geom (group 3), None for no collision, held
    by the static body ``body`` (default: a body of its own, of the same name)."""

    mesh: str
    material: str
    shape: str  # "box" (size: half extents) or "cylinder" (size: radius, half height)
    pos: tuple[float, float, float]
    size: tuple[float, ...]
    name: str | None = None
    body: str | None = None
    quat: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)  # its orientation (w, x, y, z), MuJoCo's


def _part_triangles(part: StaticPart, segments: int = 16) -> tuple[np.ndarray, list[tuple[int, int, int]]]:
    """Vertices and outward-facing triangles of a part, in world coordinates."""
    centre = np.array(part.pos, float)
    if part.shape == "box":
        half = np.array(part.size, float)
        vertices = half * np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
        quads = [(0, 1, 3, 2), (4, 5, 7, 6), (0, 1, 5, 4), (2, 3, 7, 6), (0, 2, 6, 4), (1, 3, 7, 5)]
    else:
        radius, half_height = part.size
        ring = [
            (radius * math.cos(a), radius * math.sin(a)) for a in np.linspace(0, 2 * math.pi, segments, endpoint=False)
        ]
        vertices = np.array(
            [(x, y, z) for z in (-half_height, half_height) for x, y in ring]
            + [(0, 0, -half_height), (0, 0, half_height)]
        )
        quads = [(i, (i + 1) % segments, segments + (i + 1) % segments, segments + i) for i in range(segments)]
        quads += [(2 * segments, i, (i + 1) % segments, 2 * segments) for i in range(segments)]
        quads += [
            (2 * segments + 1, segments + i, segments + (i + 1) % segments, 2 * segments + 1) for i in range(segments)
        ]
    import mujoco

    rotation = np.zeros(9)
    mujoco.mju_quat2Mat(rotation, np.array(part.quat, float))
    vertices = centre + vertices @ rotation.reshape(3, 3).T
    triangles = []
    for a, b, c, d in quads:
        for tri in ((a, b, c), (a, c, d)):
            if len(set(tri)) < 3:
                continue
            p0, p1, p2 = vertices[list(tri)]
            outward = np.dot(np.cross(p1 - p0, p2 - p0), (p0 + p1 + p2) / 3 - centre) > 0
            triangles.append(tri if outward else tri[::-1])
    return vertices, triangles


def static_parts(parts: list[StaticPart]) -> tuple[list[ET.Element], list[ET.Element]]:
    """Mesh assets, and the world's children: one visual mesh geom per ``mesh`` name, then the
    static bodies holding the collision geoms. (MuJoCo's broad phase sorts bounding boxes of
    bodies: with the walls, goals and beacons all in the world body, each robot body would be
    tested against all of them every step; ~10 % of a step.)"""
    meshes: dict[str, tuple[str, list, list]] = {}
    collision_geoms: dict[str, list[ET.Element]] = {}
    for part in parts:
        material, vertices, faces = meshes.setdefault(part.mesh, (part.material, [], []))
        if material != part.material:
            raise ValueError(f"mesh {part.mesh}: parts of materials {material} and {part.material}")
        part_vertices, triangles = _part_triangles(part)
        faces.extend(tuple(i + len(vertices) for i in tri) for tri in triangles)
        vertices.extend(part_vertices)
        if part.name is not None:
            collision_geoms.setdefault(part.body or part.name, []).append(
                E(
                    "geom",
                    name=part.name,
                    type=part.shape,
                    pos=part.pos,
                    size=part.size,
                    **({} if part.quat == (1.0, 0.0, 0.0, 0.0) else {"quat": part.quat}),
                    group=3,
                    rgba=(0.5, 0.5, 0.9, 0.4),
                )
            )
    assets = [
        E("mesh", name=n, vertex=np.array(v).ravel(), face=np.array(f).ravel(), inertia="shell")
        for n, (_, v, f) in meshes.items()
    ]
    visuals = [
        E("geom", name=n, type="mesh", mesh=n, material=m, contype=0, conaffinity=0) for n, (m, _, _) in meshes.items()
    ]
    bodies = [E("body", *geoms, name=body) for body, geoms in collision_geoms.items()]
    return assets, visuals + bodies


def _goal(colour: str, line_x: float) -> list[StaticPart]:
    sign = 1 if line_x > 0 else -1
    d, w, h, t = F.GOAL_DEPTH, F.GOAL_WIDTH, F.GOAL_HEIGHT, 0.01
    mesh = f"goal_{colour}"
    return [
        StaticPart(
            mesh,
            colour,
            "box",
            (line_x + sign * (d - t / 2), 0, h / 2),
            (t / 2, w / 2 + t, h / 2),
            f"{mesh}_back",
            mesh,
        ),
        *(
            StaticPart(
                mesh,
                colour,
                "box",
                (line_x + sign * d / 2, s * (w / 2 + t / 2), h / 2),
                (d / 2, t / 2, h / 2),
                f"{mesh}_{side}",
                mesh,
            )
            for side, s in (("left", 1), ("right", -1))
        ),
        StaticPart(
            mesh,
            colour,
            "box",
            (line_x + sign * (d / 2 + t / 2), 0, h + t / 2),
            (d / 2 + t / 2, w / 2 + t, t / 2),
            f"{mesh}_roof",
            mesh,
        ),
    ]


def _beacon(b: F.Beacon) -> list[StaticPart]:
    r, ph = F.BEACON_RADIUS, F.BEACON_PART_HEIGHT
    c_top = 0.30 - ph  # bottom of the coloured part; centre of the coloured part at 0.30 m
    return [
        StaticPart(f"beacon_{material}", material, "cylinder", (b.x, b.y, z), (r, half), f"{b.name}_{part}", b.name)
        for part, material, z, half in (
            ("white", "white", c_top / 2, c_top / 2),
            ("middle", b.middle, c_top + ph / 2, ph / 2),
            ("top", b.top, c_top + 1.5 * ph, ph / 2),
        )
    ]


def _hall(half_x: float, half_y: float, height: float = 4.0) -> list[StaticPart]:
    """The venue: a plain hall instead of a skybox (a textured skybox costs ~25 % of a head
    camera frame in software GL; one mesh costs almost nothing)."""
    return [
        StaticPart("hall", "hall", "box", pos, size)
        for size, pos in (
            ((half_x, 0.05, height / 2), (0, half_y, height / 2)),
            ((half_x, 0.05, height / 2), (0, -half_y, height / 2)),
            ((0.05, half_y, height / 2), (half_x, 0, height / 2)),
            ((0.05, half_y, height / 2), (-half_x, 0, height / 2)),
            ((half_x, half_y, 0.05), (0, 0, height)),
        )
    ]


HALL_MATERIAL = dict(name="hall", rgba=(0.72, 0.72, 0.70, 1), specular=0)


# The venue's light (models/README.md, "Light and colours of the default field"): tungsten-
# halogen lamps, one bank above each corner of the field aimed across it 40 deg below the horizon,
# plus the light the pale hall scatters back (MuJoCo's ambient: the headlight's, with no
# diffuse part: the robot carries no lamp). Lamps and ambient are neutral in the render; their
# colour is the scene's light_temperature_K, which the ers7 camera profile applies.
VENUE_LIGHT_TEMPERATURE_K = 3200.0  # halogen: white reads warm at FL white balance (spec section 5)
VENUE_AMBIENT = 0.63
VENUE_LAMP_DIFFUSE = 0.2  # each of the four banks
VENUE_LAMP_ELEVATION_DEG = 40.0


def _venue_lights() -> list[ET.Element]:
    """Four directional lamp banks, one from above each corner of the field towards its centre;
    the first casts the shadows (where a renderer draws them)."""
    e = math.radians(VENUE_LAMP_ELEVATION_DEG)
    lights = []
    for i, (sx, sy) in enumerate(((1, 1), (-1, 1), (-1, -1), (1, -1))):
        towards = np.array([-sx * math.cos(e) / math.sqrt(2), -sy * math.cos(e) / math.sqrt(2), -math.sin(e)])
        lights.append(
            E(
                "light",
                name=f"lamps_{i + 1}",
                type="directional",
                pos=-4.0 * towards,
                dir=towards,
                diffuse=(VENUE_LAMP_DIFFUSE,) * 3,
                specular=(0.2, 0.2, 0.2),
                castshadow="true" if i == 0 else "false",
            )
        )
    return lights


def scene_xml() -> ET.Element:
    cl, cw, h = F.CARPET_LENGTH / 2, F.CARPET_WIDTH / 2, F.WALL_HEIGHT
    walls = [
        StaticPart("wall", "wall", "box", pos, size, f"wall_{n}")
        for n, size, pos in (
            ("left", (cl + 0.02, 0.01, h / 2), (0, cw + 0.01, h / 2)),
            ("right", (cl + 0.02, 0.01, h / 2), (0, -cw - 0.01, h / 2)),
            ("skyblue", (0.01, cw, h / 2), (cl + 0.01, 0, h / 2)),
            ("yellow", (0.01, cw, h / 2), (-cl - 0.01, 0, h / 2)),
        )
    ]
    goals = [part for colour, x in F.GOALS.items() for part in _goal(colour, x)]
    beacons = [part for b in F.BEACONS for part in _beacon(b)]
    meshes, fixed = static_parts(walls + _hall(cl + 2.0, cw + 2.0) + goals + beacons)
    return E(
        "mujoco",
        E("include", file="ers7.xml"),
        E("statistic", center=(0, 0, 0.2), extent=1.5),
        E(
            "visual",
            E("headlight", diffuse=(0, 0, 0), ambient=(VENUE_AMBIENT,) * 3, specular=(0, 0, 0)),
            E("quality", shadowsize=2048),
            E("map", znear=0.002, zfar=20),
            E("global", azimuth=150, elevation=-25, offwidth=640, offheight=480),
        ),
        E("custom", E("numeric", name="light_temperature_K", data=VENUE_LIGHT_TEMPERATURE_K)),
        E(
            "asset",
            *(E("material", name=n, rgba=c, specular=F.SPECULAR.get(n, 0)) for n, c in F.COLOURS.items()),
            E("material", **HALL_MATERIAL),
            _line_mesh(),
            *meshes,
        ),
        E(
            "worldbody",
            *_venue_lights(),
            E(
                "geom",
                name="field_carpet",
                type="plane",
                size=(cl + 0.5, cw + 0.5, 1.0),
                material="carpet",
                friction=(0.9, 0.005, 0.0001),
            ),
            E("geom", name="field_lines", type="mesh", mesh="field_lines", material="line", contype=0, conaffinity=0),
            *fixed,
            E(
                "body",
                E("freejoint", name="ball"),
                E(
                    "geom",
                    name="ball",
                    type="sphere",
                    size=F.BALL_RADIUS,
                    mass=F.BALL_MASS,
                    material="orange",
                    condim=6,
                    friction=(0.7, 0.005, 0.002),
                ),
                name="ball",
                pos=(0.5, 0, F.BALL_RADIUS),
            ),
            E("camera", name="overview", pos=(-1.0, -1.4, 1.1), xyaxes=(0.8, -0.6, 0, 0.3, 0.4, 0.87)),
        ),
        model="ers7_robocup2005",
    )


# Webots' aibo_ers7.wbt world (spec E.1): a 2002-era 3.5 x 1.8 m pitch with six landmarks.
WEBOTS_LANDMARKS = (  # x, y, bottom colour, top colour
    (1.5, -1.03, "blue", "red"),
    (1.5, 1.03, "red", "blue"),
    (-1.5, 1.03, "red", "yellow"),
    (-1.5, -1.03, "yellow", "red"),
    (0.0, -1.03, "green", "red"),
    (0.0, 1.03, "red", "green"),
)
WEBOTS_COLOURS = {
    "pitch": (0.2, 0.55, 0.25, 1),
    "border": (0.15, 0.5, 0.2, 1),
    "white": (0.95, 0.95, 0.95, 1),
    "blue": (0.1, 0.3, 0.9, 1),
    "yellow": (0.95, 0.85, 0.1, 1),
    "green": (0.1, 0.7, 0.2, 1),
    "red": (0.9, 0.1, 0.1, 1),
    "pink": (1.0, 0.07, 0.40, 1),
}


def axis_angle_quat(x: float, y: float, z: float, angle: float) -> tuple[float, float, float, float]:
    """The unit quaternion (w, x, y, z) of a turn of ``angle`` radians about the axis (x, y, z)."""
    import mujoco

    quat = np.zeros(4)
    mujoco.mju_axisAngle2Quat(quat, np.array([x, y, z], float) / math.hypot(x, y, z), angle)
    return tuple(float(v) for v in quat)


def webots_scene_xml() -> ET.Element:
    """The Webots ERS-7 world: goals blue at +x and yellow at -x, landmarks, borders, pink ball."""
    parts = []
    for colour, sign in (("blue", 1), ("yellow", -1)):
        back, d, w, h, t, mesh = sign * 1.75, 0.25, 0.6, 0.3, 0.01, f"goal_{colour}"
        parts += [
            StaticPart(mesh, colour, "box", (back, 0, h / 2), (t / 2, w / 2, h / 2), f"{mesh}_back", mesh),
            *(
                StaticPart(
                    mesh,
                    colour,
                    "box",
                    (back - sign * d / 2, s * w / 2, h / 2),
                    (d / 2, t / 2, h / 2),
                    f"{mesh}_{side}",
                    mesh,
                )
                for side, s in (("left", 1), ("right", -1))
            ),
            StaticPart(
                mesh, colour, "box", (back - sign * d / 2, 0, 0.305), (d / 2, w / 2, t / 2), f"{mesh}_roof", mesh
            ),
        ]
    for i, (x, y, bottom, top) in enumerate(WEBOTS_LANDMARKS):
        parts += [
            StaticPart(
                "beacon_white", "white", "box", (x, y, 0.2), (0.005, 0.005, 0.2), f"beacon_{i}_post", f"beacon_{i}"
            ),
            StaticPart(
                f"beacon_{bottom}",
                bottom,
                "cylinder",
                (x, y, 0.40),  # Webots' cylinders' centres
                (0.02, 0.025),
                f"beacon_{i}_bottom",
                f"beacon_{i}",
            ),
            StaticPart(f"beacon_{top}", top, "cylinder", (x, y, 0.45), (0.02, 0.025), f"beacon_{i}_top", f"beacon_{i}"),
        ]
    # Webots' sloped borders: slabs turned about an axis (rotation x y z angle), half in the ground
    parts += [
        StaticPart("wall_border", "border", "box", pos, size, f"wall_border_{n}", quat=axis_angle_quat(*rotation))
        for n, size, pos, rotation in (
            ("left", (1.65, 0.025, 0.1), (0, 0.98, 0.05), (1, 0, 0, 2.356196)),
            ("right", (1.65, 0.025, 0.1), (0, -0.98, 0.05), (1, 0, 0, 0.785396)),
            *(
                (
                    f"end_{i}",
                    (0.1, 0.025, 0.375),
                    (sx * 1.58, sy * 0.68, 0.05),
                    (0.8628559982596194, -sx * 0.35740699927911007, sx * 0.35740699927911007, 1.717772),
                )
                for i, (sx, sy) in enumerate(((1, 1), (1, -1), (-1, 1), (-1, -1)))
            ),
        )
    ]
    meshes, fixed = static_parts(parts + _hall(4.0, 3.0))
    return E(
        "mujoco",
        E("include", file="ers7.xml"),
        E("statistic", center=(0, 0, 0.2), extent=1.5),
        E(
            "visual",
            E("headlight", diffuse=(0.5, 0.5, 0.5), ambient=(0.3, 0.3, 0.3), specular=(0, 0, 0)),
            E("map", znear=0.002, zfar=20),
            E("global", offwidth=640, offheight=480),
        ),
        E(
            "asset",
            *(
                E("material", name=n, rgba=c, specular=0.1, emission=0.31 if n == "red" else 0)
                for n, c in WEBOTS_COLOURS.items()
            ),
            E("material", **HALL_MATERIAL),
            *meshes,
        ),
        E(
            "worldbody",
            E("light", name="ceiling", pos=(0, 0, 3), dir=(0, 0, -1), directional="false", diffuse=(0.6, 0.6, 0.58)),
            E(
                "geom",
                name="field_carpet",
                type="plane",
                size=(2.0, 1.5, 1.0),
                material="pitch",
                friction=(0.99, 0.005, 0.0001),
            ),
            *fixed,
            E(
                "body",
                E("freejoint", name="ball"),
                E(
                    "geom",
                    name="ball",
                    type="sphere",
                    size=0.035,
                    mass=0.1,
                    material="pink",
                    condim=6,
                    friction=(0.7, 0.005, 0.002),
                ),
                name="ball",
                pos=(0.5, 0, 0.035),
            ),
        ),
        model="ers7_webots_aibo_ers7_wbt",
    )


XML_INDENT, XML_WIDTH = "  ", 120  # MuJoCo Menagerie's layout (its format_xml check)
QUOTE_ENTITY = {'"': "&quot;"}  # attribute values are written in double quotes


def _xml_lines(element: ET.Element, depth: int) -> list[str]:
    """``element`` in Menagerie's layout: two-space indents, ``<tag .../>`` when empty, the
    attributes wrapped onto lines indented one level deeper when the tag passes 120 columns."""
    indent = XML_INDENT * depth
    if element.tag is ET.Comment:
        return [f"{indent}<!--{element.text}-->"]
    end = ">" if len(element) else "/>"
    lines, line = [], f"{indent}<{element.tag}"
    attributes = [f'{name}="{escape(" ".join(value.split()), QUOTE_ENTITY)}"' for name, value in element.attrib.items()]
    if len(" ".join([line, *attributes]) + end) <= XML_WIDTH:
        attributes, line = [], " ".join([line, *attributes])
    for i, attribute in enumerate(attributes):
        width = XML_WIDTH - (len(end) if i == len(attributes) - 1 else 0)
        if len(f"{line} {attribute}") <= width:
            line = f"{line} {attribute}"
        else:
            lines.append(line)
            line = f"{indent}{XML_INDENT}{attribute}"
    lines.append(line + end)
    if len(element):
        lines += [text for child in element for text in _xml_lines(child, depth + 1)] + [f"{indent}</{element.tag}>"]
    return lines


def _xml_text(root: ET.Element, comment: str) -> str:
    """The file's text: ``comment`` first inside the root, Menagerie's layout."""
    root.insert(0, ET.Comment(f" {comment} "))
    return "\n".join(_xml_lines(root, 0)) + "\n"


def generated_files() -> dict[str, str]:
    """File name -> XML text of every generated model file."""
    note = "Generated by python -m aibo_sim.mjcf from {}: edit that, not this file."
    return {
        "ers7.xml": _xml_text(_with_keyframes(robot_xml()), note.format("aibo_sim/ers7.py")),
        "scene.xml": _xml_text(scene_xml(), note.format("aibo_sim/field.py")),
        "scene_webots.xml": _xml_text(webots_scene_xml(), note.format("the Webots tables in aibo_sim/mjcf.py")),
    }


def main(argv=None) -> None:
    """Write the generated files into the models folder (``sim.models_dir``)."""
    argparse.ArgumentParser(
        prog="python -m aibo_sim.mjcf",
        description=f"Write the generated model files (ers7.xml, scene.xml, ...) into {models_dir()}, replacing them.",
    ).parse_args(argv)
    for name, text in generated_files().items():
        (models_dir() / name).write_text(text)
        print(f"wrote {models_dir() / name}")


if __name__ == "__main__":
    main()
