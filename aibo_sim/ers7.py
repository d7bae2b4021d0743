"""The Sony Aibo ERS-7: one table of joints, sensors and LEDs with their OPEN-R locators.

Everything else (the MJCF generator, the controller API, MTN playback, the gymnasium
environments) reads these tables; nothing else spells a locator or a joint limit.
Facts come from ``shared/specs/ers7-reference.md`` (sections A and B); frame: X forward,
Y left, Z up, metres, radians. Where the spec marks a value unconfirmed the choice made
here is said beside it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from openr_bridge import CAMERA_LOCATOR

DEG = math.pi / 180.0
HEAD_CAMERA = "camera"  # the MJCF name of the head camera


@dataclass(frozen=True)
class Joint:
    """One actuated joint: MJCF name, OPEN-R locator and the numbers that go with it."""

    name: str
    locator: str
    hw_range_deg: tuple[float, float]  # Sony hardware limits (= Webots min/maxPosition)
    sw_range_deg: tuple[float, float]  # Sony software limits (SONY 2.1.1)
    max_speed: float  # rad/s, Sony's recommended maximum (Tekkotsu MaxOutputSpeed)
    gains: tuple[int, int, int]  # Sony standard P, I, D register values
    default_deg: float = 0.0  # Webots default position

    @property
    def is_ear(self) -> bool:
        """An ear: a Joint4 (up or down) on the robot, outside its sensor vector."""
        return "-Joint4:" in self.locator

    @property
    def range(self) -> tuple[float, float]:
        """Hardware range in radians: the MJCF joint range."""
        return (self.hw_range_deg[0] * DEG, self.hw_range_deg[1] * DEG)


# Leg prefixes in Sony's order r2..r5, with (side sign, front?) for the geometry.
LEGS = {"lf": ("r2", 1, True), "lh": ("r3", 1, False), "rf": ("r4", -1, True), "rh": ("r5", -1, False)}

_J1_FRONT = ((-120.0, 135.0), (-115.0, 130.0))
_J1_HIND = ((-135.0, 120.0), (-130.0, 115.0))
_J2 = ((-15.0, 93.0), (-10.0, 88.0))
_J3 = ((-30.0, 127.0), (-25.0, 122.0))


def _leg_joints() -> list[Joint]:
    joints = []
    for leg, (r, _, front) in LEGS.items():
        n = r[1]
        j1 = _J1_FRONT if front else _J1_HIND
        joints += [
            Joint(f"{leg}_j1", f"PRM:/{r}/c1-Joint2:{n}1", *j1, 4.865, (0x1C, 0x08, 0x01)),
            Joint(f"{leg}_j2", f"PRM:/{r}/c1/c2-Joint2:{n}2", *_J2, 5.280, (0x14, 0x04, 0x01)),
            Joint(f"{leg}_j3", f"PRM:/{r}/c1/c2/c3-Joint2:{n}3", *_J3, 5.280, (0x1C, 0x08, 0x01), 30.0),
        ]
    return joints


MAX_TORQUE = 5.4542  # N m, Webots maxForce for every servo (carried over from the ERS-210)
# OJointValue.pwmDuty at the motor's full torque, MAX_TORQUE: the scale of the duty the OPEN-R
# runtime reports and a memory stick's servo_get_motor_force_feedback reads (UNCONFIRMED: Sony's
# manuals give no range; aibo-sim's choice).
PWM_DUTY_FULL_SCALE = 255

# Order: Sony's MTN/locator order (11, 12, 13, 14, 15, 16, 21..53, 61, 62).
# Ears are binary Joint4 flappers on the robot; here they are position joints over 0..15 deg.
# Ear speed and gains are not published: the tail's are used. Mouth hardware range is
# Webots' -60..0 (Sony gives only the software range).
JOINTS: tuple[Joint, ...] = (
    Joint("neck_tilt", "PRM:/r1/c1-Joint2:11", (-80.0, 3.0), (-75.0, 0.0), 3.185, (0x0A, 0x04, 0x02), -30.0),
    Joint("head_pan", "PRM:/r1/c1/c2-Joint2:12", (-93.0, 93.0), (-88.0, 88.0), 10.057, (0x08, 0x02, 0x04)),
    Joint("head_tilt", "PRM:/r1/c1/c2/c3-Joint2:13", (-20.0, 50.0), (-15.0, 45.0), 5.781, (0x08, 0x04, 0x02), 30.0),
    Joint("mouth", "PRM:/r1/c1/c2/c3/c4-Joint2:14", (-60.0, 0.0), (-55.0, -3.0), 10.14, (0x08, 0x00, 0x04), -3.0),
    Joint("ear_l", "PRM:/r1/c1/c2/c3/e5-Joint4:15", (0.0, 15.0), (0.0, 15.0), 15.16, (0x0A, 0x04, 0x04)),
    Joint("ear_r", "PRM:/r1/c1/c2/c3/e6-Joint4:16", (0.0, 15.0), (0.0, 15.0), 15.16, (0x0A, 0x04, 0x04)),
    *_leg_joints(),
    Joint("tail_tilt", "PRM:/r6/c1-Joint2:61", (0.0, 65.0), (5.0, 60.0), 15.16, (0x0A, 0x04, 0x04)),
    Joint("tail_pan", "PRM:/r6/c2-Joint2:62", (-60.0, 60.0), (-45.0, 45.0), 15.16, (0x0A, 0x04, 0x04)),
)

JOINT_BY_NAME = {j.name: j for j in JOINTS}
JOINT_BY_LOCATOR = {j.locator: j for j in JOINTS}
JOINT_INDEX = {j.name: i for i, j in enumerate(JOINTS)}  # position in JOINTS (and in actuators)


def joint_indices(locators) -> list[int]:
    """Positions in ``JOINTS`` of the joints with these OPEN-R locators."""
    return [JOINT_INDEX[JOINT_BY_LOCATOR[locator].name] for locator in locators]


@dataclass(frozen=True)
class Sensor:
    """A non-joint device: MJCF name, OPEN-R locator, kind, and its range where it has one."""

    name: str
    locator: str
    kind: str  # "camera", "distance", "touch", "accelerometer"
    range_mm: tuple[float, float] | None = None
    threshold: float | None = None  # touch: on/off threshold in newtons (simulated)


SENSORS: tuple[Sensor, ...] = (
    Sensor(HEAD_CAMERA, CAMERA_LOCATOR, "camera"),
    # Which head IR is on which side is unconfirmed: Webots' placement is used.
    Sensor("ir_near", "PRM:/r1/c1/c2/c3/p1-Sensor:p1", "distance", (50.0, 500.0)),
    Sensor("ir_far", "PRM:/r1/c1/c2/c3/p2-Sensor:p2", "distance", (200.0, 1500.0)),
    Sensor("ir_chest", "PRM:/p1-Sensor:p1", "distance", (100.0, 900.0)),
    Sensor("touch_head", "PRM:/r1/c1/c2/c3/t1-Sensor:t1", "touch", threshold=0.1),
    Sensor("touch_chin", "PRM:/r1/c1/c2/c3/c4/s5-Sensor:s5", "touch", threshold=0.1),
    *(
        Sensor(f"touch_paw_{leg}", f"PRM:/{r}/c1/c2/c3/c4-Sensor:{r[1]}4", "touch", threshold=0.1)
        for leg, (r, _, _) in LEGS.items()
    ),
    Sensor("touch_back_rear", "PRM:/t2-Sensor:t2", "touch", threshold=0.1),
    Sensor("touch_back_middle", "PRM:/t3-Sensor:t3", "touch", threshold=0.1),
    Sensor("touch_back_front", "PRM:/t4-Sensor:t4", "touch", threshold=0.1),
    # One 3-axis device; Sony publishes a1 (front-back), a2 (right-left), a3 (up-down).
    Sensor("accelerometer", "PRM:/a1-Sensor:a1", "accelerometer"),
)

SENSOR_BY_NAME = {s.name: s for s in SENSORS}
DISTANCE_SENSORS = tuple(s for s in SENSORS if s.kind == "distance")
TOUCH_SENSORS = tuple(s for s in SENSORS if s.kind == "touch")
# a2 and a3 name the same device's other axes.
ACCELEROMETER_ALIASES = ("PRM:/a2-Sensor:a2", "PRM:/a3-Sensor:a3")
# What a1, a2, a3 read of the body's acceleration along x (forward), y (left), z (up): a1 is
# backward, a2 left, a3 down, so a robot standing still reads a3 = -9.8 m/s^2. Sony gives no
# signs; Tekkotsu does (its ERS7Info: "backward acceleration ... negative if sitting on butt",
# "downward acceleration ... negative if standing up"; its WorldState takes a1..a3 as they come).
OPENR_ACCELERATION_SIGNS = (-1, 1, -1)


# The face panel's light spots as Model Information for ERS-7 (A.2) draws them: (across, up) in
# the drawing's pixels from the middle of its 68 x 58 pixel LED grid, a pair's left spot (the
# robot's left: the drawing, seen from the front, names no side) given. ``mjcf`` puts them on the
# visor, FACE_SPOT_PITCH metres a pixel.
FACE_SPOTS = {
    "bottom_outer": (27.8, -20.2),
    "lowest_outer": (27.8, -27.6),
    "bottom_inner": (16.3, -25.0),
    "middle_outer": (27.8, -9.5),
    "middle_inner": (13.8, -9.3),
    "upper_outer": (27.8, 1.5),
    "upper_inner": (13.9, 3.1),
    "top_outer": (27.8, 10.9),
    "upper_centre": (0.0, 1.6),
    "centre": (0.0, -9.8),
}
FACE_SPOT_PITCH = 0.0005


def face_spot_geoms(spot: str, side: str = "lr") -> tuple[str, ...]:
    """The geoms of a face spot: a centre spot's one, else the pair's on ``side`` (l, r or lr)."""
    if FACE_SPOTS[spot][0] == 0:
        return (f"led_face_{spot}",)
    return tuple(f"led_face_{spot}_{s}" for s in side)


@dataclass(frozen=True)
class Led:
    """An LED: name, OPEN-R locator, colour when lit (RGB 0..1) and the geoms it lights (default
    the one named ``name``); a face light also has a B face (OPEN-R's ``oled3_MODE_B``; Model
    Information for ERS-7, 3.1.1): its colour and geoms there."""

    name: str
    locator: str
    colour: tuple[float, float, float]
    colour_b: tuple[float, float, float] | None = None
    geoms: tuple[str, ...] = ()
    geoms_b: tuple[str, ...] = ()

    def lit_geoms(self, face_b: bool = False) -> tuple[str, ...]:
        """The geoms it lights on the A face, or on the B face (``face_b``) where it has one."""
        return (self.geoms_b if face_b and self.colour_b else self.geoms) or (self.name,)

    @property
    def all_geoms(self) -> tuple[str, ...]:
        """Every geom it can light, on either face, each once."""
        return tuple(dict.fromkeys(self.lit_geoms() + self.lit_geoms(True)))

    def lit_colour(self, face_b: bool = False) -> tuple[float, float, float]:
        """Its colour on the A face, or on the B face (``face_b``) where it has one."""
        return self.colour_b if face_b and self.colour_b else self.colour


def _face_light(number: int, colour, colour_b, spot: str, spot_b: str | None = None, side: str = "") -> Led:
    """Face light ``number`` (Model Information 3.1.1 and A.2) at ``spot``, and on the B face at
    ``spot_b`` (default the same): odd numbers a pair's left spot, even the right, unless ``side``."""
    side = side or ("l" if number % 2 else "r")
    letter = "abcdefghijklmn"[number - 1]
    locator = f"PRM:/r1/c1/c2/c3/l{letter}-LED3:l{letter}"
    geoms, geoms_b = face_spot_geoms(spot, side), face_spot_geoms(spot_b or spot, side)
    return Led(f"led_face_{number}", locator, colour, colour_b, geoms, geoms_b)


