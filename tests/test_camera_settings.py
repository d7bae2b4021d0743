"""Camera white balance, gain and shutter at run time: OPEN-R's ControlPrimitive, both backends,
from the next camera frame on."""

import json

import numpy as np
import pytest

import openr_bridge
from aibo_sim import controller as api
from aibo_sim.camera import CameraSettings
from aibo_sim.config import CameraConfig
from aibo_sim.robot import DeviceError, Robot
from aibo_sim.runner import run_controller
from aibo_sim.sim import Simulation
from openr_bridge import (
    CAMERA_LOCATOR,
    Controller,
    NotConnectedError,
    OpenRSystem,
    OPrimitiveControl_CameraParam,
    PrimitiveError,
    oINVALID_ARG,
    oINVALID_PRIMITIVE_ID,
    oINVALID_REQUEST,
    oNOT_FOUND,
    oNOT_SUPPORTED,
    oOUT_OF_RANGE,
    oprimitiveID_UNDEF,
    oSUCCESS,
    sizeof,
)

BACKENDS = ("sim", "openr")
SWITCH_MS = 304  # the controller below switches gain LOW -> HIGH at its first call at or after this time


@pytest.fixture(params=BACKENDS)
def robot(request):
    robot = Robot(Simulation(camera=CameraConfig("ers7")), backend=request.param)
    api.install(robot)
    yield robot
    api.install(None)
    robot.sim.close()


def open_camera(system: OpenRSystem) -> int:
    status, camera_id = system.OPENR.OpenPrimitive(CAMERA_LOCATOR)
    assert status == oSUCCESS and camera_id != oprimitiveID_UNDEF
    return camera_id


def test_status_codes_are_sonys():
    # OStatus.h and OPrimitiveControl.h / ObjcommTypes.h values.
    assert (oSUCCESS, openr_bridge.oFAIL, oNOT_SUPPORTED, oINVALID_ARG, oNOT_FOUND, oOUT_OF_RANGE) == (
        0,
        2,
        3,
        4,
        6,
        24,
    )
    assert (oINVALID_PRIMITIVE_ID, oINVALID_REQUEST, oprimitiveID_UNDEF) == (4096, 4100, 0xFFFFFFFF)
    assert (
        openr_bridge.oprmreqCAM_SET_WHITE_BALANCE,
        openr_bridge.oprmreqCAM_SET_GAIN,
        openr_bridge.oprmreqCAM_SET_SHUTTER_SPEED,
        openr_bridge.oprmreqCAM_AWB_OFF,
    ) == (384, 385, 386, 391)
    assert sizeof(OPrimitiveControl_CameraParam) == 4 and OPrimitiveControl_CameraParam().camparam == 0


def test_control_primitive_changes_the_primitive_and_tells_listeners():
    system = OpenRSystem.from_memory_stick()
    changes = []
    system.camera.listeners.append(changes.append)
    assert system.camera.settings == {"white_balance": "fl", "gain": "mid", "shutter": "mid"}  # Sony's defaults
    fbk = open_camera(system)
    param = OPrimitiveControl_CameraParam(openr_bridge.ocamparamGAIN_HIGH)
    assert system.OPENR.ControlPrimitive(fbk, openr_bridge.oprmreqCAM_SET_GAIN, param, sizeof(param), 0, 0) == oSUCCESS
    assert system.OPENR.ControlPrimitive(fbk, 384, 1) == oSUCCESS  # a bare camparam works too
    assert system.OPENR.ControlPrimitive(fbk, 386, np.int32(3)) == oSUCCESS
    assert system.camera.settings == {"white_balance": "indoor", "gain": "high", "shutter": "fast"}
    assert changes == [{"gain": "high"}, {"white_balance": "indoor"}, {"shutter": "fast"}]


