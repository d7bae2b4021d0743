"""The ERS-7's CMOS sensor as a chain of small stages, in the order light goes through it.

Numbers and sources: ``specs/ers7-camera.md`` (section numbers below refer to it). The
rendered frame is read as scene radiance under a neutral light, encoded with the sensor's
gamma (stage 2; so ``ers7`` at neutral settings keeps the ``ideal`` picture's tones).
Then, per frame:

1. time and optics, on the wider pinhole render ``HeadCamera`` draws: motion blur, the
   average along the image motion during the exposure that the camera's angular velocity at
   the frame's tick gives (``omega x exposure x focal length`` px, section 7), taken before
   the lens as light moves across the scene's pinhole image; then the lens (``lens.py``'s
   map, as two 1-D passes, ``lens.Warp``) with a slight softness folded into each pass
   (OpenCV's 3-tap Gaussian, sigma ``softness_px``, fitted to the edges of real frames);
2. exposure and colour: per channel, linear light x scene light colour (a Planckian of the
   scene's ``light_temperature_K``) x white balance gains (von Kries against the preset's
   Planckian, section 6) x exposure (each gain step and each shutter step doubles the
   signal, section 1) x ``sensitivity``, then the on-chip gamma with clipping at 0 and full
   scale. The gamma (UNCONFIRMED) is a pure power, L^(1/``gamma``), 2.2 (sRGB's usual approximation),
   and the render's codes are read with its inverse: a factor k on the light is then a gain
   k^(1/2.2) on the codes, exact for every code, and black stays black at every exposure
   (sRGB's own curve read this way, 1.055 L^(1/2.4) - 0.055 without its linear toe, lifted a
   black target by 4 levels of Y at 2x the light; with the toe, dark codes would need a
   table lookup);
3. YCrCb: Y = 0.299 R + 0.587 G + 0.114 B spanning ``black_level`` .. ``white_level``
   (section 4: a black target reads 19-24, white 250-254), Cr and Cb = 128 + ``chroma_gain`` x
   (R - Y, B - Y). The gain is UNCONFIRMED; chosen: BT.601's (0.713, 0.564), what a CMOS
   camera's YCbCr output uses. The inverse of Sony's decoder (128/255 on both) cannot give
   what real robots read on the field carpet (Cr 101 at Y 52 would need R < 0): the real
   chroma is stronger than the decoder assumes, which is why Sony's RGB looks saturated;
4. vignetting with the blue cast, as measured on output bytes (rUNSWift 2005's table,
   section 3): per channel a quadratic ``c(r) v^2 + a(r) v + b(r)`` through the table's
   columns at each tabulated radius from the channel's own ring centre (within 0.6 levels of
   every entry), linear in r between the radii;
5. per-robot colour: ``v' = pivot + gain (v - pivot) + offset`` per channel (section 4);
6. noise: Gaussian, sigma per channel at MID gain times sqrt(gain factor) (section 4; per
   layer-H pixel: a 416 x 320 picture's pixels draw twice the sigma, its 2 x 2 means the measured one),
   in output levels whatever the brightness: in rUNSWift's table (one gain) the darkest targets
   are no noisier (blue, Y 21: sigma Y 1.1; red 0.9; white, Y 149: 2.0), so a dark scene at
   high gain is noisier against its signal, not in levels; from
   a fixed pool of normal numbers (bytes, in steps of sigma / ``NOISE_STEPS``), each row at an
   offset drawn from (seed, frame index, row): the same frame of the same seed gets the same
   noise whoever asks and in whatever order;
7. rounding and clipping to bytes (Y floor ``y_floor``, below ``black_level``: a black target
   reads the black level, its noise reaching down to the floor).

UNCONFIRMED in the spec, chosen here and configurable: rolling shutter (``readout_ms``,
default 0: off, no source gives the ERS-7's readout time; the last row ends its exposure at
the frame's tick), frame latency (``latency_frames``, default 0), the gamma curve
(``gamma``, 2.2). Chosen and not configurable beyond ``vignetting=False``: the measured
vignetting table (FL / HIGH / FAST) for every setting (ARAIBO's per-setting offsets belong to
its correction, not to a falloff anyone measured).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields, replace
from functools import cache

import cv2
import numpy as np

from openr_bridge import CAMERA_DEFAULTS, CAMERA_SETTINGS, LAYER_SIZE

from .lens import LENSES, Warp

GAIN_STEPS = {"low": -1, "mid": 0, "high": 1}  # -6, 0, +6 dB: each step doubles the signal
SHUTTER_S = {"slow": 1 / 50, "mid": 1 / 100, "fast": 1 / 200}
# Each white balance preset's colour temperature, the one table of them (camera.h's comments are made from it).
WHITE_BALANCE_K = {"indoor": 2856.0, "fl": 5000.0, "outdoor": 6500.0}
REFERENCE_WHITE_K = 6504.0  # the render's neutral light: sRGB's D65 white
# Section 3: rUNSWift 2005's vignetting, raw value at radius r for a centre value, per channel.
VIGNETTING_RADII = (0, 40, 80, 100, 120, 130)
VIGNETTING_TABLE = {  # channel: (centre values, raw values at each radius)
    "Y": (
        (60, 120, 150, 210),
        (
            (60, 120, 150, 210),
            (58, 116, 146, 206),
            (52, 104, 133, 192),
            (48, 95, 123, 182),
            (42, 84, 110, 167),
            (38, 77, 102, 160),
        ),
    ),
    "Cr": ((64, 192), ((64, 192), (68, 188), (79, 177), (88, 168), (100, 157), (107, 150))),
    "Cb": (
        (64, 128, 192),
        ((64, 128, 192), (68, 130, 190), (81, 135, 184), (91, 139, 180), (105, 145, 174), (113, 149, 171)),
    ),
}
RING_CENTRES = ((110.0, 79.5), (105.0, 79.5), (97.0, 79.5))  # Y, Cr, Cb, layer-H pixels
# Section 4: robot-to-robot spread as a linear map per channel, v' = pivot + gain (v - pivot) +
# offset (rUNSWift's correction): the sample sigma over rUNSWift 2005's ten robots of each robot's
# gain and offset, fitted by least squares to its means of the seven targets against the
# robots' average. What no per-channel line explains stays out (1.1-1.4 levels rms: white's Cr
# spreads by 4.8 levels, the line's share of it is 1.9).
ROBOT_PIVOT = (0.0, 128.0, 128.0)
ROBOT_GAIN_SIGMA = (0.034, 0.046, 0.021)
ROBOT_OFFSET_SIGMA = (1.5, 1.8, 2.25)
NOISE_POOL_FRAMES = 8
NOISE_STEPS = 32  # the noise pool's steps per sigma: bytes reach 127 / 32, ~4 sigma
MIN_BLUR_PX = 0.25  # image motion below this is left sharp


@dataclass(frozen=True)
class CameraSettings:
    """What a program sets with ControlPrimitive: white balance, gain, shutter (by name)."""

    white_balance: str = CAMERA_DEFAULTS["white_balance"]
    gain: str = CAMERA_DEFAULTS["gain"]
    shutter: str = CAMERA_DEFAULTS["shutter"]

    def __post_init__(self):
        for name, (_, values) in CAMERA_SETTINGS.items():
            value = getattr(self, name)
            if value not in values:
                raise ValueError(f"camera {name.replace('_', ' ')} must be one of {', '.join(values)}, not {value!r}")

    @property
    def exposure_s(self) -> float:
        """The shutter's exposure time in seconds (``SHUTTER_S``)."""
        return SHUTTER_S[self.shutter]

    @property
    def exposure_factor(self) -> float:
        """Signal relative to MID gain and MID shutter (the nine combinations span 16x)."""
        return 2.0 ** (GAIN_STEPS[self.gain] + round(math.log2(SHUTTER_S[self.shutter] / SHUTTER_S["mid"])))

    def as_dict(self) -> dict:
        """``{"white_balance": ..., "gain": ..., "shutter": ...}``, by name."""
        return {"white_balance": self.white_balance, "gain": self.gain, "shutter": self.shutter}


