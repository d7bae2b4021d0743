"""OPEN-R delivery semantics and the wrapper Controller's camera functions."""

import math
import subprocess
import sys

import numpy as np
import pytest

from openr_bridge import (
    FIELD_OF_VIEW,
    ConfigError,
    Controller,
    ImageAccessError,
    NoImageError,
    NotConnectedError,
    OObject,
    OpenRSystem,
    OVirtualRobotComm,
    camera_image_get_blue,
    camera_image_get_green,
    camera_image_get_red,
    encode_frame,
    ofbkimageBAND_Y,
    ofbkimageLAYER_H,
    parse_connect_cfg,
    parse_stub_cfg,
)
from openr_bridge.report_c import compile_report_c

SLOW_STUB = """\
ObjectName : Slow
NumOfOSubject : 1
NumOfOObserver : 2
Service : "Slow.Dummy.DontConnect.S", null, null
Service : "Slow.Other.char.O", null, null
Service : "Slow.Image.OFbkImageVectorData.O", null, Notify()
"""
SLOW_LINE = "OVirtualRobotComm.FbkImageSensor.OFbkImageVectorData.S Slow.Image.OFbkImageVectorData.O"
CAMERA_LINE = "OVirtualRobotComm.FbkImageSensor.OFbkImageVectorData.S Controller.Image.OFbkImageVectorData.O"


class Slow(OObject):
    """An observer that keeps its events and asserts ready only when told."""

    def __init__(self):
        super().__init__(parse_stub_cfg(SLOW_STUB, "Slow/stub.cfg"))
        self.events = []

    def DoStart(self):
        self.observer[1].AssertReady()

    def Notify(self, event):
        self.events.append(event)


def frame(value: int) -> np.ndarray:
    return np.full((160, 208, 3), value, np.uint8)


@pytest.fixture(scope="module")
def messages():
    return [encode_frame(frame(10 * i)) for i in range(4)]


def test_notify_event_and_ready_semantics(messages):
    robot, slow = OVirtualRobotComm(), Slow()
    OpenRSystem(parse_connect_cfg(SLOW_LINE), [robot, slow])
    robot.publish_image(messages[0])
    (event,) = slow.events
    assert event.Data(0) is messages[0] and event.NumOfData() == 1
    assert event.ObsIndex() == 1 and event.SenderID() is robot.image_subject

    robot.publish_image(messages[1])  # not ready: kept
    robot.publish_image(messages[2])  # replaces it: one dropped
    assert len(slow.events) == 1
    assert robot.image_subject.dropped == {"Slow.Image.OFbkImageVectorData.O": 1}
    slow.observer[event.ObsIndex()].AssertReady(event.SenderID())
    assert [e.Data(0) for e in slow.events] == [messages[0], messages[2]]

    slow.observer[1].AssertReady()
    slow.observer[1].DeassertReady()
    robot.publish_image(messages[3])
    assert len(slow.events) == 2  # deasserted: nothing delivered
    slow.observer[1].AssertReady()
    assert slow.events[-1].Data(0) is messages[3]
    assert robot.image_subject.dropped == {"Slow.Image.OFbkImageVectorData.O": 1}


def test_assert_ready_to_an_unconnected_subject():
    slow = Slow()
    OpenRSystem([], [OVirtualRobotComm(), slow])
    with pytest.raises(NotConnectedError):
        slow.observer[1].AssertReady(OVirtualRobotComm().image_subject)


def test_a_stub_naming_a_missing_method():
    class Mute(OObject):
        pass

    with pytest.raises(ConfigError, match=r"Slow/stub.cfg:6: Mute has no method Notify\(\)"):
        Mute(parse_stub_cfg(SLOW_STUB, "Slow/stub.cfg"))


