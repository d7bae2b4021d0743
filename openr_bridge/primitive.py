"""OPEN-R's primitive API (``OPENR::OpenPrimitive`` / ``ControlPrimitive`` / ``ClosePrimitive``)
for the one primitive modelled here: the head camera, ``PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1``.

On the robot a program changes the camera's settings with (spec ``openr-image.md`` section 1,
``ers7-camera.md`` section 1)::

    OPrimitiveID fbkID;
    OPENR::OpenPrimitive("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1", &fbkID);
    OPrimitiveControl_CameraParam gain(ocamparamGAIN_HIGH);
    OPENR::ControlPrimitive(fbkID, oprmreqCAM_SET_GAIN, &gain, sizeof(gain), 0, 0);

Here the same calls, with the C out-parameter returned::

    status, fbk_id = system.OPENR.OpenPrimitive(CAMERA_LOCATOR)
    status = system.OPENR.ControlPrimitive(fbk_id, oprmreqCAM_SET_GAIN,
                                           OPrimitiveControl_CameraParam(ocamparamGAIN_HIGH))

Like the C API, these return an ``OStatus`` and never raise; ``check(status, what)`` turns a
failure into a ``PrimitiveError`` that names the status. The codes are Sony's (``OStatus.h``).
Sony's Level2 Reference Guide gives ``ControlPrimitive`` three results: ``oSUCCESS``,
``oINVALID_PRIMITIVE_ID`` and ``oINVALID_ARG`` ("request and param are invalid"); so here:

- ``OpenPrimitive`` of a locator no primitive has: ``oNOT_FOUND`` (id ``oprimitiveID_UNDEF``);
- ``ControlPrimitive`` / ``ClosePrimitive`` with an id ``OpenPrimitive`` did not return (or
  one closed since): ``oINVALID_PRIMITIVE_ID``;
- a request code the camera does not know, a missing parameter, one that is not an
  ``OPrimitiveControl_CameraParam`` / integer, a ``paramSize`` other than
  ``sizeof(OPrimitiveControl_CameraParam)`` (4), a value outside 1..3 (``ocamparamUNDEF`` = 0
  included): ``oINVALID_ARG``;
- a camera request Sony defines but this model does not implement (``GET_CDT_TABLE`` 387,
  ``AE_ON``/``AE_OFF`` 388/389, ``AWB_ON``/``AWB_OFF`` 390/391): ``oNOT_SUPPORTED`` (an
  aibo-sim choice: the robot does them).

A failed request changes nothing. A successful one updates ``OCameraPrimitive.settings`` and
calls its listeners with the change, e.g. ``{"gain": "high"}`` (the simulator passes it to
its camera, which exposes the next frame with it: a frame already exposed keeps its
settings, as on the robot).
"""

from __future__ import annotations

import numbers
from collections.abc import Callable
from dataclasses import dataclass

from .errors import PrimitiveError
from .ers7_camera import CAMERA_DEFAULTS, CAMERA_LOCATOR, CAMERA_SETTINGS, oprmreqCAM_BASE

# OStatus (Sony's OStatus.h): the codes this module returns.
oSUCCESS = 0
oFAIL = 2
oNOT_SUPPORTED = 3
oINVALID_ARG = 4
oNOT_FOUND = 6
oOUT_OF_RANGE = 24
oINVALID_PRIMITIVE_ID = 4096
oINVALID_REQUEST = 4100
OSTATUS_NAMES = {
    oSUCCESS: "oSUCCESS",
    oFAIL: "oFAIL",
    oNOT_SUPPORTED: "oNOT_SUPPORTED",
    oINVALID_ARG: "oINVALID_ARG",
    oNOT_FOUND: "oNOT_FOUND",
    oOUT_OF_RANGE: "oOUT_OF_RANGE",
    oINVALID_PRIMITIVE_ID: "oINVALID_PRIMITIVE_ID",
    oINVALID_REQUEST: "oINVALID_REQUEST",
}