@dataclass(frozen=True)
class SceneLight:
    """The scene's light as the camera meets it, from the scene's custom numerics: colour
    temperature (``light_temperature_K``) and flicker. Lamps on AC mains ripple at twice the
    mains frequency (``mains_frequency_Hz``) by ``light_flicker_depth`` of their mean: on 50 Hz
    mains MID (1/100 s) and SLOW integrate whole ripples, FAST half of one (section 7), so at FAST
    a frame's brightness depends on when its exposure falls. Default: steady light, as in
    rUNSWift's lab: through the gamma a ripple m moves white's Y (~149) at FAST by ~40 m
    levels (sigma ~28 m over frames), and its 1000-frame sigma, Y 1.8, with 1.7 from the noise
    model, leaves room for m of about 2 % at most."""

    temperature_k: float = 5000.0
    flicker_depth: float = 0.0
    mains_hz: float = 50.0

    def __post_init__(self):
        checks = (
            ("light_temperature_K", self.temperature_k, 1667.0, 25000.0),  # planckian_rgb's range
            ("light_flicker_depth", self.flicker_depth, 0.0, 1.0),
            ("mains_frequency_Hz", self.mains_hz, 1.0, 1000.0),
        )
        for name, value, low, high in checks:
            if not (isinstance(value, (int, float)) and low <= value <= high):  # NaN fails too
                raise ValueError(
                    f"scene custom numeric {name} must be a number from {low:g} to {high:g}, not {value!r}"
                )

    def exposure_gain(self, end_s: float, exposure_s: float) -> float:
        """The light over the exposure [end_s - exposure_s, end_s] relative to its mean, the
        lamp's output being mean x (1 + depth cos(2 pi 2 f t))."""
        if not self.flicker_depth:
            return 1.0
        w = 4 * math.pi * self.mains_hz
        return 1 + self.flicker_depth * (math.sin(w * end_s) - math.sin(w * (end_s - exposure_s))) / (w * exposure_s)

    def as_dict(self) -> dict:
        """The light as the scene's custom numerics name it."""
        return {
            "light_temperature_K": self.temperature_k,
            "light_flicker_depth": self.flicker_depth,
            "mains_frequency_Hz": self.mains_hz,
        }


