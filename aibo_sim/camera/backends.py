"""Where the controller's camera images come from, per backend.

``SimCamera`` hands over the frame's RGB picture. ``OpenRCamera`` does what the robot does:
the frame's ``OFbkImageVectorData`` (frameNumber = the exposure's 8 ms tick, field counter =
frame index at 30 fps) is published by ``OVirtualRobotComm``, routed by the memory stick's
CONNECT.CFG to the wrapper object, and read back through the wrapper's
``camera_get_image``. Both return row-major RGB, 3 bytes a pixel, as a flat uint8 array.
Listeners are called with ``(camera frame index, (h, w, 3) RGB)`` for every capture.
"""

from __future__ import annotations

import numpy as np

import openr_bridge

from .head import CameraFrame


class SimCamera:
    def __init__(self, sim):
        self.sim = sim
        self.width, self.height = sim.camera.width, sim.camera.height
        self.fov = openr_bridge.FIELD_OF_VIEW
        self.listeners = []

    def capture(self) -> np.ndarray:
        frame = self.sim.camera.frame()
        self._notify(frame.index, frame.rgb)
        return frame.rgb.reshape(-1)

    def _notify(self, index: int, rgb: np.ndarray) -> None:
        for listener in self.listeners:
            listener(index, rgb)


class OpenRCamera(SimCamera):
    def __init__(self, sim, memory_stick=None):
        super().__init__(sim)
        self.width, self.height = openr_bridge.LAYER_SIZE[openr_bridge.ofbkimageLAYER_H]
        self.system = openr_bridge.OpenRSystem.from_memory_stick(memory_stick or openr_bridge.DEFAULT_MEMORY_STICK)
        self.wrapper = self.system.controller

    def serve(self, frame: CameraFrame) -> np.ndarray:
        """Deliver the frame's message to the wrapper; what its ``camera_get_image`` then
        serves, (h, w, 3)."""
        self.system.robot_comm.publish_image(frame.message)
        image = np.asarray(self.wrapper.camera_get_image(), dtype=np.uint8)
        self.width, self.height = self.wrapper.camera_get_width(), self.wrapper.camera_get_height()
        self.fov = self.wrapper.camera_get_fov()
        return image.reshape(self.height, self.width, 3)

    def capture(self) -> np.ndarray:
        frame = self.sim.camera.frame()
        image = self.serve(frame)
        self._notify(frame.index, image)
        return image.reshape(-1)