oprimitiveID_UNDEF = 0xFFFFFFFF  # ObjcommTypes.h: the id of no primitive
ocamparamUNDEF = 0  # OPrimitiveControl.h: what OPrimitiveControl_CameraParam() holds
# OPrimitiveControl.h's camera requests this model knows of but does not implement.
oprmreqCAM_GET_CDT_TABLE = oprmreqCAM_BASE + 3
oprmreqCAM_AE_ON, oprmreqCAM_AE_OFF = oprmreqCAM_BASE + 4, oprmreqCAM_BASE + 5
oprmreqCAM_AWB_ON, oprmreqCAM_AWB_OFF = oprmreqCAM_BASE + 6, oprmreqCAM_BASE + 7
_UNSUPPORTED_CAMERA_REQUESTS = {
    oprmreqCAM_GET_CDT_TABLE: "oprmreqCAM_GET_CDT_TABLE",
    oprmreqCAM_AE_ON: "oprmreqCAM_AE_ON",
    oprmreqCAM_AE_OFF: "oprmreqCAM_AE_OFF",
    oprmreqCAM_AWB_ON: "oprmreqCAM_AWB_ON",
    oprmreqCAM_AWB_OFF: "oprmreqCAM_AWB_OFF",
}
# Request code -> (setting name, {Sony value: value name}); and the requests' C names.
CAMERA_REQUESTS = {
    request: (setting, {number: name for name, number in values.items()})
    for setting, (request, values) in CAMERA_SETTINGS.items()
}
REQUEST_NAMES = {
    CAMERA_SETTINGS["white_balance"][0]: "oprmreqCAM_SET_WHITE_BALANCE",
    CAMERA_SETTINGS["gain"][0]: "oprmreqCAM_SET_GAIN",
    CAMERA_SETTINGS["shutter"][0]: "oprmreqCAM_SET_SHUTTER_SPEED",
    **_UNSUPPORTED_CAMERA_REQUESTS,
}
# The C names of each setting's values, for messages.
VALUE_NAMES = {
    "white_balance": {1: "ocamparamWB_INDOOR_MODE", 2: "ocamparamWB_OUTDOOR_MODE", 3: "ocamparamWB_FL_MODE"},
    "gain": {1: "ocamparamGAIN_LOW", 2: "ocamparamGAIN_MID", 3: "ocamparamGAIN_HIGH"},
    "shutter": {1: "ocamparamSHUTTER_SLOW", 2: "ocamparamSHUTTER_MID", 3: "ocamparamSHUTTER_FAST"},
}


def status_name(status: int) -> str:
    """The C name of an OStatus (``oSUCCESS``, ...), or ``OStatus <n>`` for an unknown one."""
    return OSTATUS_NAMES.get(status, f"OStatus {status}")


def allowed_values(setting: str) -> str:
    """'1 (ocamparamGAIN_LOW), 2 (ocamparamGAIN_MID) or 3 (ocamparamGAIN_HIGH)'."""
    names = [f"{number} ({name})" for number, name in VALUE_NAMES[setting].items()]
    return ", ".join(names[:-1]) + " or " + names[-1]


def check(status: int, what: str) -> None:
    """Raise ``PrimitiveError`` naming ``what`` and the status unless ``status`` is ``oSUCCESS``."""
    if status != oSUCCESS:
        raise PrimitiveError(f"{what} returned {status_name(status)} ({status})", status)


@dataclass
class OPrimitiveControl_CameraParam:  # noqa: N801  (Sony's name)
    """``struct OPrimitiveControl_CameraParam { longword camparam; }``."""

    camparam: int = ocamparamUNDEF

    SIZE = 4  # sizeof(OPrimitiveControl_CameraParam)


def sizeof(struct) -> int:
    """``sizeof`` of the parameter structs here (4 for OPrimitiveControl_CameraParam)."""
    return struct.SIZE


class OPrimitive:
    """A primitive: its locator and what ``ControlPrimitive`` does to it."""

    locator: str

    def control(self, request: int, param, param_size: int | None) -> int:
        """What ``ControlPrimitive`` does with ``request``; an OStatus (here ``oINVALID_ARG``)."""
        return oINVALID_ARG


