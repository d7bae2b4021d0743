"""The ERS-7 camera facts, kept here once (spec sections 1, 3, 8; the report section 3.2.5)."""

from .image import odataFBK_CDT, odataFBK_YCrCb_HPF

CAMERA_LOCATOR = "PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1"

FULL_WIDTH, FULL_HEIGHT = 416, 320
# Names, (width, height) and types of the layers H, M, L, C, indexed by ofbkimageLAYER_*.
LAYER_NAMES = ("H", "M", "L", "C")
LAYER_SIZE = ((208, 160), (104, 80), (52, 40), (104, 80))
LAYER_TYPE = (odataFBK_YCrCb_HPF, odataFBK_YCrCb_HPF, odataFBK_YCrCb_HPF, odataFBK_CDT)

FRAME_RATE_HZ = 30
FRAME_TICK_MS = 8  # frameNumber counts 8 ms system frames, not images

HORIZONTAL_FOV_DEG = 56.9
VERTICAL_FOV_DEG = 45.2
# What the report's camera_get_fov returns. Its text calls this "the height" and quotes
# 56.7 degrees, but 0.993092 rad is 56.900 degrees: the horizontal field of view (the
# value Webots' ERS-7 camera uses too).
FIELD_OF_VIEW = 0.993092


# OPEN-R frame numbers count 8 ms frames from 0; after oframeMAX_NUMBER they start again at 1.
oframeMAX_NUMBER = 0x0FFFFFF0


def openr_frame_number(tick: int) -> int:
    """The OPEN-R frame number of the 8 ms frame ``tick`` (0, 1, ...): wraps to 1 after oframeMAX_NUMBER."""
    return tick if tick <= oframeMAX_NUMBER else (tick - 1) % oframeMAX_NUMBER + 1


def frame_number_for_image(index: int) -> int:
    """frameNumber of the index-th image at 30 fps: the first 8 ms frame at or after index/30 s,
    where the simulator takes it (steps of 4 or 5, 25 per 6 images)."""
    return -(-index * 1000 // (FRAME_RATE_HZ * FRAME_TICK_MS))


# Camera settings (OPrimitiveControl.h): OPENR::ControlPrimitive(cameraID, request, &value, ...).
oprmreqCAM_BASE = 384
oprmreqCAM_SET_WHITE_BALANCE = 384
oprmreqCAM_SET_GAIN = 385
oprmreqCAM_SET_SHUTTER_SPEED = 386
ocamparamWB_INDOOR_MODE, ocamparamWB_OUTDOOR_MODE, ocamparamWB_FL_MODE = 1, 2, 3
ocamparamGAIN_LOW, ocamparamGAIN_MID, ocamparamGAIN_HIGH = 1, 2, 3
ocamparamSHUTTER_SLOW, ocamparamSHUTTER_MID, ocamparamSHUTTER_FAST = 1, 2, 3
# Each setting's values by name, as the command line and the settings API spell them.
CAMERA_SETTINGS = {
    "white_balance": (
        oprmreqCAM_SET_WHITE_BALANCE,
        {"indoor": ocamparamWB_INDOOR_MODE, "outdoor": ocamparamWB_OUTDOOR_MODE, "fl": ocamparamWB_FL_MODE},
    ),
    "gain": (oprmreqCAM_SET_GAIN, {"low": ocamparamGAIN_LOW, "mid": ocamparamGAIN_MID, "high": ocamparamGAIN_HIGH}),
    "shutter": (
        oprmreqCAM_SET_SHUTTER_SPEED,
        {"slow": ocamparamSHUTTER_SLOW, "mid": ocamparamSHUTTER_MID, "fast": ocamparamSHUTTER_FAST},
    ),
}
CAMERA_DEFAULTS = {"white_balance": "fl", "gain": "mid", "shutter": "mid"}  # Sony's defaults