@dataclass(frozen=True)
class RobotColour:
    """One robot's colour deviation: per channel (Y, Cr, Cb) gain about the pivot and offset."""

    gain: tuple[float, float, float] = (1.0, 1.0, 1.0)
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self):
        values = (*self.gain, *self.offset)
        if len(self.gain) != 3 or len(self.offset) != 3 or not all(math.isfinite(v) for v in values):
            raise ValueError(f"robot colour needs 3 finite gains and 3 finite offsets, not {self.gain}, {self.offset}")

    @classmethod
    def draw(cls, rng: np.random.Generator, scale: float = 1.0) -> RobotColour:
        """A robot drawn from the measured spread (``scale`` 1) or a multiple of it."""
        gain = 1 + scale * np.asarray(ROBOT_GAIN_SIGMA) * rng.standard_normal(3)
        offset = scale * np.asarray(ROBOT_OFFSET_SIGMA) * rng.standard_normal(3)
        return cls(tuple(gain.tolist()), tuple(offset.tolist()))


@dataclass(frozen=True)
class CameraProfile:
    """The head camera's model: ``ideal`` (no effect at all) or a sensor."""

    name: str
    lens: str = "pinhole"  # a key of lens.LENSES
    sensor: bool = False  # False: the rendered RGB is the picture, untouched
    sensitivity: float = 1.0  # signal at MID / MID relative to the render's light
    black_level: float = 20.0  # what a black target reads (section 4: 19-24)
    y_floor: float = 16.0  # Y never below this (section 4: 16-19)
    white_level: float = 252.0
    vignetting: bool = True
    chroma_gain: tuple[float, float] = (0.5 / 0.701, 0.5 / 0.886)  # Cr, Cb per level of R - Y, B - Y: BT.601
    noise_sigma: tuple[float, float, float] = (1.2, 1.5, 2.1)  # Y, Cr, Cb at MID gain
    # OpenCV's 3x3 Gaussian sigma at 208 x 160, from the real frames: step edges in their Y
    # have a median width (erf sigma) of 0.475 px, ours on field views 0.47 with 0.37 (0.62 with
    # 0.5, 0.40 with none). Real edges may be soft themselves: this is the softest the data allow.
    softness_px: float = 0.37
    motion_blur: bool = True
    readout_ms: float = 0.0  # rolling shutter: time from the first row's exposure end to the last's
    gamma: float = 2.2  # stage 2's curve, L ** (1 / gamma): a pure power, black stays black
    latency_frames: int = 0  # a frame is delivered this many camera frames after its exposure
    robot: RobotColour = field(default_factory=RobotColour)

    def __post_init__(self):
        """ValueError naming the first parameter that is not one this model takes."""

        def finite(value) -> bool:
            return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)

        def bad(parameter: str, wanted: str):
            value = getattr(self, parameter)
            raise ValueError(f"camera profile {self.name!r}: {parameter} must be {wanted}, not {value!r}")

        if self.lens not in LENSES:
            bad("lens", "one of " + ", ".join(LENSES))
        for parameter, count in (("chroma_gain", 2), ("noise_sigma", 3)):
            value = getattr(self, parameter)
            if not (isinstance(value, (tuple, list)) and len(value) == count and all(map(finite, value))):
                bad(parameter, f"{count} finite numbers")
        if min(self.noise_sigma) < 0:
            bad("noise_sigma", "3 numbers >= 0")
        for parameter, low, above in (
            ("sensitivity", 0, True),
            ("softness_px", 0, False),
            ("readout_ms", 0, False),
            ("gamma", 0, True),
        ):
            value = getattr(self, parameter)
            if not (finite(value) and (value > low if above else value >= low)):
                bad(parameter, f"a finite number {'>' if above else '>='} {low}")
        levels = (self.y_floor, self.black_level, self.white_level)
        if not (all(map(finite, levels)) and 0 <= self.y_floor <= self.black_level < self.white_level <= 255):
            raise ValueError(
                f"camera profile {self.name!r}: the levels must be 0 <= y_floor <= black_level < white_level <= 255, "
                f"not {levels}"
            )
        if not isinstance(self.latency_frames, int) or isinstance(self.latency_frames, bool) or self.latency_frames < 0:
            bad("latency_frames", "a whole number >= 0")

    def with_options(self, **options) -> CameraProfile:
        """A copy with ``options`` (field names) replaced; ValueError for values out of range."""
        return replace(self, **options)

    def options(self) -> dict:
        """The parameters in which this profile differs from the preset of its name (all of
        them for a name that is no preset), as JSON takes them: what run.json and meta.json
        record beside the name."""

        def as_json(value):
            if isinstance(value, RobotColour):
                return {part: list(values) for part, values in asdict(value).items()}
            return list(value) if isinstance(value, tuple) else value

        preset = PROFILES.get(self.name)
        return {
            f.name: as_json(getattr(self, f.name))
            for f in fields(self)
            if f.name != "name" and (preset is None or getattr(self, f.name) != getattr(preset, f.name))
        }


