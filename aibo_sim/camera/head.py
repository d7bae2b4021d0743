"""The head camera: the one place that turns the simulation's state into camera frames.

Timing: camera frame k is exposed at its tick, the first 8 ms joint frame at or after k / 30 s.
The camera sees the simulation through a small interface (``CameraMount``: the model, the live
data, the clock, the world's render lock and robots); the simulation tells it two things only:
a joint frame is about to change the state (``before_frame``) and one has ended
(``after_frame``); the camera keeps its own exposures. Its picture,
labels and OPEN-R message are made from the state at that tick, whoever asks and whenever
(until the next tick, or ``latency_frames`` later): ``run``, ``dump`` and the environments
see the same frames, bit for bit. Settings changed during a frame apply from the next tick.

A frame (``CameraFrame``) holds the picture as RGB and as Sony's Y, Cr, Cb (one is made from
the other on first use: the ``ideal`` profile renders RGB; the ``ers7`` sensor delivers
Y, Cr, Cb and its RGB is Sony's ``YCrCb2RGB`` of them, what the wrapper serves), the camera's
pose at the exposure, and the OPEN-R message, encoded once.
"""

from __future__ import annotations

import threading
from typing import Protocol

import cv2
import mujoco
import numpy as np

import openr_bridge
from openr_bridge import FULL_HEIGHT, FULL_WIDTH, LAYER_SIZE, encode_frame, encode_ycrcb

from ..ers7 import HEAD_CAMERA
from ..render import Renderer
from .lens import LENSES, Lens
from .sensor import CameraProfile, CameraSettings, RobotColour, SceneLight, Sensor, camera_profile

HEAD_CAMERA_GROUPS = (0, 2)  # group 1 holds the robot's geoms behind the head camera
BEHIND_CAMERA_GROUP = 1
# MuJoCo camera axes (x right, y up, z backwards) to OpenCV's (x right, y down, z forward).
_MUJOCO_TO_OPENCV = np.diag([1.0, -1.0, -1.0])


def camera_size(camera_full: bool) -> tuple[int, int]:
    """(width, height) the head camera delivers: the sensor's 416x320, or layer H's 208x160."""
    return (FULL_WIDTH, FULL_HEIGHT) if camera_full else LAYER_SIZE[0]


def scene_light(model: mujoco.MjModel) -> SceneLight:
    """The scene's light from its custom numerics (``SceneLight``; the defaults where absent);
    ValueError naming a numeric out of range."""
    values = {}
    for field_name, numeric in (
        ("temperature_k", "light_temperature_K"),
        ("flicker_depth", "light_flicker_depth"),
        ("mains_hz", "mains_frequency_Hz"),
    ):
        index = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, numeric)
        if index >= 0:
            values[field_name] = float(model.numeric_data[model.numeric_adr[index]])
    return SceneLight(**values)


def describe_camera(
    profile: str | CameraProfile, settings: CameraSettings, size: tuple[int, int], light: SceneLight
) -> dict:
    """The head camera's profile (its name, and ``profile_options``: where it differs from the
    preset of that name), lens (OpenCV intrinsics and distortion at ``size``) and settings,
    as run.json and a dump's meta.json record them."""
    profile = camera_profile(profile)
    lens = LENSES[profile.lens].scaled(*size)
    return {
        "profile": profile.name,
        "profile_options": profile.options(),
        "lens": lens.name,
        "width": lens.width,
        "height": lens.height,
        "fx": lens.fx,
        "fy": lens.fy,
        "cx": lens.cx,
        "cy": lens.cy,
        "distortion": list(lens.distortion),
        "distortion_model": "OpenCV k1, k2, p1, p2, k3",
        **settings.as_dict(),
        **light.as_dict(),
    }