def test_controller_without_connection_or_image():
    unconnected = OpenRSystem([]).controller
    for call in (unconnected.camera_get_image, unconnected.camera_get_width, unconnected.camera_get_height):
        with pytest.raises(NotConnectedError, match="CONNECT.CFG needs the line"):
            call()
    waiting = OpenRSystem(parse_connect_cfg(CAMERA_LINE)).controller
    with pytest.raises(NoImageError):
        waiting.camera_get_image()
    assert waiting.camera_get_fov() == FIELD_OF_VIEW == 0.993092


def test_fov_is_the_horizontal_56_9_degrees():
    assert math.degrees(FIELD_OF_VIEW) == pytest.approx(56.9, abs=0.001)


def test_controller_serves_the_newest_frame(messages):
    system = OpenRSystem.from_memory_stick()
    for message in messages[:3]:
        system.robot_comm.publish_image(message)
    controller = system.controller
    assert (controller.camera_get_width(), controller.camera_get_height()) == (208, 160)
    image = controller.camera_get_image()
    assert image.shape == (208 * 160 * 3,) and image.dtype == np.uint8
    assert camera_image_get_red(image, 208, 100, 50) == 20  # grey 20: Y 20, Cr = Cb = 128
    assert system.robot_comm.image_subject.dropped == {"Controller.Image.OFbkImageVectorData.O": 0}


def test_camera_get_image_equals_the_reports_c_loop(tmp_path):
    report_c = compile_report_c(tmp_path)
    if report_c is None:
        pytest.skip("no C compiler")
    rgb = np.random.default_rng(5).integers(0, 256, (320, 416, 3), dtype=np.uint8)
    message = encode_frame(rgb, field_counter=999)
    system = OpenRSystem.from_memory_stick()
    system.robot_comm.publish_image(message)
    layer_h = message.GetData(ofbkimageLAYER_H).reshape(160, 6, 208)
    assert np.array_equal(system.controller.camera_get_image(), report_c.camera_get_image(layer_h))


def served_image(controller: Controller, message) -> np.ndarray:
    system = OpenRSystem(parse_connect_cfg(CAMERA_LINE), [OVirtualRobotComm(), controller])
    system.robot_comm.publish_image(message)
    return controller.camera_get_image()


def rgb_at(image, x, y):
    return [get(image, 208, x, y) for get in (camera_image_get_red, camera_image_get_green, camera_image_get_blue)]


def test_pixel_macros_and_restore_tag():
    rgb = frame(0)
    rgb[158, 0:12] = (200, 100, 50)
    rgb[159, 12] = (0, 0, 255)
    message = encode_frame(rgb, field_counter=0xFFFF)
    tagged = served_image(Controller(), message)
    restored = served_image(Controller(restore_tag=True), message)
    # the tag's field counter 0xFFFF makes pixel (0, 159) Y 255 with Cr = Cb = 128: white
    assert rgb_at(tagged, 0, 159) == [255, 255, 255]
    # restored: row 158's Y (124, that of (200, 100, 50)) with row 159's own chroma (black: 128)
    assert message.band(ofbkimageLAYER_H, ofbkimageBAND_Y)[158, 0] == 124
    assert rgb_at(restored, 0, 159) == [124, 124, 124]
    # blue: Y 29, Cr' -15, Cb' 113: R = 29 - 29.9 -> 0, G = 29 + 15.2 - 42.8 = 1.47 -> 1, B = 254.1 -> 254
    assert rgb_at(restored, 12, 159) == rgb_at(tagged, 12, 159) == [0, 1, 254]
    for x, y in [(208, 0), (-1, 0), (0, 160), (0, -1)]:
        with pytest.raises(ImageAccessError):
            camera_image_get_red(tagged, 208, x, y)


def test_openr_bridge_imports_neither_mujoco_nor_aibo_sim():
    check = "import sys, openr_bridge; print(sorted({'mujoco', 'aibo_sim'} & set(sys.modules)))"
    assert subprocess.run([sys.executable, "-c", check], capture_output=True, text=True, check=True).stdout == "[]\n"
