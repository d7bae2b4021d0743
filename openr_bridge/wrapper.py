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
"""

import numpy as np

from .colour import ycrcb_to_rgb
from .config import load_stub_cfg
from .errors import ImageAccessError, NoImageError, NotConnectedError
from .ers7_camera import FIELD_OF_VIEW
from .image import OFbkImage, ofbkimageBAND_Cb, ofbkimageBAND_Cr, ofbkimageBAND_Y, ofbkimageLAYER_H, restore_tag_pixels
from .wiring import DATA_DIR, OObject

IMAGE_SERVICE = "Controller.Image.OFbkImageVectorData.O"
CAMERA_CONNECTION = f"OVirtualRobotComm.FbkImageSensor.OFbkImageVectorData.S {IMAGE_SERVICE}"


class Controller(OObject):
    """The wrapper object; ``restore_tag=True`` hides the tag pixels in camera_get_image."""

    def __init__(self, *, restore_tag: bool = False):
        super().__init__(load_stub_cfg(DATA_DIR / "Controller" / "stub.cfg"))
        self.restore_tag = restore_tag
        self._image_observer = next(o for o in self.observer if str(o.service.name) == IMAGE_SERVICE)
        self._image = None
        self._bands = {}  # the OFbkImage of each band of _image's layer H read so far

    def DoStart(self) -> None:
        for observer in self.observer:
            observer.AssertReady()

    def Notify(self, event) -> None:
        self._image = event.Data(0)
        self._bands = {}
        self.observer[event.ObsIndex()].AssertReady(event.SenderID())

    def camera_get_width(self) -> int:
        return self._band(ofbkimageBAND_Y).Width()

    def camera_get_height(self) -> int:
        return self._band(ofbkimageBAND_Y).Height()

    def camera_get_image(self) -> np.ndarray:
        """Layer H as RGB, 3 bytes a pixel, row-major: a flat uint8 array of height * width * 3."""
        y = self._band(ofbkimageBAND_Y).array
        if self.restore_tag:
            y = restore_tag_pixels(y)
        rgb = ycrcb_to_rgb(y, self._band(ofbkimageBAND_Cr).array, self._band(ofbkimageBAND_Cb).array)
        return rgb.reshape(-1)

    def camera_get_fov(self) -> float:
        return FIELD_OF_VIEW

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
    return _component(image, width, x, y, 1)


def camera_image_get_blue(image, width: int, x: int, y: int) -> int:
    return _component(image, width, x, y, 2)


def _component(image, width: int, x: int, y: int, channel: int) -> int:
    index = 3 * (y * width + x) + channel
    if not (0 <= x < width and 0 <= index < len(image)):
        raise ImageAccessError(f"pixel ({x}, {y}) outside an image {width} wide of {len(image) // 3} pixels")
    return int(image[index])