class CameraFrame:
    """One 30 fps frame of the head camera; see the module docstring."""

    def __init__(
        self,
        index: int,
        frame_number: int,
        settings: CameraSettings,
        pose: tuple[np.ndarray, np.ndarray],
        rgb: np.ndarray | None = None,
        ycrcb: np.ndarray | None = None,
    ):
        self.index, self.frame_number, self.settings = index, frame_number, settings
        self.position, self.xmat = pose  # camera position and MuJoCo rotation matrix (3, 3) at the exposure
        self._rgb, self._ycrcb, self._message = rgb, ycrcb, None
        for picture in (rgb, ycrcb):
            if picture is not None:
                picture.flags.writeable = False

    @property
    def rgb(self) -> np.ndarray:
        """(h, w, 3) uint8 RGB, read-only."""
        if self._rgb is None:
            self._rgb = openr_bridge.colour.ycrcb_image_to_rgb(self._ycrcb)
            self._rgb.flags.writeable = False
        return self._rgb

    @property
    def ycrcb(self) -> np.ndarray:
        """(h, w, 3) uint8 Y, Cr, Cb, read-only."""
        if self._ycrcb is None:
            self._ycrcb = np.ascontiguousarray(openr_bridge.colour.rgb_to_ycrcb_packed(self._rgb)[..., :3])
            self._ycrcb.flags.writeable = False
        return self._ycrcb

    @property
    def message(self) -> openr_bridge.OFbkImageVectorData:
        """The OFbkImageVectorData of this frame: frameNumber the exposure's 8 ms tick, field
        counter the frame index."""
        if self._message is None:
            if self._ycrcb is not None:
                self._message = encode_ycrcb(self._ycrcb, frame_number=self.frame_number, field_counter=self.index)
            else:
                self._message = encode_frame(self._rgb, frame_number=self.frame_number, field_counter=self.index)
        return self._message


class _Exposure:
    """The state a frame is made from: the live MjData until ``freeze`` copies it."""

    __slots__ = ("index", "frame_number", "settings", "data", "frame")

    def __init__(self, index, frame_number, settings, data):
        self.index, self.frame_number, self.settings, self.data = index, frame_number, settings, data
        self.frame: CameraFrame | None = None


class _OpenCvOneThread:
    """OpenCV on one thread while any camera makes a frame, the caller's setting back after the
    last: OpenCV's worker threads cost more than they save on frames this small (an ers7 frame
    ~15 % faster on one thread), and a match's cameras make their frames in several threads at
    once (the setting is the process's)."""

    def __init__(self):
        self._lock, self._makers, self._saved = threading.Lock(), 0, 0

    def __enter__(self) -> None:
        with self._lock:
            if not self._makers:
                self._saved = cv2.getNumThreads()
                cv2.setNumThreads(1)
            self._makers += 1

    def __exit__(self, *error) -> None:
        with self._lock:
            self._makers -= 1
            if not self._makers:
                cv2.setNumThreads(self._saved)


_OPENCV_ONE_THREAD = _OpenCvOneThread()


class CameraMount(Protocol):
    """What the head camera reads of the robot that carries it (``sim.Simulation`` is one): the
    compiled model, the live state, the clock, and its world's render lock and robots."""

    model: mujoco.MjModel
    data: mujoco.MjData  # the live state
    frame: int  # 8 ms joint frames since reset
    world: object  # ``render_lock`` (an RLock) and ``robots`` (each with its root body ``_body``)
    _body: int  # the carrying robot's root body

    def camera_frame_index(self) -> int:
        """Index of the newest 30 fps camera frame (frame k at k/30 s)."""
        ...