LED_OFF_RGBA = (0.15, 0.15, 0.16, 1.0)
_WHITE, _RED, _GREEN, _BLUE = (1.0, 1.0, 1.0), (1.0, 0.1, 0.1), (0.1, 1.0, 0.2), (0.2, 0.4, 1.0)
LEDS: tuple[Led, ...] = (
    Led("led_head_colour", "PRM:/r1/c1/c2/c3/l1-LED2:l1", (1.0, 0.6, 0.1)),
    Led("led_head_white", "PRM:/r1/c1/c2/c3/l2-LED2:l2", _WHITE),
    Led("led_mode_r", "PRM:/r1/c1/c2/c3/l3-LED2:l3", _RED),
    Led("led_mode_g", "PRM:/r1/c1/c2/c3/l4-LED2:l4", _GREEN),
    Led("led_mode_b", "PRM:/r1/c1/c2/c3/l5-LED2:l5", _BLUE),
    Led("led_wireless", "PRM:/r1/c1/c2/c3/l6-LED2:l6", _BLUE),
    # Face lights 1-12 white and 13-14 red on the A face; on the B face 1-5 green, 6-12 white,
    # 13-14 blue. B3, B4 and B13 sit apart from A's, as do A14 and B14 (each a pair).
    _face_light(1, _WHITE, _GREEN, "bottom_outer"),
    _face_light(2, _WHITE, _GREEN, "bottom_outer"),
    _face_light(3, _WHITE, _GREEN, "middle_outer", "bottom_inner"),
    _face_light(4, _WHITE, _GREEN, "middle_outer", "bottom_inner"),
    _face_light(5, _WHITE, _GREEN, "middle_inner"),
    _face_light(6, _WHITE, _WHITE, "middle_inner"),
    _face_light(7, _WHITE, _WHITE, "upper_outer"),
    _face_light(8, _WHITE, _WHITE, "upper_outer"),
    _face_light(9, _WHITE, _WHITE, "upper_inner"),
    _face_light(10, _WHITE, _WHITE, "upper_inner"),
    _face_light(11, _WHITE, _WHITE, "upper_centre"),
    _face_light(12, _WHITE, _WHITE, "centre"),
    _face_light(13, _RED, _BLUE, "upper_inner", "bottom_inner", side="lr"),
    _face_light(14, _RED, _BLUE, "top_outer", "lowest_outer", side="lr"),
    Led("led_back_front_colour", "PRM:/lu-LED3:lu", _BLUE),
    Led("led_back_front_white", "PRM:/lv-LED3:lv", _WHITE),
    Led("led_back_middle_colour", "PRM:/lw-LED3:lw", (1.0, 0.55, 0.0)),
    Led("led_back_middle_white", "PRM:/lx-LED3:lx", _WHITE),
    Led("led_back_rear_colour", "PRM:/ly-LED3:ly", _RED),
    Led("led_back_rear_white", "PRM:/lz-LED3:lz", _WHITE),
)

LED_BY_LOCATOR = {led.locator: led for led in LEDS}
LED_BY_NAME = {led.name: led for led in LEDS}
# The LEDs that can light each LED geom, on either face (a face spot can have several: A9 and A13).
LEDS_BY_GEOM = {
    geom: tuple(led for led in LEDS if geom in led.all_geoms)
    for geom in dict.fromkeys(g for led in LEDS for g in led.all_geoms)
}


# OPEN-R primitives the Webots-era API has no device for: the wireless LAN switch, the speaker
# and the stereo microphones (Model Information for ERS-7, A.1).
WLAN_SWITCH_LOCATOR = "PRM:/b1-Sensor:b1"
SPEAKER_LOCATOR = "PRM:/s1-Speaker:S1"
MIC_LOCATOR = "PRM:/r1/c1/c2/c3/m1-Mic:M1"


def all_locators() -> list[str]:
    """Every device locator the simulated robot has (joints, sensors, LEDs)."""
    return (
        [j.locator for j in JOINTS]
        + [s.locator for s in SENSORS]
        + list(ACCELEROMETER_ALIASES)
        + [led.locator for led in LEDS]
    )