def test_control_primitive_failures_return_the_documented_status_and_change_nothing():
    system = OpenRSystem.from_memory_stick()
    changes = []
    system.camera.listeners.append(changes.append)
    openr = system.OPENR
    assert openr.OpenPrimitive("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F2") == (oNOT_FOUND, oprimitiveID_UNDEF)
    fbk = open_camera(system)
    assert openr.ControlPrimitive(fbk, 999, 1) == oINVALID_ARG  # Level2 Reference Guide: "request ... invalid"
    assert openr.ControlPrimitive(fbk, 383, 1) == oINVALID_ARG
    for request in range(387, 392):  # GET_CDT_TABLE, AE_ON/OFF, AWB_ON/OFF: Sony's, not modelled
        assert openr.ControlPrimitive(fbk, request, 0, 0, 0, 0) == oNOT_SUPPORTED
    for value in (4, 0, -1, 2**32 + 2):
        assert openr.ControlPrimitive(fbk, 385, OPrimitiveControl_CameraParam(value)) == oINVALID_ARG
    for value in ("high", 2.0, True, None):
        assert openr.ControlPrimitive(fbk, 385, value) == oINVALID_ARG
    assert openr.ControlPrimitive(fbk, 385, OPrimitiveControl_CameraParam(3), 8, 0, 0) == oINVALID_ARG
    assert openr.ControlPrimitive(fbk + 100, 385, 3) == oINVALID_PRIMITIVE_ID  # never opened
    assert openr.ControlPrimitive(oprimitiveID_UNDEF, 385, 3) == oINVALID_PRIMITIVE_ID
    assert openr.ClosePrimitive(fbk) == oSUCCESS
    assert openr.ControlPrimitive(fbk, 385, 3) == oINVALID_PRIMITIVE_ID  # closed
    assert openr.ClosePrimitive(fbk) == oINVALID_PRIMITIVE_ID
    assert system.camera.settings == {"white_balance": "fl", "gain": "mid", "shutter": "mid"} and changes == []
    with pytest.raises(PrimitiveError, match=r"OpenPrimitive\(x\) returned oNOT_FOUND \(6\)") as error:
        openr_bridge.check(openr.OpenPrimitive("nowhere")[0], "OpenPrimitive(x)")
    assert error.value.status == oNOT_FOUND and isinstance(error.value, openr_bridge.OpenRError)


def test_wrapper_camera_functions_call_control_primitive():
    system = OpenRSystem.from_memory_stick()
    changes = []
    system.camera.listeners.append(changes.append)
    wrapper = system.controller
    wrapper.camera_set_gain(openr_bridge.ocamparamGAIN_LOW)
    wrapper.camera_set_white_balance(openr_bridge.ocamparamWB_OUTDOOR_MODE)
    wrapper.camera_set_shutter_speed(openr_bridge.ocamparamSHUTTER_SLOW)
    assert changes == [{"gain": "low"}, {"white_balance": "outdoor"}, {"shutter": "slow"}]
    with pytest.raises(
        PrimitiveError,
        match=r"camera_set_gain\(4\): OPENR::ControlPrimitive\(fbkID, "
        r"oprmreqCAM_SET_GAIN, \.\.\.\) returned oINVALID_ARG \(4\); the value must be "
        r"1 \(ocamparamGAIN_LOW\), 2 \(ocamparamGAIN_MID\) or 3 \(ocamparamGAIN_HIGH\)",
    ) as error:
        wrapper.camera_set_gain(4)
    assert error.value.status == oINVALID_ARG
    with pytest.raises(PrimitiveError, match=r"oINVALID_ARG.*ocamparamWB_FL_MODE"):
        wrapper.camera_set_white_balance("fl")
    assert system.camera.settings == {"white_balance": "outdoor", "gain": "low", "shutter": "slow"}
    assert len(changes) == 3
    with pytest.raises(NotConnectedError, match="camera_set_gain: this Controller was not started by an OpenRSystem"):
        Controller().camera_set_gain(3)


