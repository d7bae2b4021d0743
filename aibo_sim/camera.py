"""Where the controller's camera images come from, per backend.

``SimCamera`` hands over the rendered RGB frame. ``OpenRCamera`` does what the robot does:
the frame is encoded into an ``OFbkImageVectorData`` (frameNumber in 8 ms ticks, field
counter = image index at 30 fps), published by ``OVirtualRobotComm``, routed by the
memory stick's CONNECT.CFG to the wrapper object, and read back through the wrapper's
``camera_get_image``. Both return row-major RGB, 3 bytes a pixel, as a flat uint8 array.
Listeners are called with ``(camera frame index, (h, w, 3) RGB)`` for every capture.
"""

from __future__ import annotations

import numpy as np

import openr_bridge

from .sim import Simulation


class SimCamera:
    def __init__(self, sim: Simulation):
        self.sim = sim
        self.width, self.height = sim.camera_size
        self.fov = openr_bridge.FIELD_OF_VIEW
        self.listeners = []

    def capture(self) -> np.ndarray:
        rgb = self.sim.render_camera()
        self._notify(rgb)
        return rgb.reshape(-1)

    def _notify(self, rgb: np.ndarray) -> None:
        for listener in self.listeners:
            listener(self.sim.camera_frame_index(), rgb)


class OpenRCamera(SimCamera):
    def __init__(self, sim: Simulation, memory_stick=None):
        super().__init__(sim)
        self.width, self.height = openr_bridge.LAYER_SIZE[openr_bridge.ofbkimageLAYER_H]
        self.system = openr_bridge.OpenRSystem.from_memory_stick(memory_stick or openr_bridge.DEFAULT_MEMORY_STICK)
        self.wrapper = self.system.controller
        self.last_message: openr_bridge.OFbkImageVectorData | None = None

    def serve(self, rgb: np.ndarray) -> np.ndarray:
        """Deliver ``rgb`` as the current frame's message to the wrapper; what its
        ``camera_get_image`` then serves, (h, w, 3)."""
        self.last_message = self.sim.openr_message(rgb)
        self.system.robot_comm.publish_image(self.last_message)
        image = np.asarray(self.wrapper.camera_get_image(), dtype=np.uint8)
        self.width, self.height = self.wrapper.camera_get_width(), self.wrapper.camera_get_height()
        self.fov = self.wrapper.camera_get_fov()
        return image.reshape(self.height, self.width, 3)

    def capture(self) -> np.ndarray:
        image = self.serve(self.sim.render_camera())
        self._notify(image)
        return image.reshape(-1)
