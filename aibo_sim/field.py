"""The RoboCup 2005-06 Four-Legged League field (spec section E.2), in metres.

Frame: origin at the centre spot, +X towards the sky-blue goal, +Y to the left when
looking from the yellow goal towards the sky-blue one, Z up.
"""

from __future__ import annotations

from dataclasses import dataclass

FIELD_LENGTH = 5.40  # inside the lines, along X
FIELD_WIDTH = 3.60
LINE_WIDTH = 0.025
CENTRE_CIRCLE_RADIUS = 0.18
PENALTY_BOX_WIDTH = 1.30  # along Y
PENALTY_BOX_DEPTH = 0.65  # along X
FRINGE_SIDE = 0.20
FRINGE_END = 0.30
WALL_HEIGHT = 0.30  # 2004 rules: white outer wall
CARPET_LENGTH = FIELD_LENGTH + 2 * FRINGE_END
CARPET_WIDTH = FIELD_WIDTH + 2 * FRINGE_SIDE

GOAL_WIDTH = 0.80
GOAL_DEPTH = 0.30
GOAL_HEIGHT = 0.30

BALL_RADIUS = 0.042
BALL_MASS = 0.055  # not in the spec: a light plastic ball (choice)
# Sony's pink ball, the AIBO's toy (Sony's samples find it with their CDT table): the size and mass
# Webots' ERS-7 world (aibo_ers7.wbt) gives it; UNCONFIRMED, no Sony source gives them. Its albedo
# (COLOURS["pink_ball"], plastic like the orange ball) is chosen, also UNCONFIRMED, so that the
# ers7 camera on the default field reads it where Sony's table for it looks (Cr ~200, Cb ~140
# inside Cr 150-230, Cb 120-190), as the real ball under the samples' indoor light.
PINK_BALL_RADIUS = 0.035
PINK_BALL_MASS = 0.1
BALL_TYPES = ("robocup", "pink")  # --ball-type: the orange RoboCup ball (the default) or the pink one
DEFAULT_BALL_TYPE = BALL_TYPES[0]

BEACON_RADIUS = 0.05
BEACON_X = 1.35
BEACON_Y = FIELD_WIDTH / 2 + 0.15
BEACON_PART_HEIGHT = 0.10  # parts A (top) and B (middle) around 0.30 m; part C white below

# Albedos as MuJoCo multiplies them with the light: with the venue's light (mjcf.py) the ers7
# camera at FL / HIGH / FAST reads them as real ERS-7s read the field (models/README.md).
COLOURS = {
    "carpet": (0.0, 0.2, 0.16, 1.0),
    "line": (0.65, 0.65, 0.65, 1.0),
    "wall": (0.65, 0.65, 0.65, 1.0),
    "yellow": (0.69, 0.62, 0.08, 1.0),
    "skyblue": (0.04, 0.38, 0.69, 1.0),
    "pink": (0.8, 0.27, 0.59, 1.0),
    "white": (0.65, 0.65, 0.65, 1.0),
    "orange": (1.0, 0.45, 0.05, 1.0),
    "pink_ball": (1.0, 0.2, 0.85, 1.0),
}
# The league's team uniforms (red, dark blue), on the robots of a match: albedos fitted as the
# field's, so that the ers7 camera at FL / HIGH / FAST, facing a uniform, reads the ten robots'
# mean of rUNSWift's red (47, 178, 113) and blue (21, 127, 130) targets (specs/ers7-camera.md
# section 5): the dark blue reads near the black level.
UNIFORM_COLOURS = {"red": (0.385, 0.0, 0.02, 1.0), "blue": (0.0, 0.008, 0.032, 1.0)}
SPECULAR = {"orange": 0.1, "pink_ball": 0.1}  # the plastic balls; carpet and paint are matte (0)


def _line_segments() -> tuple[tuple[float, float, float, float], ...]:
    """Straight field lines as (x0, y0, x1, y1) centre lines; the centre circle is separate."""
    hl, hw = FIELD_LENGTH / 2, FIELD_WIDTH / 2
    box_x, box_y = hl - PENALTY_BOX_DEPTH, PENALTY_BOX_WIDTH / 2
    segments = [(-hl, hw, hl, hw), (-hl, -hw, hl, -hw), (hl, -hw, hl, hw), (-hl, -hw, -hl, hw), (0, -hw, 0, hw)]
    for s in (1, -1):
        segments += [
            (s * box_x, -box_y, s * box_x, box_y),
            (s * box_x, box_y, s * hl, box_y),
            (s * box_x, -box_y, s * hl, -box_y),
        ]
    return tuple(segments)


LINE_SEGMENTS = _line_segments()


@dataclass(frozen=True)
class Beacon:
    """A landmark beacon: its name, position (x, y in metres) and the colours of its top (part A) and
    middle (part B)."""

    name: str
    x: float
    y: float
    top: str  # part A
    middle: str  # part B


def _beacons() -> tuple[Beacon, ...]:
    beacons = []
    for x, goal in ((BEACON_X, "skyblue"), (-BEACON_X, "yellow")):
        # Right-hand beacons (y < 0): B in the neighbouring goal's colour, A pink;
        # left-hand ones: B pink, A in the goal colour.
        beacons.append(Beacon(f"beacon_{goal}_right", x, -BEACON_Y, top="pink", middle=goal))
        beacons.append(Beacon(f"beacon_{goal}_left", x, BEACON_Y, top=goal, middle="pink"))
    return tuple(beacons)


BEACONS = _beacons()
GOALS = {"skyblue": FIELD_LENGTH / 2, "yellow": -FIELD_LENGTH / 2}  # goal line X of each goal

# Segmentation classes for frame dumps: geoms are tagged by name prefix (every robot's are "robot").
SEGMENTATION_CLASSES = ("background", "field", "line", "ball", "goal", "beacon", "robot", "wall")
# A match's robots in the labels (team.TEAMS): the team ids of the per-pixel team labels (0: no
# robot, or the lone robot without a team) and the COCO category of each team's robots, their ids
# after the segmentation classes' (those keep theirs): COCO_CATEGORIES, coco.json's ids.
LABEL_TEAMS = (None, "red", "blue")
TEAM_CATEGORIES = {"red": "robot_red", "blue": "robot_blue"}
COCO_CATEGORIES = (*SEGMENTATION_CLASSES, *TEAM_CATEGORIES.values())
