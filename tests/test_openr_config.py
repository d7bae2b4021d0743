"""stub.cfg and CONNECT.CFG: the report's formats, memory stick lookup, errors with file and line."""

import pytest

from openr_bridge import (
    DEFAULT_MEMORY_STICK,
    ConfigError,
    OpenRSystem,
    find_connect_cfg,
    load_stub_cfg,
    parse_connect_cfg,
    parse_stub_cfg,
)
from openr_bridge.wiring import DATA_DIR

REPORT_SAMPLE_STUB = """\
ObjectName : SampleClass
NumOfOSubject : 1
NumOfOObserver : 2
Service : "SampleClass.Func1.Data1.S", Control(), Ready()
Service : "SampleClass.Func2.Data2.O", Connect(), Notify1()
Service : "SampleClass.Func3.Data2.O", null, Notify2()
"""

CAMERA_LINE = "OVirtualRobotComm.FbkImageSensor.OFbkImageVectorData.S Controller.Image.OFbkImageVectorData.O"


def test_the_reports_sample_stub():
    stub = parse_stub_cfg(REPORT_SAMPLE_STUB)
    assert stub.object_name == "SampleClass"
    assert [str(s.name) for s in stub.of_kind("O")] == ["SampleClass.Func2.Data2.O", "SampleClass.Func3.Data2.O"]
    first = stub.services[0]
    assert (first.name.sub, first.name.data, first.connect_method, first.notify_method) == (
        "Func1",
        "Data1",
        "Control",
        "Ready",
    )
    assert stub.services[2].connect_method is None and stub.services[2].line == 6


def test_the_shipped_stubs():
    controller = load_stub_cfg(DATA_DIR / "Controller" / "stub.cfg")
    assert controller.object_name == "Controller"
    observer = controller.of_kind("O")[0]
    assert (str(observer.name), observer.connect_method, observer.notify_method) == (
        "Controller.Image.OFbkImageVectorData.O",
        None,
        "Notify",
    )
    assert len(controller.of_kind("S")) == 1  # the dummy subject OPEN-R requires
    robot_comm = load_stub_cfg(DATA_DIR / "OVirtualRobotComm" / "stub.cfg")
    assert str(robot_comm.of_kind("S")[0].name) == "OVirtualRobotComm.FbkImageSensor.OFbkImageVectorData.S"


def test_connect_cfg_with_comments_and_crlf():
    text = (
        b"# camera\r\n\r\n  " + CAMERA_LINE.encode() + b"  # the report's line\r\nA.Send.char.S\tB.Receive.char.O\r\n"
    )
    first, second = parse_connect_cfg(text, "ms/CONNECT.CFG")
    assert (str(first.subject), str(first.observer), first.line) == (CAMERA_LINE.split()[0], CAMERA_LINE.split()[1], 3)
    assert (second.subject.object, second.observer.sub, second.line) == ("A", "Receive", 4)


SUBJECT = 'Service : "X.a.d.S", null, null\n'
OBSERVER = 'Service : "X.b.d.O", null, null\n'


@pytest.mark.parametrize(
    "text, line, words",
    [
        ("ObjectName : X\nNumOfOSubject : 1\nNumOfOObserver : 1\n", 2, "0 subject services"),
        (
            "ObjectName : X\nNumOfOSubject : 1\nNumOfOObserver : 2\n" + SUBJECT + OBSERVER,
            3,
            "NumOfOObserver is 2 but 1",
        ),
        ("ObjectName : X\nNumOfOSubject : 0\nNumOfOObserver : 1\n" + OBSERVER, 2, "at least 1"),
        ("NumOfOSubject : 1\nNumOfOObserver : 1\n" + SUBJECT + OBSERVER, None, "no ObjectName"),
        ("ObjectName : X\nObjectName : Y\n", 2, "twice"),
        ("ObjectName : X\nNumOfOSubjects : 1\n", 2, "unknown item"),
        ("ObjectName : X\nNumOfOSubject : one\nNumOfOObserver : 1\n", 2, "not a number"),
        ('ObjectName : X\nService : "X.a.d.Q", null, null\n', 2, "neither S nor O"),
        ('ObjectName : X\nService : "X.a.S", null, null\n', 2, "not a service name"),
        ('ObjectName : X\nService : "X.a.d.S", null, Notify\n', 2, "expected"),
        ('ObjectName : X\nService : "X.a.d.S", null, null\nService : "X.a.d.S", null, null\n', 3, "listed twice"),
        ("ObjectName X\n", 1, "Key : value"),
        (b"// \xe9t\xe9\nObjectName : X\n", 1, "not ASCII"),
        ("ObjectName : X\u00e9\n", 1, "non-ASCII"),
        ("ObjectName : 9X\nNumOfOSubject : 1\nNumOfOObserver : 1\n", 1, "not a name"),
    ],
)
def test_malformed_stubs_name_file_and_line(text, line, words):
    with pytest.raises(ConfigError, match=words) as caught:
        parse_stub_cfg(text, "Obj/stub.cfg")
    assert caught.value.path == "Obj/stub.cfg" and caught.value.line == line
    assert str(caught.value).startswith("Obj/stub.cfg" if line is None else f"Obj/stub.cfg:{line}:")