class HeadCamera:
    """The ERS-7's head camera on the robot ``sim`` (a ``CameraMount``): renderer, lens, sensor,
    frames and labels."""

    def __init__(
        self,
        sim: CameraMount,
        size: tuple[int, int],
        profile: str | CameraProfile = "ers7",
        settings: CameraSettings | None = None,
        light: SceneLight | None = None,
        camera_name: str = HEAD_CAMERA,
    ):
        self.sim, self.model = sim, sim.model
        self.width, self.height = size
        self.profile = camera_profile(profile)
        self.camera_id = self.model.camera(camera_name).id
        self.light = light or scene_light(self.model)
        self.lens: Lens = LENSES[self.profile.lens].scaled(self.width, self.height)
        self._settings = settings or CameraSettings()
        if self.lens.distorted or self.profile.lens != "pinhole":
            self._pinhole = self.lens.render_pinhole()
            maps = self.lens.render_maps(self._pinhole)
            self._remap = cv2.convertMaps(*(m.astype(np.float32) for m in maps), cv2.CV_16SC2)
            render_scale = (self._pinhole.focal / self.lens.fx, self._pinhole.focal / self.lens.fy)
        else:  # the model's own camera renders the picture
            self._pinhole = self._remap = None
            maps = tuple(np.meshgrid(np.arange(self.width, dtype=np.float64), np.arange(self.height, dtype=np.float64)))
            render_scale = (1.0, 1.0)
        self.sensor = (
            Sensor(self.profile, self._settings, self.light.temperature_k, maps, self.render_size, render_scale)
            if self.profile.sensor
            else None
        )
        self._renderer: Renderer | None = None
        self._spare: list[mujoco.MjData] = []
        self._exposures: list[_Exposure] = []
        self._velocity = np.zeros(6)
        self.seed = 0

    # ---------------------------------------------------------------- settings

    @property
    def settings(self) -> CameraSettings:
        """The settings the next frame is exposed with."""
        return self._settings

    def set_settings(self, settings: CameraSettings | None = None, **changes) -> None:
        """Change white balance, gain or shutter (names, see ``CameraSettings``) from the next frame."""
        base = settings or self._settings
        self._settings = CameraSettings(**{**base.as_dict(), **changes})

    def set_robot(self, robot: RobotColour) -> None:
        """This robot's colour deviation, for the frames made from now on."""
        if self.sensor is not None:
            self.sensor.configure(self.sensor.settings, robot)

    def describe(self, size: tuple[int, int] | None = None) -> dict:
        """Profile, lens and settings, as run.json and meta.json record them, for pictures of
        ``size`` (default the camera's own; the openr backend serves layer H of it)."""
        return describe_camera(self.profile, self._settings, size or (self.width, self.height), self.light)

    # ---------------------------------------------------------------- timing (called by the simulation)

    def before_frame(self) -> None:
        """A joint frame is about to change the live state: the newest exposure keeps a copy."""
        if self.live:
            self.freeze()

    def after_frame(self) -> None:
        """A joint frame has ended: a new exposure when the clock reached the next camera frame."""
        if self.sim.camera_frame_index() != self._exposures[-1].index:
            self.tick()

    def reset(self, seed: int) -> None:
        """Start again from the live state with the noise seed ``seed``: earlier exposures are dropped."""
        self.seed = seed
        self._spare.extend(e.data for e in self._exposures if e.data is not self.sim.data)
        self._exposures.clear()
        self.tick()

    def tick(self) -> None:
        """A frame's exposure ends now, in the live state."""
        self._exposures.append(_Exposure(self.sim.camera_frame_index(), self.sim.frame, self._settings, self.sim.data))
        while len(self._exposures) > self.profile.latency_frames + 1:
            old = self._exposures.pop(0)
            if old.data is not self.sim.data:
                self._spare.append(old.data)

    def freeze(self) -> None:
        """The live state is about to change: keep a copy for the newest exposure."""
        exposure = self._exposures[-1]
        if exposure.data is self.sim.data:
            copy = self._spare.pop() if self._spare else mujoco.MjData(self.model)
            mujoco.mj_copyData(copy, self.model, self.sim.data)
            exposure.data = copy

    def moved(self) -> None:
        """Something was placed by hand in the live state: its frame is made again."""
        if self.live:
            self._exposures[-1].frame = None

    @property
    def live(self) -> bool:
        """Whether the newest exposure is still the live state (no copy kept yet)."""
        return bool(self._exposures) and self._exposures[-1].data is self.sim.data

    # ---------------------------------------------------------------- frames

    def frame(self) -> CameraFrame:
        """The frame the camera delivers now (the newest, or ``latency_frames`` older)."""
        exposure = self._exposures[0]
        if exposure.frame is None:
            exposure.frame = self._make_frame(exposure)
        return exposure.frame

    def made_frame(self) -> CameraFrame | None:
        """The frame ``frame`` gives now if it was already made (by whoever asked), else None:
        it renders nothing, so any thread may ask."""
        return self._exposures[0].frame

    def _make_frame(self, exposure: _Exposure) -> CameraFrame:
        with _OPENCV_ONE_THREAD:
            return self._expose(exposure)

    def _expose(self, exposure: _Exposure) -> CameraFrame:
        data = exposure.data
        pose = (data.cam_xpos[self.camera_id].copy(), data.cam_xmat[self.camera_id].reshape(3, 3).copy())
        if self.sensor is None:
            rendered = self._render(data, "rgb")
            picture = rendered if self._remap is None else self._lens_remap(rendered, cv2.INTER_LINEAR)
            return CameraFrame(exposure.index, exposure.frame_number, exposure.settings, pose, rgb=picture)
        rendered = self._render(data, "rgba")
        if self.sensor.settings != exposure.settings:
            self.sensor.configure(exposure.settings, self.sensor.robot)
        motion = self.image_motion(data, exposure.settings.exposure_s)
        light = self.light.exposure_gain(data.time, exposure.settings.exposure_s)
        ycrcb = self.sensor.expose(rendered, motion, self.seed, exposure.index, light)
        return CameraFrame(exposure.index, exposure.frame_number, exposure.settings, pose, ycrcb=ycrcb)

    def image_motion(self, data: mujoco.MjData, seconds: float) -> tuple[float, float]:
        """How far (du, dv pixels) the image moves in ``seconds`` at the camera's angular velocity
        in ``data`` (rotation only: what turns the head and the body)."""
        mujoco.mj_objectVelocity(self.model, data, mujoco.mjtObj.mjOBJ_CAMERA, self.camera_id, self._velocity, 1)
        wx, wy = self._velocity[0], self._velocity[1]  # about the camera's right and up axes
        return float(self.lens.fx * wy * seconds), float(self.lens.fy * wx * seconds)

    def _lens_remap(self, image: np.ndarray, interpolation: int) -> np.ndarray:
        """The render as the lens draws it (the ``ideal`` picture of a distorted lens, and the
        labels). Nearest-neighbour lookups (labels) use float maps: OpenCV's fixed-point maps
        would round down."""
        maps = cv2.convertMaps(*self._remap, cv2.CV_32FC1) if interpolation == cv2.INTER_NEAREST else self._remap
        return cv2.remap(image, *maps, interpolation, borderMode=cv2.BORDER_REPLICATE)

    @property
    def render_size(self) -> tuple[int, int]:
        """(width, height) of the render the picture is made from."""
        return (self.width, self.height) if self._pinhole is None else (self._pinhole.width, self._pinhole.height)

    def draws_in_parallel(self) -> bool:
        """Whether this camera draws outside the world's render lock, in parallel with the other
        robots' cameras (``Renderer.parallel``: a match, with a software OpenGL); makes its
        renderer if it has none yet."""
        return self._made_renderer().parallel

    def _render(self, data: mujoco.MjData, kind: str) -> np.ndarray:
        renderer = self._made_renderer()
        render = {
            "rgb": renderer.render,
            "rgba": renderer.render_rgba,
            "depth": renderer.render_depth,
            "segmentation": renderer.render_segmentation,
        }[kind]
        return render(data, self.camera_id)

    def _made_renderer(self) -> Renderer:
        if self._renderer is None:
            with self.sim.world.render_lock:  # its geoms read from the groups: not while another changes them
                self._renderer = Renderer(
                    self.model,
                    *self.render_size,
                    groups=(*HEAD_CAMERA_GROUPS, BEHIND_CAMERA_GROUP),
                    hidden=self.own_geoms(),
                    distant=self.other_robots_geoms(),
                    pinholes=None if self._pinhole is None else {self.camera_id: self._pinhole_intrinsics()},
                    lock=self.sim.world.render_lock if len(self.sim.world.robots) > 1 else None,
                )
        return self._renderer

    def _pinhole_intrinsics(self) -> tuple:
        """The model camera's ``(cam_intrinsic, cam_sensorsize, cam_resolution)`` for the pinhole
        render the lens's picture is resampled from."""
        pinhole = self._pinhole
        pitch = 1e-5  # metres per render pixel: any value, as long as the three agree
        # MuJoCo's principal point offsets (metres) are the image centre less the principal
        # point in image axes (x right, y down): positive values move the principal point left, up.
        offset = ((pinhole.width - 1) / 2 - pinhole.centre[0], (pinhole.height - 1) / 2 - pinhole.centre[1])
        return (
            (pinhole.focal * pitch, pinhole.focal * pitch, offset[0] * pitch, offset[1] * pitch),
            (pinhole.width * pitch, pinhole.height * pitch),
            (pinhole.width, pinhole.height),
        )

    def _other_robots(self) -> np.ndarray:
        """Whether each geom belongs to another robot of the world."""
        model = self.model
        others = [robot._body for robot in self.sim.world.robots if robot is not self.sim]
        return np.isin(model.body_rootid[model.geom_bodyid], model.body_rootid[others])

    def own_geoms(self) -> np.ndarray:
        """Ids of the geoms this camera never draws: those of group ``BEHIND_CAMERA_GROUP`` but the
        other robots' (in a match, each camera sees the other robots whole)."""
        return np.flatnonzero((self.model.geom_group == BEHIND_CAMERA_GROUP) & ~self._other_robots())

    def other_robots_geoms(self) -> np.ndarray:
        """Ids of the other robots' geoms: drawn only where they span a pixel (``Renderer``)."""
        return np.flatnonzero(self._other_robots())

    # ---------------------------------------------------------------- labels

    def exposure_data(self) -> mujoco.MjData:
        """The state the current frame is exposed in (the live one until the next joint frame):
        what its labels and its frames.jsonl record are made from."""
        return self._exposures[0].data

    def depth(self) -> np.ndarray:
        """Metres along the optical axis at each pixel of the current frame, float32 (h, w)."""
        depth = self._render(self.exposure_data(), "depth")
        return depth if self._remap is None else self._lens_remap(depth, cv2.INTER_NEAREST)

    def segmentation(self) -> np.ndarray:
        """Geom id at each pixel of the current frame, int32 (h, w); -1 where nothing is drawn."""
        ids = self._render(self.exposure_data(), "segmentation")
        if self._remap is None:
            return ids
        return self._lens_remap(ids.astype(np.float32), cv2.INTER_NEAREST).astype(np.int32)

    def project(self, points_world, frame: CameraFrame | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Pixels (n, 2) (x right, y down, pixel centres at integers; NaN behind the camera) and
        depths (n,) of world points in a frame (default: the current one), through the lens."""
        frame = frame or self.frame()
        relative = np.asarray(points_world, dtype=np.float64).reshape(-1, 3) - frame.position
        return self.lens.project(relative @ frame.xmat @ _MUJOCO_TO_OPENCV)

    def image_offset(self, point_world) -> tuple[tuple[float, float], bool]:
        """A world point's offset from the image centre in half-widths and half-heights (x right,
        y down) and whether it is in front of the camera and inside the image."""
        frame = self.frame()
        # The camera frame's axes are the columns of xmat, y and z flipped (``project``), in floats.
        relative = [float(p) - c for p, c in zip(point_world, frame.position.tolist())]
        x, y, z = [relative[0] * m[0] + relative[1] * m[1] + relative[2] * m[2] for m in zip(*frame.xmat.tolist())]
        pixel = self.lens.project_point(x, -y, -z)
        if pixel is None:
            return (0.0, 0.0), False
        u, v = pixel
        x, y = (u + 0.5) / (self.width / 2) - 1, (v + 0.5) / (self.height / 2) - 1
        return (x, y), abs(x) <= 1 and abs(y) <= 1

    def close(self) -> None:
        """Free the renderer; a second call does nothing."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
