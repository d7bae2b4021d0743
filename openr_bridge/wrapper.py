"""The Webots OPEN-R wrapper object, ``Controller``, with the report's camera functions.

Its stub.cfg (``data/Controller/stub.cfg``) carries the report's service line
``"Controller.Image.OFbkImageVectorData.O", null, Notify()`` and the dummy subject OPEN-R
requires; CONNECT.CFG must connect ``OVirtualRobotComm.FbkImageSensor.OFbkImageVectorData.S``
to it. ``Notify`` keeps the newest message and asserts ready, as in the report.

The camera functions read layer H of that message, as the report's do (each band's
``OFbkImage`` is made once per message). Where the C code would read through a null pointer
(no connection, or no image yet) they raise ``NotConnectedError`` or ``NoImageError``.
``camera_get_fov`` needs no image and returns the report's constant (see
``ers7_camera.FIELD_OF_VIEW``).

The camera settings functions (not in the report; what a wrapper would add with Sony's API)
``camera_set_white_balance``, ``camera_set_gain`` and ``camera_set_shutter_speed`` take
Sony's values (1..3: ``ocamparamWB_INDOOR_MODE``/``OUTDOOR``/``FL``, ``ocamparamGAIN_LOW``/
``MID``/``HIGH``, ``ocamparamSHUTTER_SLOW``/``MID``/``FAST``) and do what the C would::

    OPENR::OpenPrimitive("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1", &fbkID);  // once
    OPrimitiveControl_CameraParam param(value);
    OPENR::ControlPrimitive(fbkID, oprmreqCAM_SET_GAIN, &param, sizeof(param), 0, 0);

through the ``OPENR`` the ``OpenRSystem`` gave the object; a status other than ``oSUCCESS``
raises ``PrimitiveError`` (its ``status``; the message names the call and, for a bad value,
the allowed ones). The camera exposes its next frame with the new setting.
"""

import operator
from pathlib import Path

import numpy as np

from .colour import ycrcb_to_rgb
from .config import load_stub_cfg
from .errors import ImageAccessError, NoImageError, NotConnectedError, PrimitiveError
from .ers7_camera import (
    CAMERA_LOCATOR,
    FIELD_OF_VIEW,
    oprmreqCAM_SET_GAIN,
    oprmreqCAM_SET_SHUTTER_SPEED,
    oprmreqCAM_SET_WHITE_BALANCE,
)
from .image import OFbkImage, ofbkimageBAND_Cb, ofbkimageBAND_Cr, ofbkimageBAND_Y, ofbkimageLAYER_H, restore_tag_pixels
from .primitive import (
    REQUEST_NAMES,
    OPrimitiveControl_CameraParam,
    allowed_values,
    check,
    oINVALID_ARG,
    oSUCCESS,
    sizeof,
    status_name,
)
from .wiring import DATA_DIR, OObject

WRAPPER_SOURCES = Path(__file__).resolve().parent / "wrapper"  # the wrapper as a C++ OPEN-R object (build-ms)
IMAGE_SERVICE = "Controller.Image.OFbkImageVectorData.O"
CAMERA_CONNECTION = f"OVirtualRobotComm.FbkImageSensor.OFbkImageVectorData.S {IMAGE_SERVICE}"


# Each settings function: its request and the setting it changes (a key of CAMERA_SETTINGS).
CAMERA_SETTING_FUNCTIONS = {
    "camera_set_white_balance": (oprmreqCAM_SET_WHITE_BALANCE, "white_balance"),
    "camera_set_gain": (oprmreqCAM_SET_GAIN, "gain"),
    "camera_set_shutter_speed": (oprmreqCAM_SET_SHUTTER_SPEED, "shutter"),
}


def layer_h_rgb(y: np.ndarray, cr: np.ndarray, cb: np.ndarray, restore_tag: bool = False) -> np.ndarray:
    """The (h, w, 3) RGB picture of layer H's bands, as ``camera_get_image`` serves it (Sony's
    YCrCb2RGB; the tag pixels as they are, unless ``restore_tag``)."""
    return ycrcb_to_rgb(restore_tag_pixels(y) if restore_tag else y, cr, cb)


def message_rgb(image) -> np.ndarray:
    """The picture ``camera_get_image`` serves of an ``OFbkImageVectorData``, (h, w, 3)."""
    info, data = image.GetInfo(ofbkimageLAYER_H), image.GetData(ofbkimageLAYER_H)
    return layer_h_rgb(
        *(OFbkImage(info, data, band).array for band in (ofbkimageBAND_Y, ofbkimageBAND_Cr, ofbkimageBAND_Cb))
    )


