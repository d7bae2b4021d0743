"""Settings as frozen, typed objects: the head camera (``CameraConfig``) and the world a run
starts in (``WorldConfig``). Each is built once at an edge (the command line, an environment's
constructor, a dump shard), checked there (a ``ParameterError`` naming the parameter), handed
whole to the library, recorded in ``run.json`` and a dump's ``meta.json`` (``as_dict``) and read
back from them (``from_dict``).
"""

from __future__ import annotations

import math
import numbers
import reprlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from openr_bridge import FULL_HEIGHT, FULL_WIDTH

from .camera import CameraProfile, CameraSettings, camera_profile, camera_size
from .field import BALL_TYPES, DEFAULT_BALL_TYPE

MAX_MAGNITUDE = 1e6  # |value| beyond this is a typo, not a position (metres) or an angle (degrees)
SEED_LIMIT = 2**64  # seeds are whole numbers below this (the camera's noise mixes 64 bits of them)
DEFAULT_DURATION_S = 10.0  # simulated seconds of a run, a match or a dump not told how long


def is_seed(value, count: int = 1) -> bool:
    """Whether ``value`` and the ``count - 1`` whole numbers after it are all seeds."""
    return not isinstance(value, bool) and isinstance(value, numbers.Integral) and 0 <= value <= SEED_LIMIT - count


class ParameterError(ValueError):
    """An argument that cannot be used, made by ``at``: the message leads with the parameter and
    its value (``pose 0.62 -0.06 0: the robot would overlap the ball by 1.2 cm``) and may end
    with ``fix``, another parameter that would set it right."""

    parameter: str
    fix: str | None

    @classmethod
    def at(cls, parameter: str, value, reason: str, fix: str | None = None) -> ParameterError:
        """The error for ``parameter`` at ``value``: ``"<parameter> <value>: <reason> [<fix>]"``.

        :param fix: another parameter that would set it right, named last in the message.
        """
        error = cls(f"{parameter} {value}: {reason}" + (f" {fix}" if fix else ""))
        error.parameter, error.fix = parameter, fix
        return error

    def named(self, name: Callable[[str], str]) -> str:
        """The message with ``name(parameter)`` for each parameter it names (the CLI's option);
        text put before it (a dump shard's folder) stays."""
        text = str(self).replace(f"{self.parameter} ", f"{name(self.parameter)} ", 1)
        if self.fix:
            text = text.removesuffix(f" {self.fix}") + f" {name(self.fix)}"
        return text


NO_PATH = "an empty string names no file or folder"  # a path made of it would name the working folder


def refuse_empty_path(parameter: str, value) -> None:
    """ParameterError naming ``parameter`` for an empty string given as a file or folder's name."""
    if isinstance(value, str) and not value:
        raise ParameterError.at(parameter, "''", NO_PATH)


def start_values(name: str, values, count: int) -> tuple[float, ...] | None:
    """``values`` (a pose or ball position given to a function, not through argparse) as a tuple
    of ``count`` finite floats, or None; a ``ParameterError`` naming the parameter ``name`` otherwise."""
    if values is None:
        return None
    try:
        if isinstance(values, (str, bytes)):
            raise TypeError  # "123" is not three numbers
        values = tuple(values)
        if any(isinstance(v, (str, bytes, bool)) for v in values):
            raise TypeError  # nor True one
        numbers = tuple(float(v) for v in values)
    except (TypeError, ValueError, OverflowError):  # OverflowError: an int beyond a float (10**400)
        raise ParameterError.at(name, reprlib.repr(values), f"must be {count} numbers") from None
    shown = " ".join(map(str, numbers))
    if len(numbers) != count or not all(math.isfinite(v) for v in numbers):
        raise ParameterError.at(name, shown, f"must be {count} finite numbers")
    if any(abs(v) > MAX_MAGNITUDE for v in numbers):
        raise ParameterError.at(name, shown, f"out of range (at most {MAX_MAGNITUDE:g} in magnitude)")
    return numbers