def test_control_primitive_385_3_sets_the_simulated_camera_gain_high():
    robot = Robot(Simulation(camera=CameraConfig("ers7")), backend="openr")
    try:
        system, camera = robot.camera_source.system, robot.sim.camera
        fbk = open_camera(system)
        assert camera.settings.gain == "mid"
        assert system.OPENR.ControlPrimitive(fbk, 385, OPrimitiveControl_CameraParam(3), 4, 0, 0) == oSUCCESS
        assert camera.settings == CameraSettings(white_balance="fl", gain="high", shutter="mid")
        assert system.OPENR.ControlPrimitive(fbk, 384, 2) == oSUCCESS
        assert system.OPENR.ControlPrimitive(fbk, 386, 1) == oSUCCESS
        assert camera.settings == CameraSettings(white_balance="outdoor", gain="high", shutter="slow")
        assert system.OPENR.ControlPrimitive(fbk, 385, 4) == oINVALID_ARG
        assert camera.settings.gain == "high"
    finally:
        robot.sim.close()


def test_the_openr_camera_primitive_starts_at_the_simulated_cameras_settings():
    sim = Simulation(camera=CameraConfig(settings=CameraSettings(white_balance="indoor", gain="high", shutter="fast")))
    robot = Robot(sim, backend="openr")
    try:
        assert robot.camera_source.system.camera.settings == {
            "white_balance": "indoor",
            "gain": "high",
            "shutter": "fast",
        }
    finally:
        sim.close()


def test_api_sets_the_camera_on_both_backends(robot):
    camera = api.robot_get_device(CAMERA_LOCATOR)
    api.camera_set_white_balance(camera, api.CAMERA_WB_OUTDOOR)
    api.camera_set_gain(camera, api.CAMERA_GAIN_HIGH)
    api.camera_set_shutter_speed(camera, api.ocamparamSHUTTER_FAST)
    assert robot.sim.camera.settings == CameraSettings(white_balance="outdoor", gain="high", shutter="fast")
    assert robot.get_device(CAMERA_LOCATOR).settings == robot.sim.camera.settings
    if robot.backend == "openr":  # it went through the primitive
        assert robot.camera_source.system.camera.settings == {
            "white_balance": "outdoor",
            "gain": "high",
            "shutter": "fast",
        }
    assert (api.CAMERA_WB_INDOOR, api.CAMERA_WB_OUTDOOR, api.CAMERA_WB_FL) == (1, 2, 3)
    assert (api.CAMERA_GAIN_LOW, api.CAMERA_GAIN_MID, api.CAMERA_GAIN_HIGH) == (1, 2, 3)
    assert (api.CAMERA_SHUTTER_SLOW, api.CAMERA_SHUTTER_MID, api.CAMERA_SHUTTER_FAST) == (1, 2, 3)
    exported = set(api.__all__)
    assert {
        "camera_set_white_balance",
        "camera_set_gain",
        "camera_set_shutter_speed",
        "CAMERA_GAIN_HIGH",
        "ocamparamWB_FL_MODE",
    } <= exported


def test_api_bad_values_raise_device_error_and_change_nothing(robot):
    camera = api.robot_get_device(CAMERA_LOCATOR)
    before = robot.sim.camera.settings
    for value in (4, 0, "high", 2.0, True):
        with pytest.raises(
            DeviceError,
            match=rf"camera_set_gain\({value!r}\): the value must be 1 "
            r"\(ocamparamGAIN_LOW\), 2 \(ocamparamGAIN_MID\) or 3 \(ocamparamGAIN_HIGH\)",
        ) as error:
            api.camera_set_gain(camera, value)
        if robot.backend == "openr":  # refused by ControlPrimitive itself
            assert "OPENR::ControlPrimitive returned" in str(error.value)
            assert isinstance(error.value.__cause__.__cause__, PrimitiveError)
    with pytest.raises(DeviceError, match=r"camera_set_white_balance\(7\).*3 \(ocamparamWB_FL_MODE\)"):
        api.camera_set_white_balance(camera, 7)
    with pytest.raises(DeviceError, match=r"camera_set_shutter_speed\(-1\).*1 \(ocamparamSHUTTER_SLOW\)"):
        api.camera_set_shutter_speed(camera, -1)
    assert robot.sim.camera.settings == before
    with pytest.raises(DeviceError, match="is a servo, not a camera"):
        api.camera_set_gain(api.robot_get_device("PRM:/r1/c1/c2-Joint2:12"), 3)


