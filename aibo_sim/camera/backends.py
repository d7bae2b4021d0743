"""Where the controller's camera images come from, per backend.

``SimCamera`` hands over the frame's RGB picture. ``OpenRCamera`` does what the robot does:
the frame's ``OFbkImageVectorData`` (frameNumber = the exposure's 8 ms tick, field counter =
frame index at 30 fps) is published by ``OVirtualRobotComm``, routed by the memory stick's
CONNECT.CFG to the wrapper object, and read back through the wrapper's
``camera_get_image``. Both return row-major RGB, 3 bytes a pixel, as a flat uint8 array.
Listeners are called with ``(camera frame index, (h, w, 3) RGB)`` for every capture.

Camera settings: ``set_setting(setting, value)`` takes a setting of
``openr_bridge.CAMERA_SETTINGS`` ("white_balance", "gain", "shutter") and Sony's value for it
(1..3, the ``ocamparam*`` constants); the camera (``sim.camera``) exposes its next frame with
it, a frame already exposed keeps its settings. ``SimCamera`` sets ``sim.camera`` directly.
``OpenRCamera`` does it the robot's way: the wrapper's ``camera_set_*`` calls
``OPENR::ControlPrimitive`` on the system's camera primitive, whose listener (connected here)
passes the change on to ``sim.camera.set_settings``; the primitive starts at ``sim.camera``'s
settings. A bad value raises ``ValueError`` naming the allowed ones on both (on openr it is
ControlPrimitive that refuses it, ``oOUT_OF_RANGE`` or ``oINVALID_ARG``) and changes nothing.
"""

from __future__ import annotations

import numpy as np

import openr_bridge
from openr_bridge.primitive import allowed_values

from .head import CameraFrame

# Each setting's values by Sony's number: {"gain": {1: "low", 2: "mid", 3: "high"}, ...}.
SETTING_VALUES = {
    setting: {number: name for name, number in values.items()}
    for setting, (_, values) in openr_bridge.CAMERA_SETTINGS.items()
}
# The wrapper function that sets each setting.
WRAPPER_FUNCTIONS = {setting: function for function, (_, setting) in openr_bridge.CAMERA_SETTING_FUNCTIONS.items()}


class SimCamera:
    """The ``sim`` backend's camera: the rendered frame's RGB picture."""

    def __init__(self, sim):
        self.sim = sim
        self.width, self.height = sim.camera.width, sim.camera.height
        self.fov = openr_bridge.FIELD_OF_VIEW
        self.listeners = []

    def set_setting(self, setting: str, value: int) -> None:
        """Sony's ``value`` (1..3) for ``setting``, from the next camera frame on."""
        values = SETTING_VALUES[setting]
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or int(value) not in values:
            raise ValueError(f"the value must be {allowed_values(setting)}")
        self.sim.camera.set_settings(**{setting: values[int(value)]})

    def capture(self) -> np.ndarray:
        """The camera's current frame, row-major RGB as a flat uint8 array; tells the listeners."""
        frame = self.sim.camera.frame()
        self._notify(frame.index, frame.rgb)
        return frame.rgb.reshape(-1)

    def _notify(self, index: int, rgb: np.ndarray) -> None:
        for listener in self.listeners:
            listener(index, rgb)


class OpenRCamera(SimCamera):
    """The ``openr`` backend's camera: each frame goes through OPEN-R's wiring to the wrapper
    ``Controller``, the memory stick's CONNECT.CFG (default: the bundled one) routing it."""

    def __init__(self, sim, memory_stick=None):
        super().__init__(sim)
        self.width, self.height = openr_bridge.LAYER_SIZE[openr_bridge.ofbkimageLAYER_H]
        primitive = openr_bridge.OCameraPrimitive(sim.camera.settings.as_dict())
        self.system = openr_bridge.OpenRSystem.from_memory_stick(
            memory_stick or openr_bridge.DEFAULT_MEMORY_STICK, camera=primitive
        )
        self.wrapper = self.system.controller
        primitive.listeners.append(self._apply_settings)

    def set_setting(self, setting: str, value: int) -> None:
        """Through the wrapper: ``OPENR::ControlPrimitive`` on the camera primitive."""
        try:
            getattr(self.wrapper, WRAPPER_FUNCTIONS[setting])(value)
        except openr_bridge.PrimitiveError as error:
            if error.status not in (openr_bridge.oOUT_OF_RANGE, openr_bridge.oINVALID_ARG):
                raise
            raise ValueError(
                f"the value must be {allowed_values(setting)} (OPENR::ControlPrimitive returned "
                f"{openr_bridge.status_name(error.status)})"
            ) from error

    def _apply_settings(self, change: dict[str, str]) -> None:
        """The camera primitive's listener: its change, for the next frame."""
        self.sim.camera.set_settings(**change)

    def serve(self, frame: CameraFrame) -> np.ndarray:
        """Deliver the frame's message to the wrapper; what its ``camera_get_image`` then
        serves, (h, w, 3)."""
        self.system.robot_comm.publish_image(frame.message)
        image = np.asarray(self.wrapper.camera_get_image(), dtype=np.uint8)
        self.width, self.height = self.wrapper.camera_get_width(), self.wrapper.camera_get_height()
        self.fov = self.wrapper.camera_get_fov()
        return image.reshape(self.height, self.width, 3)

    def capture(self) -> np.ndarray:
        """The current frame as the wrapper's ``camera_get_image`` serves it; tells the listeners."""
        frame = self.sim.camera.frame()
        image = self.serve(frame)
        self._notify(frame.index, image)
        return image.reshape(-1)