@dataclass(frozen=True)
class CameraConfig:
    """The head camera: its ``profile`` (``ers7``, ``ideal``, or a ``CameraProfile``: sensor,
    lens, noise, latency), ``full`` (the sensor's 416 x 320 instead of layer H's 208 x 160) and
    the ``settings`` it starts with (white balance, gain, shutter). The light it meets is the
    scene's (``SceneLight``, from the scene file)."""

    profile: str | CameraProfile = "ers7"
    full: bool = False
    settings: CameraSettings = field(default_factory=CameraSettings)

    def __post_init__(self):
        try:
            resolved = camera_profile(self.profile)
        except (KeyError, ValueError, TypeError) as exc:
            raise ParameterError.at("camera_profile", self.profile, f"not a camera profile ({exc})") from None
        object.__setattr__(self, "profile", resolved)
        if not isinstance(self.full, bool):
            raise ParameterError.at("camera_full", self.full, "must be True or False")
        if not isinstance(self.settings, CameraSettings):
            raise ParameterError.at("camera_settings", self.settings, "must be a CameraSettings")

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) of its pictures."""
        return camera_size(self.full)

    def as_dict(self) -> dict:
        """The keys ``HeadCamera.describe`` records (profile, its options, settings) and ``full``."""
        return {
            "profile": self.profile.name,
            "profile_options": self.profile.options(),
            "full": self.full,
            **self.settings.as_dict(),
        }

    @classmethod
    def from_dict(cls, recorded: dict) -> CameraConfig:
        """The config ``as_dict`` recorded, or the one a ``run.json``/``meta.json`` camera entry
        (``HeadCamera.describe``) describes (``full`` then from its size)."""
        _check_recorded(recorded, "camera", "profile")
        full = recorded.get("full", (recorded.get("width"), recorded.get("height")) == (FULL_WIDTH, FULL_HEIGHT))
        settings = CameraSettings(**{k: recorded[k] for k in CameraSettings().as_dict() if k in recorded})
        if not isinstance(full, bool):
            raise ParameterError.at("full", repr(full), "must be true or false")
        options = recorded.get("profile_options")
        try:
            profile = camera_profile(recorded["profile"], options)
        except (TypeError, ValueError, AttributeError, KeyError) as exc:  # an unknown option, a value of another kind
            if not options:  # the name alone: one that is no profile
                name = reprlib.repr(recorded["profile"])
                raise ParameterError.at("profile", name, f"not a camera profile ({exc})") from None
            raise ParameterError.at(
                "profile_options", reprlib.repr(options), f"not the profile's options ({exc})"
            ) from None
        return cls(profile, full, settings)


@dataclass(frozen=True)
class WorldConfig:
    """Where a run starts: the ``scene`` file (None: the RoboCup field), the ``seed`` of every
    noise stream, the robot's ``pose`` (x, y metres, yaw degrees; None: the scene's start), the
    ball's position ``ball`` (x, y; None: the scene's) and its type ``ball_type``
    (``field.BALL_TYPES``)."""

    scene: str | None = None
    seed: int = 0
    pose: tuple[float, float, float] | None = None
    ball: tuple[float, float] | None = None
    ball_type: str = DEFAULT_BALL_TYPE

    def __post_init__(self):
        if self.scene is not None:
            refuse_empty_path("scene", self.scene)
            object.__setattr__(self, "scene", str(self.scene))
        if not is_seed(self.seed):
            raise ParameterError.at("seed", self.seed, "must be a whole number from 0 to 2**64 - 1")
        object.__setattr__(self, "seed", int(self.seed))
        object.__setattr__(self, "pose", start_values("pose", self.pose, 3))
        object.__setattr__(self, "ball", start_values("ball", self.ball, 2))
        if self.ball_type not in BALL_TYPES:
            raise ParameterError.at("ball_type", self.ball_type, f"must be one of {', '.join(BALL_TYPES)}")

    def as_dict(self) -> dict:
        """The keys ``run.json`` records them under."""
        return {
            "scene": self.scene,
            "seed": self.seed,
            "pose": None if self.pose is None else list(self.pose),
            "ball": None if self.ball is None else list(self.ball),
            "ball_type": self.ball_type,
        }

    @classmethod
    def from_dict(cls, recorded: dict) -> WorldConfig:
        """The config ``as_dict`` (or a run's ``run.json``) recorded; a dict with none of its keys
        is refused (a misspelt key, or a dump's ``meta.json``, which holds them under ``parameters``)."""
        _check_recorded(recorded, "world")
        defaults = cls().as_dict()
        if not any(key in recorded for key in defaults):
            raise ParameterError.at(
                "world",
                reprlib.repr(recorded),
                f"has none of {', '.join(defaults)} (a dump's meta.json: its 'parameters')",
            )
        return cls(**{key: recorded.get(key, default) for key, default in defaults.items()})


def _check_recorded(recorded, what: str, *required: str) -> None:
    """A ParameterError unless ``recorded`` is a dict holding the ``required`` keys."""
    if not isinstance(recorded, Mapping):
        raise ParameterError.at(what, reprlib.repr(recorded), "a recorded config is a dict (as_dict's, run.json's)")
    missing = [key for key in required if key not in recorded]
    if missing:
        raise ParameterError.at(what, reprlib.repr(recorded), f"has no {missing[0]!r}")


def configs(world=None, camera=None) -> tuple[WorldConfig, CameraConfig]:
    """``world`` and ``camera``, the defaults for None; a TypeError naming the one that is not a
    ``WorldConfig`` or ``CameraConfig`` (``from_dict`` reads a recorded dict)."""
    world, camera = world if world is not None else WorldConfig(), camera if camera is not None else CameraConfig()
    for value, kind, name in ((world, WorldConfig, "world"), (camera, CameraConfig, "camera")):
        if not isinstance(value, kind):
            kind_name = kind.__name__
            raise TypeError(
                f"{name} must be a {kind_name} ({kind_name}.from_dict reads a recorded dict), not {reprlib.repr(value)}"
            )
    return world, camera