class OCameraPrimitive(OPrimitive):
    """The ERS-7 head camera's settings: white balance, gain, shutter, by name (see
    ``CAMERA_SETTINGS``; Sony's defaults FL, MID, MID unless ``settings`` says otherwise).

    ``listeners`` are called with each successful change, ``{setting: value name}``.
    """

    def __init__(self, settings: dict[str, str] | None = None, locator: str = CAMERA_LOCATOR):
        self.locator = locator
        self._settings = dict(CAMERA_DEFAULTS)
        for setting, value in (settings or {}).items():
            if setting not in CAMERA_SETTINGS or value not in CAMERA_SETTINGS[setting][1]:
                raise ValueError(
                    f"no camera setting {setting}={value!r}: settings are "
                    + "; ".join(f"{s}: {', '.join(v)}" for s, (_, v) in CAMERA_SETTINGS.items())
                )
            self._settings[setting] = value
        self.listeners: list[Callable[[dict[str, str]], None]] = []

    @property
    def settings(self) -> dict[str, str]:
        """The settings last set (a copy): ``{"white_balance": "fl", "gain": "mid", "shutter": "mid"}``."""
        return dict(self._settings)

    def control(self, request: int, param, param_size: int | None) -> int:
        """Apply a ``oprmreqCAM_SET_*`` request; returns an OStatus.

        :param param: an ``OPrimitiveControl_CameraParam`` or its ``camparam`` as an int.
        :param param_size: ``sizeof(param)``, 4; None skips the check.
        :returns: ``oSUCCESS`` (listeners told), ``oNOT_SUPPORTED`` for a camera request not
            modelled, ``oINVALID_ARG`` for any other request or a bad value or size.
        """
        request = int(request) if _is_integer(request) else None
        if request in _UNSUPPORTED_CAMERA_REQUESTS:
            return oNOT_SUPPORTED
        if request not in CAMERA_REQUESTS:
            return oINVALID_ARG
        setting, values = CAMERA_REQUESTS[request]
        if isinstance(param, OPrimitiveControl_CameraParam):
            param = param.camparam
        if param_size is not None and param_size != OPrimitiveControl_CameraParam.SIZE:
            return oINVALID_ARG
        if not _is_integer(param):
            return oINVALID_ARG
        if int(param) not in values:
            return oINVALID_ARG
        change = {setting: values[int(param)]}
        self._settings.update(change)
        for listener in list(self.listeners):
            listener(dict(change))
        return oSUCCESS


def _is_integer(value) -> bool:
    """A C integer: int or numpy integer, not bool (nor float, str...)."""
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


class OPENR:
    """``OPENR::`` for one system's primitives: open, control and close by id."""

    FIRST_ID = 1  # ids count up from here; never oprimitiveID_UNDEF

    def __init__(self, primitives: list[OPrimitive]):
        self.primitives = {primitive.locator: primitive for primitive in primitives}
        self._open: dict[int, OPrimitive] = {}
        self._next_id = self.FIRST_ID

    def OpenPrimitive(self, locator: str) -> tuple[int, int]:
        """``(oSUCCESS, id)``, or ``(oNOT_FOUND, oprimitiveID_UNDEF)`` for an unknown locator."""
        primitive = self.primitives.get(locator) if isinstance(locator, str) else None
        if primitive is None:
            return oNOT_FOUND, oprimitiveID_UNDEF
        primitive_id, self._next_id = self._next_id, self._next_id + 1
        self._open[primitive_id] = primitive
        return oSUCCESS, primitive_id

    def ControlPrimitive(
        self,
        primitive_id: int,
        request: int,
        param=None,
        param_size: int | None = None,
        result=None,
        result_size: int = 0,
    ) -> int:
        """Send ``request`` with ``param`` (an ``OPrimitiveControl_CameraParam`` or its
        ``camparam`` as an int) to an open primitive; an OStatus (see the module docstring).
        ``result`` and ``result_size`` are accepted for the C signature; no request modelled
        here returns a result."""
        primitive = self._open.get(int(primitive_id)) if _is_integer(primitive_id) else None
        if primitive is None:
            return oINVALID_PRIMITIVE_ID
        return primitive.control(request, param, param_size)

    def ClosePrimitive(self, primitive_id: int) -> int:
        """Close an open primitive: ``oSUCCESS``, or ``oINVALID_PRIMITIVE_ID`` for one not open."""
        if not _is_integer(primitive_id) or self._open.pop(int(primitive_id), None) is None:
            return oINVALID_PRIMITIVE_ID
        return oSUCCESS