@pytest.mark.parametrize(
    "text, line, words",
    [
        (
            "Controller.Image.OFbkImageVectorData.O OVirtualRobotComm.FbkImageSensor.OFbkImageVectorData.S",
            1,
            "should be subject",
        ),
        ("# ok\nA.x.char.S B.y.int.O", 2, "data names differ"),
        ("A.x.char.S", 1, "expected 'subject-service observer-service'"),
        ("A.x.char.S B.y.char.O C.z.char.O", 1, "expected"),
        ("A.x..S B.y.char.O", 1, "not a service name"),
        ("A.x.char.S B.y.char.O\nA.x.char.S  B.y.char.O", 2, "repeated from line 1"),
        (b"A.x.char.S B.y.char.O\n\xff", 2, "not ASCII"),
    ],
)
def test_malformed_connect_cfg_names_file_and_line(text, line, words):
    with pytest.raises(ConfigError, match=words) as caught:
        parse_connect_cfg(text, "MS/CONNECT.CFG")
    assert str(caught.value).startswith(f"MS/CONNECT.CFG:{line}:")


def test_the_reports_spelling_is_rejected_with_a_hint():
    connections = parse_connect_cfg(CAMERA_LINE.replace("OVirtual", "Ovirtual"), "CONNECT.CFG")
    with pytest.raises(ConfigError, match="case-sensitive: did you mean 'OVirtualRobotComm'") as caught:
        OpenRSystem(connections)
    assert caught.value.line == 1


def test_unknown_objects_and_services():
    with pytest.raises(ConfigError, match="unknown object 'Tracker'"):
        OpenRSystem(parse_connect_cfg("# x\n" + CAMERA_LINE.replace("Controller", "Tracker")))
    with pytest.raises(ConfigError, match="Controller has no service Controller.Camera") as caught:
        OpenRSystem(parse_connect_cfg(CAMERA_LINE.replace("Controller.Image", "Controller.Camera")))
    assert str(caught.value).startswith("CONNECT.CFG:1:")
    assert str(caught.value).endswith("a stick built by aibo-sim build-ms runs as itself (aibo-sim run ITS_FOLDER)")


def write(path, text):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def test_memory_stick_folder_in_any_case(tmp_path):
    write(tmp_path / "open-r" / "mw" / "Conf" / "connect.cfg", CAMERA_LINE + "\n")
    assert find_connect_cfg(tmp_path) == tmp_path / "open-r" / "mw" / "Conf" / "connect.cfg"
    system = OpenRSystem.from_memory_stick(tmp_path)
    assert system.controller.observer[0].is_connected()


def test_the_default_memory_stick():
    assert find_connect_cfg(DEFAULT_MEMORY_STICK).read_text().count("OVirtualRobotComm.FbkImageSensor") == 1
    assert OpenRSystem.from_memory_stick().controller.observer[0].is_connected()


def test_missing_or_ambiguous_memory_stick(tmp_path):
    with pytest.raises(ConfigError, match="no OPEN-R"):
        OpenRSystem.from_memory_stick(tmp_path)
    write(tmp_path / "OPEN-R" / "MW" / "CONF" / "CONNECT.CFG", CAMERA_LINE)
    write(tmp_path / "OPEN-R" / "MW" / "CONF" / "connect.cfg", CAMERA_LINE)
    with pytest.raises(ConfigError, match="more than one CONNECT.CFG"):
        find_connect_cfg(tmp_path)
    with pytest.raises(ConfigError, match="cannot read"):
        load_stub_cfg(tmp_path / "nothing" / "stub.cfg")