SWITCHING_CONTROLLER = f"""
import json
from aibo_sim.controller import *

def init():
    global camera, log, switched
    camera = robot_get_device("{CAMERA_LOCATOR}")
    camera_enable(camera, 8)
    camera_set_gain(camera, CAMERA_GAIN_LOW)  # frame 0 is already exposed (MID); LOW from frame 1
    log, switched = [], None

def run(ms):
    global switched
    t = round(robot_get_time() * 1000)
    if ms:
        image = camera_get_image(camera)
        log.append([t, float(image.mean())])
        if switched is None and t >= {SWITCH_MS}:
            camera_set_gain(camera, CAMERA_GAIN_HIGH)  # after reading this frame's picture
            switched = t
    return 8

def die():
    json.dump({{"log": log, "switched": switched}}, open("log.json", "w"))

robot_live(init)
robot_die(die)
robot_run(run)
"""


def test_gain_low_to_high_brightens_from_the_next_frame_not_the_current_one(tmp_path):
    controller = tmp_path / "switch_gain.py"
    controller.write_text(SWITCHING_CONTROLLER)
    brightness = {}
    for backend in BACKENDS:
        out = tmp_path / backend
        run_controller(controller, backend=backend, duration=0.6, out=out, progress=False)
        result = json.loads((out / "log.json").read_text())
        switch_frame = result["switched"] * 30 // 1000
        by_frame = {}
        for t, mean in result["log"]:
            by_frame.setdefault(t * 30 // 1000, []).append(mean)
        assert all(len(set(means)) == 1 for means in by_frame.values())  # one picture per camera frame
        assert len(by_frame[switch_frame]) >= 2  # read before and after the switch within that frame
        frames = {k: means[0] for k, means in by_frame.items()}
        dark = [frames[k] for k in frames if 1 <= k <= switch_frame]
        bright = [frames[k] for k in frames if k > switch_frame]
        assert len(dark) >= 5 and len(bright) >= 5
        assert min(bright) > max(dark) + 20  # HIGH is 4x the signal of LOW
        assert max(dark) < frames[0] < min(bright)  # frame 0: MID, exposed before init ran
        brightness[backend] = frames
    assert brightness["sim"].keys() == brightness["openr"].keys()
    for k in brightness["sim"]:  # the same pictures, up to the colour round trip and the tag bytes
        assert brightness["sim"][k] == pytest.approx(brightness["openr"][k], abs=1.0)


def test_a_frames_picture_keeps_the_settings_of_its_tick():
    changed, reference = (
        Simulation(seed=5, camera=CameraConfig("ers7")),
        Simulation(seed=5, camera=CameraConfig("ers7")),
    )
    try:
        for sim in (changed, reference):
            sim.step_frames(sim.frames_to_camera_frame())  # to a tick: frame 1 exposed, its picture not yet made
        changed.camera.set_settings(white_balance="indoor", gain="high", shutter="slow")  # after the tick
        assert changed.camera.settings == CameraSettings("indoor", "high", "slow")
        frame, same = changed.camera.frame(), reference.camera.frame()
        assert frame.index == same.index == 1
        assert frame.settings == CameraSettings() == same.settings
        np.testing.assert_array_equal(frame.ycrcb, same.ycrcb)
        np.testing.assert_array_equal(frame.message.GetData(0), same.message.GetData(0))
        for sim in (changed, reference):
            sim.step_frames(sim.frames_to_camera_frame())
        frame, same = changed.camera.frame(), reference.camera.frame()
        assert frame.index == same.index == 2 and frame.settings.gain == "high"
        assert frame.ycrcb[..., 0].mean() > same.ycrcb[..., 0].mean() + 20  # high gain, slow shutter: 8x
    finally:
        changed.close()
        reference.close()