PROFILES = {
    "ideal": CameraProfile("ideal"),
    "ers7": CameraProfile("ers7", lens="tekkotsu", sensor=True),
}


def camera_profile(profile: str | CameraProfile, options: dict | None = None) -> CameraProfile:
    """A profile by name (``PROFILES``), or the profile itself; with ``options`` (what
    ``CameraProfile.options`` gave), the profile they describe."""
    if isinstance(profile, CameraProfile):
        return profile
    if options:
        values = {
            name: RobotColour(**{part: tuple(v) for part, v in value.items()})
            if name == "robot"
            else tuple(value)
            if isinstance(value, list)
            else value
            for name, value in options.items()
        }
        return PROFILES[profile].with_options(**values) if profile in PROFILES else CameraProfile(profile, **values)
    if profile not in PROFILES:
        raise ValueError(f"camera profile must be one of {', '.join(PROFILES)}, not {profile!r}")
    return PROFILES[profile]


# ---------------------------------------------------------------- colour of light


def planckian_rgb(kelvin: float) -> np.ndarray:
    """Linear sRGB of a Planckian light (Kim et al. 2002 cubic fit of the locus, 1667-25000
    K), scaled to green 1."""
    if not 1667 <= kelvin <= 25000:
        raise ValueError(f"colour temperature must be within 1667..25000 K, not {kelvin}")
    t = float(kelvin)
    if t <= 4000:
        x = -0.2661239e9 / t**3 - 0.2343589e6 / t**2 + 0.8776956e3 / t + 0.179910
    else:
        x = -3.0258469e9 / t**3 + 2.1070379e6 / t**2 + 0.2226347e3 / t + 0.240390
    if t <= 2222:
        y = -1.1063814 * x**3 - 1.34811020 * x**2 + 2.18555832 * x - 0.20219683
    elif t <= 4000:
        y = -0.9549476 * x**3 - 1.37418593 * x**2 + 2.09137015 * x - 0.16748867
    else:
        y = 3.0817580 * x**3 - 5.87338670 * x**2 + 3.75112997 * x - 0.37001483
    xyz = np.array([x / y, 1.0, (1 - x - y) / y])
    rgb = np.array([[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]]) @ xyz
    return rgb / rgb[1]


