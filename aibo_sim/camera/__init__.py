"""The ERS-7's head camera, all of it: lens, sensor model, frames, labels and backends.

``HeadCamera`` (``head.py``) owns the renderer and makes each 30 fps frame once; ``lens.py``
the geometry; ``sensor.py`` the ``ideal`` and ``ers7`` profiles and the settings;
``backends.py`` what a controller's camera device serves on the ``sim`` and ``openr``
backends.
"""

from .head import HEAD_CAMERA_GROUPS, CameraFrame, HeadCamera, camera_size, describe_camera, scene_light
from .lens import LENSES, Lens
from .sensor import PROFILES, CameraProfile, CameraSettings, RobotColour, SceneLight, camera_profile

__all__ = [
    "HEAD_CAMERA_GROUPS",
    "LENSES",
    "PROFILES",
    "CameraFrame",
    "CameraProfile",
    "CameraSettings",
    "HeadCamera",
    "Lens",
    "RobotColour",
    "SceneLight",
    "camera_profile",
    "camera_size",
    "describe_camera",
    "scene_light",
]
