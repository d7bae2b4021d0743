"""``aibo-sim run ... --view``: MuJoCo's interactive viewer on the running simulation.

The controller runs as without the viewer, paced to real time; the viewer shows the
simulation (MuJoCo's passive viewer: mouse, panels, rendering options as MuJoCo has them)
with the head camera's newest frame in its lower right corner. Space pauses and resumes,
the right arrow advances one 8 ms frame while paused, as in MuJoCo's own viewer; closing
the window ends the run as its duration does. It needs a display (X11 or Wayland): without
one, ``ViewerUnavailable`` says so before anything runs.
"""

from __future__ import annotations

import os
import threading
import time
import warnings

import mujoco
import numpy as np

from .robot import SimulationEnd

KEY_SPACE, KEY_RIGHT = 32, 262  # GLFW key codes
TRACKING_VIEW = {"distance": 0.9, "elevation": -25.0, "azimuth": 135.0}  # the free camera follows the robot
PAUSED_POLL_S = 0.02
CLOSE_WAIT_S = 10.0


class ViewerUnavailable(RuntimeError):
    """No display to open the viewer on."""


def check_display() -> None:
    """Raise ViewerUnavailable unless a window can be opened."""
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise ViewerUnavailable(
            "--view needs a display (DISPLAY or WAYLAND_DISPLAY is not set); "
            "on a machine without one, run under a virtual display: xvfb-run -a aibo-sim run ... --view"
        )
    import glfw

    with warnings.catch_warnings(record=True) as warned:  # GLFW's errors come as warnings
        warnings.simplefilter("always")
        opened = glfw.init()
    if not opened:
        why = "; ".join(str(w.message) for w in warned)
        raise ViewerUnavailable(
            f"--view: cannot open the display {os.environ.get('DISPLAY') or os.environ.get('WAYLAND_DISPLAY')!r}"
            + (f" ({why})" if why else "")
        )


class LiveViewer:
    """A frame listener for ``run_controller`` (or robot 1's in ``run_match``): shows the
    simulation live, following robot ``robot`` (0: the first) with its camera's newest frame;
    in a match, another robot's newest frame its controller has already made (its camera renders
    in its own thread)."""

    def __init__(self, robot: int = 0):
        check_display()
        self.robot = robot
        self._handle, self._threads = None, set()
        self.paused, self._steps_asked = False, 0
        self._shown_camera_frame = -1
        self._clock_start = 0.0  # wall time at which simulated time 0 would have been shown

    def _key(self, key: int) -> None:  # called in the viewer's thread
        if key == KEY_SPACE:
            self.paused = not self.paused
        elif key == KEY_RIGHT and self.paused:
            self._steps_asked += 1

    def __call__(self, program) -> None:
        sim = program.sim.world.robots[self.robot]
        if self._handle is None:
            import mujoco.viewer

            before = set(threading.enumerate())
            self._handle = mujoco.viewer.launch_passive(sim.model, sim.data, key_callback=self._key)
            self._threads = set(threading.enumerate()) - before  # the viewer's, joined by close()
            with self._handle.lock():
                camera = self._handle.cam
                camera.type, camera.trackbodyid = mujoco.mjtCamera.mjCAMERA_TRACKING, sim._body
                for name, value in TRACKING_VIEW.items():
                    setattr(camera, name, value)
            self._clock_start = time.monotonic() - sim.time_ms / 1000
        handle = self._handle
        if not handle.is_running():
            raise SimulationEnd()
        self._show_camera(sim)
        handle.sync()
        ahead = self._clock_start + sim.time_ms / 1000 - time.monotonic()
        if ahead > 0:
            time.sleep(ahead)
        paused_at = time.monotonic()
        while self.paused and not self._steps_asked and handle.is_running():
            time.sleep(PAUSED_POLL_S)
            handle.sync()
        self._steps_asked = max(0, self._steps_asked - 1)
        self._clock_start += time.monotonic() - paused_at  # a pause does not make the run hurry after

    def _show_camera(self, sim) -> None:
        index = sim.camera_frame_index()
        if index == self._shown_camera_frame:
            return
        frame = sim.camera.frame() if self.robot == 0 else sim.camera.made_frame()
        if frame is None:
            return
        self._shown_camera_frame = index
        inset = frame.rgb
        view = self._handle.viewport
        left = max(0, (view.left + view.width - inset.shape[1]) if view is not None else 0)
        self._handle.set_images((mujoco.MjrRect(left, 0, inset.shape[1], inset.shape[0]), np.ascontiguousarray(inset)))

    def close(self) -> None:
        """Close the window and wait for the viewer's thread: GLFW ends with the process, and
        ending it under a thread that still draws crashes (segmentation fault at exit)."""
        if self._handle is not None:
            self._handle.close()
            self._handle = None
            for thread in self._threads:
                thread.join(CLOSE_WAIT_S)