def light_gains(scene_kelvin: float, white_balance: str) -> np.ndarray:
    """Per-channel factor on linear R, G, B: the scene light's colour relative to the render's
    neutral light, times the white balance preset's von Kries gains (green 1)."""
    light = planckian_rgb(scene_kelvin) / planckian_rgb(REFERENCE_WHITE_K)
    preset = planckian_rgb(WHITE_BALANCE_K[white_balance]) / planckian_rgb(REFERENCE_WHITE_K)
    return light / preset


# ---------------------------------------------------------------- vignetting


@cache
def vignetting_fit() -> np.ndarray:
    """Coefficients (3 channels, radii, 3: v^2, v, 1) of the quadratic through each channel's
    raw values at each tabulated radius (least squares for Y's four columns; Cb's three
    exactly; Cr's two columns give a line). A line leaves Y up to 5 levels and Cb 4.7 off the
    table in the corners (a grey at Y 150 corners 0.71 of the centre where the table says
    0.68); the quadratic, 0.6 at most."""
    fit = np.zeros((3, len(VIGNETTING_RADII), 3))
    for c, (centre, rows) in enumerate(VIGNETTING_TABLE.values()):
        degree = min(2, len(centre) - 1)
        for i, raw in enumerate(rows):
            fit[c, i, 2 - degree :] = np.polyfit(centre, raw, degree)
    return fit