class Controller(OObject):
    """The wrapper object; ``restore_tag=True`` hides the tag pixels in camera_get_image."""

    OPENR = None  # the OPENR:: API (primitive.OPENR) the OpenRSystem gives the object before DoStart

    def __init__(self, *, restore_tag: bool = False):
        super().__init__(load_stub_cfg(DATA_DIR / "Controller" / "stub.cfg"))
        self.restore_tag = restore_tag
        self._image_observer = next(o for o in self.observer if str(o.service.name) == IMAGE_SERVICE)
        self._image = None
        self._bands = {}  # the OFbkImage of each band of _image's layer H read so far
        self._camera_id = None  # fbkID, once opened

    def DoStart(self) -> None:
        """Assert ready on every observer."""
        for observer in self.observer:
            observer.AssertReady()

    def Notify(self, event) -> None:
        """Keep the newest image message and assert ready for the next."""
        self._image = event.Data(0)
        self._bands = {}
        self.observer[event.ObsIndex()].AssertReady(event.SenderID())

    def camera_get_width(self) -> int:
        """Layer H's width in pixels; NotConnectedError or NoImageError as the module says."""
        return self._band(ofbkimageBAND_Y).Width()

    def camera_get_height(self) -> int:
        """Layer H's height in pixels; NotConnectedError or NoImageError as the module says."""
        return self._band(ofbkimageBAND_Y).Height()

    def camera_get_image(self) -> np.ndarray:
        """Layer H as RGB, 3 bytes a pixel, row-major: a flat uint8 array of height * width * 3."""
        bands = [self._band(band).array for band in (ofbkimageBAND_Y, ofbkimageBAND_Cr, ofbkimageBAND_Cb)]
        return layer_h_rgb(*bands, restore_tag=self.restore_tag).reshape(-1)

    def camera_get_fov(self) -> float:
        """The report's horizontal field of view in radians (``FIELD_OF_VIEW``)."""
        return FIELD_OF_VIEW

    def camera_set_white_balance(self, value: int) -> None:
        """1 ocamparamWB_INDOOR_MODE, 2 ocamparamWB_OUTDOOR_MODE, 3 ocamparamWB_FL_MODE."""
        self._camera_control("camera_set_white_balance", value)

    def camera_set_gain(self, value: int) -> None:
        """1 ocamparamGAIN_LOW, 2 ocamparamGAIN_MID, 3 ocamparamGAIN_HIGH."""
        self._camera_control("camera_set_gain", value)

    def camera_set_shutter_speed(self, value: int) -> None:
        """1 ocamparamSHUTTER_SLOW, 2 ocamparamSHUTTER_MID, 3 ocamparamSHUTTER_FAST."""
        self._camera_control("camera_set_shutter_speed", value)

    def _camera_control(self, function: str, value) -> None:
        request, setting = CAMERA_SETTING_FUNCTIONS[function]
        if self.OPENR is None:
            raise NotConnectedError(
                f"{function}: this Controller was not started by an OpenRSystem, "
                "so it has no OPENR to open the camera primitive with"
            )
        if self._camera_id is None:
            status, camera_id = self.OPENR.OpenPrimitive(CAMERA_LOCATOR)
            check(status, f'{function}: OPENR::OpenPrimitive("{CAMERA_LOCATOR}")')
            self._camera_id = camera_id
        param = OPrimitiveControl_CameraParam(value)
        status = self.OPENR.ControlPrimitive(self._camera_id, request, param, sizeof(param), 0, 0)
        if status != oSUCCESS:
            hint = f"; the value must be {allowed_values(setting)}" if status == oINVALID_ARG else ""
            raise PrimitiveError(
                f"{function}({value!r}): OPENR::ControlPrimitive(fbkID, {REQUEST_NAMES[request]}, "
                f"...) returned {status_name(status)} ({status}){hint}",
                status,
            )

    def _band(self, band: int) -> OFbkImage:
        if not self._image_observer.is_connected():
            raise NotConnectedError(
                f"{IMAGE_SERVICE} is not connected: CONNECT.CFG needs the line '{CAMERA_CONNECTION}'"
            )
        if self._image is None:
            raise NoImageError("no camera image has arrived yet")
        if band not in self._bands:
            layer = ofbkimageLAYER_H
            self._bands[band] = OFbkImage(self._image.GetInfo(layer), self._image.GetData(layer), band)
        return self._bands[band]


def camera_image_get_red(image, width: int, x: int, y: int) -> int:
    """The report's macro ``image[3 * (y * width + x)]`` on camera_get_image's array."""
    return _component(image, width, x, y, 0)


def camera_image_get_green(image, width: int, x: int, y: int) -> int:
    """The report's macro ``image[3 * (y * width + x) + 1]`` on camera_get_image's array."""
    return _component(image, width, x, y, 1)


def camera_image_get_blue(image, width: int, x: int, y: int) -> int:
    """The report's macro ``image[3 * (y * width + x) + 2]`` on camera_get_image's array."""
    return _component(image, width, x, y, 2)


def _component(image, width: int, x: int, y: int, channel: int) -> int:
    function = f"camera_image_get_{('red', 'green', 'blue')[channel]}"
    try:  # whole numbers as C's int arguments are, computed as Python ints (numpy's uint8 would wrap)
        width, x, y = operator.index(width), operator.index(x), operator.index(y)
    except TypeError:
        raise TypeError(f"{function}: width, x and y must be ints, not {width!r}, {x!r}, {y!r}") from None
    index = 3 * (y * width + x) + channel
    if not (0 <= x < width and 0 <= index < len(image)):
        raise ImageAccessError(f"pixel ({x}, {y}) outside an image {width} wide of {len(image) // 3} pixels")
    return int(image[index])