def _along_radius(values: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Linear in r between the tabulated radii, the last segment extended beyond them."""
    radii = np.asarray(VIGNETTING_RADII, dtype=np.float64)
    inside = np.interp(r, radii, values)
    slope = (values[-1] - values[-2]) / (radii[-1] - radii[-2])
    return np.where(r > radii[-1], values[-1] + slope * (r - radii[-1]), inside)


def vignetting_maps(width: int, height: int) -> np.ndarray:
    """Per-pixel quadratic coefficients (v^2, v, 1), (3, h, w, 3) float64, of an image of this size."""
    scale = LAYER_SIZE[0][0] / width  # radii and ring centres are in layer-H pixels
    v, u = np.mgrid[0:height, 0:width].astype(np.float64)
    fit = vignetting_fit()
    maps = np.empty((3, height, width, 3))
    for c, (x0, y0) in enumerate(RING_CENTRES):
        r = np.hypot((u + 0.5) * scale - 0.5 - x0, (v + 0.5) * scale - 0.5 - y0)
        for k in range(3):
            maps[k, ..., c] = _along_radius(fit[c, :, k], r)
    return maps


# ---------------------------------------------------------------- the sensor


@cache
def _noise_pool(length: int) -> np.ndarray:
    """A fixed pool of standard normal numbers in steps of 1 / ``NOISE_STEPS``, as int8 (the
    same on every run; beyond 127 / 32 sigma, clipped: about 1 in 14000)."""
    normal = np.random.default_rng(0x45525337).standard_normal(length, dtype=np.float32)
    return np.clip(np.round(normal * NOISE_STEPS), -127, 127).astype(np.int8)


def noise_rows(seed: int, index: int, rows: int, choices: int) -> np.ndarray:
    """Where each row of frame ``index`` of ``seed`` starts in the noise pool (splitmix64 of the
    three), int64 (rows,): each row drawn apart, so that no two frames share a noise field
    shifted (one offset for the whole frame made frames whose offsets fell close copies of each
    other, moved along the rows)."""
    key = (seed * 0x9E3779B97F4A7C15 + index * 0xBF58476D1CE4E5B9 + 0x94D049BB133111EB) & (2**64 - 1)
    z = np.uint64(key) + np.arange(rows, dtype=np.uint64) * np.uint64(0xD1B54A32D192ED03)
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return ((z ^ (z >> np.uint64(31))) % np.uint64(choices)).astype(np.int64)


def box_average(image: np.ndarray, scale: int) -> np.ndarray:
    """``image`` (uint8, H x W x C) made ``scale`` times smaller: each pixel the mean of its
    ``scale`` x ``scale`` block, rounded half up, in integers (numpy's float mean over the blocks'
    axes cost ~0.8 ms of a layer L observation)."""
    rows = image[0::scale].astype(np.uint16)
    for row in range(1, scale):
        rows += image[row::scale]
    blocks = rows[:, 0::scale].copy()
    for column in range(1, scale):
        blocks += rows[:, column::scale]
    blocks += scale * scale // 2
    blocks //= scale * scale
    return blocks.astype(np.uint8)


class Sensor:
    """Stages 1-7 for one image size: ``expose`` turns the pinhole render into the lens's
    picture in Y, Cr, Cb, through the passes of ``kernels``: ``maps`` (x, y, float (h, w)) say
    where each pixel of the picture lies in the render of ``render_size`` (width, height),
    ``render_scale`` its pixels per picture pixel (x, y)."""

    def __init__(
        self,
        profile: CameraProfile,
        settings: CameraSettings,
        light_temperature_k: float,
        maps: tuple[np.ndarray, np.ndarray],
        render_size: tuple[int, int],
        render_scale: tuple[float, float],
    ):
        self.profile, self.light_temperature_k = profile, light_temperature_k
        self.height, self.width = maps[0].shape
        self.maps, self.render_size, self.render_scale = maps, render_size, render_scale
        from . import kernels  # numba, loaded by the first sensor rather than by every import of aibo_sim

        self._kernels = kernels
        self.warp = Warp.from_maps(*maps, render_size[0], kernels.SLACK)
        # The softness's 3-tap Gaussian (OpenCV's, as GaussianBlur uses), in render pixels.
        sigma = profile.softness_px * self.width / LAYER_SIZE[0][0] * render_scale[0]
        outer, centre, _ = cv2.getGaussianKernel(3, sigma).ravel() if sigma >= 0.05 else (0.0, 1.0, 0.0)
        self._taps = np.float32(outer), np.float32(centre)
        vignetting = (
            vignetting_maps(self.width, self.height)
            if profile.vignetting
            else np.broadcast_to(np.array([0.0, 1.0, 0.0])[:, None, None, None], (3, self.height, self.width, 3))
        )
        self._vignetting_rows, self._coefficient_row = self._distinct_rows(vignetting.transpose(0, 3, 1, 2))
        pixels = self.width * self.height
        self._pool = _noise_pool(NOISE_POOL_FRAMES * pixels * 3).reshape(3, -1)
        self._choices = NOISE_POOL_FRAMES * pixels - self.width + 1
        self._buffers: dict[tuple, np.ndarray] = {}
        self.configure(settings, profile.robot)
        # Every pass loaded now (numba's cache): not at a run's first moving frame, where a
        # Ctrl-C or SIGTERM could land inside llvmlite and leave its objects half made.
        self.expose(np.zeros((render_size[1], render_size[0], 4), np.uint8), (1.0, 1.0), 0, 0)

    def configure(self, settings: CameraSettings, robot: RobotColour) -> None:
        """Take new settings or a new robot: the light's gains, colour maps and noise scale."""
        self.settings, self.robot = settings, robot
        p = self.profile
        self._gains = (
            light_gains(self.light_temperature_k, settings.white_balance) * settings.exposure_factor * p.sensitivity
        )
        self._responses: dict[float, np.ndarray] = {}
        # Sony's forward model with the black level on Y; rows Y, Cr, Cb; columns R, G, B, 1.
        luma = np.array([0.299, 0.587, 0.114])
        y_scale = (p.white_level - p.black_level) / 255
        self._matrix = np.array(
            [
                [*(y_scale * luma), p.black_level],
                [*(p.chroma_gain[0] * (np.array([1.0, 0, 0]) - luma)), 128.0],
                [*(p.chroma_gain[1] * (np.array([0, 0, 1.0]) - luma)), 128.0],
            ],
            np.float32,
        )
        curve, slope, intercept = self._vignetting_rows
        gain, pivot, offset = (np.asarray(values)[:, None, None] for values in (robot.gain, ROBOT_PIVOT, robot.offset))
        # Robot after vignetting: gain (c v^2 + a v + b - pivot) + pivot + offset, per channel.
        self._coefficients = tuple(
            np.ascontiguousarray(values, np.float32)
            for values in (gain * curve, gain * slope, gain * (intercept - pivot) + pivot + offset)
        )
        # Sigma is measured on layer H: a larger picture (416 x 320, --camera-full) draws each pixel's
        # noise stronger by its side's ratio, so that layer H, its 2 x 2 means, reads the same.
        pixels_per_h_pixel = self.width / LAYER_SIZE[0][0]
        sigma = np.asarray(p.noise_sigma) * math.sqrt(2.0 ** GAIN_STEPS[settings.gain]) * pixels_per_h_pixel
        self._noise_scale = (sigma / NOISE_STEPS).astype(np.float32)
        self._y_floor = np.float32(p.y_floor)

    def _distinct_rows(self, planes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The planes (coefficients, channels, h, w) holding each distinct image row once,
        (coefficients, channels, rows, w), and the row each image row reads: the vignetting's
        rings are centred on the middle row, so that the top half mirrors the bottom (half the
        memory the colour pass streams through each frame)."""
        by_row = planes.transpose(2, 0, 1, 3).reshape(self.height, -1)
        distinct, row_of = np.unique(by_row, axis=0, return_inverse=True)
        return distinct.reshape(-1, *planes.shape[:2], self.width).transpose(1, 2, 0, 3), row_of.ravel().astype(
            np.int64
        )

    def _response(self, light: float) -> np.ndarray:
        """Stage 2 as (3,) float32: each channel's gain on the codes for ``light``
        x the scene's mean light (a flickering light takes a few values, frame after frame:
        each is kept)."""
        response = self._responses.get(light)
        if response is None:
            response = self._responses[light] = ((self._gains * light) ** (1 / self.profile.gamma)).astype(np.float32)
        return response

    def _buffer(self, shape: tuple[int, ...], dtype: type) -> np.ndarray:
        """A scratch array of this shape, kept from frame to frame (arrays of a few hundred KB are
        mapped afresh by each allocation, and their pages faulted in); zeros at first, so that
        what a pass computes into the slack is always a number."""
        buffer = self._buffers.get((shape, dtype))
        if buffer is None:
            buffer = self._buffers[(shape, dtype)] = np.zeros(shape, dtype)
        return buffer

    def _rolling_warp(self, motion_px: tuple[float, float]) -> Warp:
        """The warp with each row read where the image was when that row's exposure ended
        (``readout_ms`` after the first row's, the last row's at the frame's tick)."""
        readout = self.profile.readout_ms / 1000
        delay = (self.height - 1 - np.arange(self.height)) / (self.height - 1) * readout / self.settings.exposure_s
        (width, height), (map_x, map_y) = self.render_size, self.maps
        shift_x, shift_y = (m * scale * delay[:, np.newaxis] for m, scale in zip(motion_px, self.render_scale))
        return Warp.from_maps(
            np.clip(map_x + shift_x, 0, width - 1), np.clip(map_y + shift_y, 0, height - 1), width, self._kernels.SLACK
        )

    def expose(
        self, render: np.ndarray, motion_px: tuple[float, float], seed: int, index: int, light: float = 1.0
    ) -> np.ndarray:
        """Y, Cr, Cb (h, w, 3) uint8 of the (h', w', 4) uint8 RGBA pinhole render (alpha unread),
        with ``motion_px`` the image motion (image pixels) and ``light`` the scene's light
        (relative to its mean) during the exposure."""
        kernels = self._kernels
        warp = self._rolling_warp(motion_px) if self.profile.readout_ms > 0 and any(motion_px) else self.warp
        height, width = render.shape[:2]
        slack = kernels.SLACK
        du, dv = motion_px[0] * self.render_scale[0], motion_px[1] * self.render_scale[1]
        if self.profile.motion_blur and math.hypot(du, dv) >= MIN_BLUR_PX:
            dx, dy, weights, reach = kernels.smear_taps(du, dv)
            padded = self._buffer((3, height, width + 2 * reach + slack), np.uint8)
            kernels.split(render, reach, padded)
            planes, level = self._buffer((3, height, width + slack), np.uint16), np.float32(1 / 256)
            kernels.smear(padded, reach, dx, dy, weights, planes)
        else:
            planes, level = self._buffer((3, height, width + slack), np.uint8), np.float32(1)
            kernels.split(render, 0, planes)
        ycrcb = np.empty((self.height, self.width, 3), np.uint8)
        kernels.develop(
            planes,
            warp.rows_frac,
            *warp.rows_runs,
            warp.columns_frac,
            *warp.columns_runs,
            level,
            *self._taps,
            self._response(light),
            self._matrix,
            *self._coefficients,
            self._coefficient_row,
            self._pool,
            self._noise_scale,
            noise_rows(seed, index, self.height, self._choices),
            self._y_floor,
            self._buffer((3, width + 4 + slack), np.float32),
            self._buffer((3, self.width + slack), np.float32),
            ycrcb,
        )
        if self.width > LAYER_SIZE[0][0]:
            # 416 x 320: the sensor's colour is 4:2:2 and OPEN-R keeps it at layer H only (2 x 2
            # means), which is all a program's full picture can have (Sony's Full Band, Tekkotsu)
            chroma = box_average(ycrcb[:, :, 1:], 2)
            ycrcb[:, :, 1:] = chroma.repeat(2, axis=0).repeat(2, axis=1)
        return ycrcb
