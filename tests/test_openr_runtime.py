"""The host OPEN-R runtime's semantics, with OPEN-R objects of our own (tests/openr_programs),
built by the host SDK with Sony-style Makefiles and run on the simulated ERS-7."""

import gzip
import json
import os
import re
import shutil
import signal
import struct
import subprocess
import threading
import wave

import numpy as np
import pytest
from openr_support import build_programs, make, make_stick, run_stick
from test_match import ROOT, ctrl_c_at

import openr_bridge
from aibo_sim import ers7
from aibo_sim.cli import main
from aibo_sim.files import SymlinkRefused
from aibo_sim.match import run_match
from aibo_sim.openr import host, mkbin
from aibo_sim.openr.host import MemoryStickRun, OpenRObjectCrashed
from aibo_sim.openr.sdk import sdk_root
from aibo_sim.sim import Simulation
from aibo_sim.team import RobotSpec
from openr_bridge import ConfigError, host_protocol
from openr_bridge.cdt import OCdtVectorData, orange_ball_cdt, pink_ball_cdt
from openr_bridge.config import parse_stub_cfg
from openr_bridge.memory_stick import load_memory_stick
from openr_bridge.stubgen import generate

pytestmark = pytest.mark.slow  # heavy: run by CI and by python -m pytest -m slow

PAN = ers7.JOINT_INDEX["head_pan"]
EFFECTOR = "OVirtualRobotComm.Effector.OCommandVectorData.O"
SENSOR = "OVirtualRobotComm.Sensor.OSensorFrameVectorData.S"
IMAGE = "OVirtualRobotComm.FbkImageSensor.OFbkImageVectorData.S"
JOINT_PROBE = f"JointProbe.Move.OCommandVectorData.S {EFFECTOR}\n{SENSOR} JointProbe.Sensor.OSensorFrameVectorData.O\n"


@pytest.fixture(scope="module")
def objects(tmp_path_factory):
    return build_programs(tmp_path_factory.mktemp("openr"))


def test_stubgen2_numbers_entries_as_sony_does():
    stub = parse_stub_cfg(
        "ObjectName : Probe\nNumOfOSubject : 2\nNumOfOObserver : 3\n"
        'Service : "Probe.A.X.S", null, Ready()\nService : "Probe.B.X.S", Control(), null\n'
        'Service : "Probe.C.X.O", null, Notify()\nService : "Probe.D.X.O", Connect(), null\n'
        'Service : "Probe.E.X.O", null, null\nExtra : Power()\n'
    )
    files = generate(stub)
    assert set(files) == {"def.h", "entry.h", "ProbeStub.h", "ProbeStub.cc"}
    entry = files["entry.h"]
    for table, selectors in (
        ("Hook   [numOfHook]    ", "0, 1, 2, 3"),
        ("Control[numOfSubject] ", "4, 5"),
        ("Ready  [numOfSubject] ", "6, 7"),
        ("Connect[numOfObserver]", "8, 9, 10"),
        ("Notify [numOfObserver]", "11, 12, 13"),
    ):
        assert f"const Selector Entry_{table} = {{ {selectors} }};" in entry
    assert "const Selector Extra_Entry[] = { 14 };" in entry and "const int entryPower = 0;" in entry
    assert "const longword numOfBasicEntries = 14;" in entry
    definitions = files["def.h"]
    assert "const int sbjA = 0;" in definitions and "const int sbjB = 1;" in definitions
    assert "const int obsE = 2;" in definitions and '"Probe.D.X.O",' in definitions
    stub_cc = files["ProbeStub.cc"]
    for line in (
        "StubFuncDefine_Ready(0, Ready)",
        "StubFuncDefine_Control_nofunc(0)",
        "StubFuncDefine_Control(1, Control)",
        "StubFuncDefine_Ready_nofunc(1)",
        "StubFuncDefine_Notify(0, Notify)",
        "StubFuncDefine_Connect(1, Connect)",
        "StubFuncDefine_Notify_nofunc(2)",
        "{Extra_Entry[0], (Entry)::_Power},",
        "Probe Self;",
    ):
        assert line in stub_cc


def test_the_sdks_stubgen2_and_gzcp_replace_a_link_where_they_write_never_writing_through_it(tmp_path):
    """Both wrote through a link at their output (stubgen2's entry.h, gzcp's .BIN): a file outside
    the stick was overwritten."""
    outside = tmp_path / "outside"
    outside.write_text("kept")
    shutil.copy(ROOT / "tests" / "openr_programs" / "Talker" / "stub.cfg", tmp_path / "stub.cfg")
    (tmp_path / "entry.h").symlink_to(outside)
    bin_folder = sdk_root() / "OPEN_R" / "bin"
    subprocess.run([bin_folder / "stubgen2", "stub.cfg"], cwd=tmp_path, check=True, capture_output=True)
    assert not (tmp_path / "entry.h").is_symlink() and "Generated" in (tmp_path / "entry.h").read_text()
    (tmp_path / "TALKER.BIN").symlink_to(outside)
    subprocess.run([bin_folder / "gzcp", "stub.cfg", "TALKER.BIN"], cwd=tmp_path, check=True)
    assert gzip.decompress((tmp_path / "TALKER.BIN").read_bytes()) == (tmp_path / "stub.cfg").read_bytes()
    assert outside.read_text() == "kept" and not (tmp_path / "TALKER.BIN").is_symlink()
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []  # no temporary file left
    (tmp_path / "folder").mkdir()
    (tmp_path / "LINKED.BIN").symlink_to(tmp_path / "folder")  # a link to a folder is replaced too
    subprocess.run([bin_folder / "gzcp", "stub.cfg", "LINKED.BIN"], cwd=tmp_path, check=True)
    assert not (tmp_path / "LINKED.BIN").is_symlink() and not list((tmp_path / "folder").iterdir())
    done = subprocess.run([bin_folder / "gzcp", "stub.cfg", "folder"], cwd=tmp_path, capture_output=True)
    assert done.returncode != 0 and not list((tmp_path / "folder").iterdir())  # a folder is no object file


def test_stubgen2_takes_what_sonys_takes_comments_and_a_space_before_the_parentheses():
    """Sony's RPlugIn stub.cfg begins with '#' lines; Sony's stubgen2 trims "Ready ()" to Ready."""
    text = "#\n# comment\nObjectName : P\nNumOfOSubject : 1\nNumOfOObserver : 1\n"
    text += 'Service : "P.A.X.S", null, Ready ()\nService : "P.B.X.O", Connect\t(), Notify()\n'
    stub = parse_stub_cfg(text)
    assert [(s.connect_method, s.notify_method, s.line) for s in stub.services] == [
        (None, "Ready", 6),
        ("Connect", "Notify", 7),
    ]
    with pytest.raises(ConfigError, match=r"stub\.cfg:3: expected 'Key : value', got 'Object Name P'"):
        parse_stub_cfg(text.replace("ObjectName :", "Object Name"))


def test_mkbin_reads_the_ocf_as_sonys_gensnap_does(tmp_path, capsys):
    """'object' then 7 or 14 words, '#' comments left out; without one, OUT.ocf (Sony's default)."""
    (tmp_path / "short.ocf").write_text("object Controller 65536\n")
    (tmp_path / "good.ocf").write_text("# hints\nobject good 3072 16384 128 # here\ncache tlb user\n")
    link = "true"  # what the link would run: nothing
    assert mkbin.main(["-o", str(tmp_path / "a.bin"), str(tmp_path / "short.ocf")], link) == 2
    assert f"mkbin: {tmp_path / 'short.ocf'}: ocf format error: expected 'object NAME" in capsys.readouterr().err
    assert mkbin.main(["-o", str(tmp_path / "b.bin"), "x.o"], link) == 2
    assert f"mkbin: {tmp_path / 'b.ocf'}: No such file or directory" in capsys.readouterr().err
    assert mkbin.main(["-o", str(tmp_path / "good.bin")], link) == 0


def test_sdk_structures_read_the_encoders_bytes(tmp_path):
    """A C++ program of the SDK reads an OFbkImageVectorData our encoder wrote, field for field."""
    rgb = np.random.default_rng(3).integers(0, 256, (160, 208, 3), np.uint8)
    message = openr_bridge.encode_frame(
        rgb, frame_number=1234, field_counter=77, cdt=OCdtVectorData.of(orange_ball_cdt())
    )
    (tmp_path / "image.bin").write_bytes(bytes(message))
    (tmp_path / "read.cc").write_text(r"""
#include <OPENR/ODataFormats.h>
#include <OPENR/OFbkImage.h>
static int kind(const OSensorValue&) { return 0; }
static int kind(const OAcceleration&) { return 1; }  /* each quantity a type of its own, as Sony's */
static int kind(const OForce&) { return 2; }
int main() {
    static byte buffer[300000];
    FILE* file = fopen("image.bin", "rb");
    size_t size = fread(buffer, 1, sizeof buffer, file);
    OFbkImageVectorData* image = (OFbkImageVectorData*)buffer;
    printf("%u %u %u %u\n", (unsigned)size, (unsigned)image->vectorInfo.totalSize, (unsigned)image->vectorInfo.numData,
           (unsigned)image->vectorInfo.infoOffset);
    for (int layer = 0; layer < 4; layer++) {
        OFbkImageInfo* info = image->GetInfo(layer);
        printf("%u %u %u %u %u %u\n", (unsigned)info->type, (unsigned)info->frameNumber, (unsigned)info->dataOffset,
               (unsigned)info->dataSize, (unsigned)info->width, (unsigned)info->height);
    }
    OFbkImage y(image->GetInfo(0), image->GetData(0), ofbkimageBAND_Y);
    OFbkImage hh(image->GetInfo(1), image->GetData(1), ofbkimageBAND_Y_HH);
    OFbkImage c(image->GetInfo(3), image->GetData(3), ofbkimageBAND_CDT);
    printf("%u %u %u %u %u %u\n", y.Pixel(17, 33), hh.Pixel(5, 7), c.Pixel(9, 2), (unsigned)y.FieldCounter(),
           (unsigned)c.ColorFrequency(ocdtCHANNEL1), (unsigned)y.Skip());
    printf("%u %u %u\n", (unsigned)sizeof(ODataVectorInfo), (unsigned)sizeof(OCdtVectorData),
           (unsigned)sizeof(OSensorFrameData));
    printf("%d %d %d %u\n", kind(OSensorValue()), kind(OAcceleration()), kind(OForce()), (unsigned)sizeof(OLength));
    return 0;
}
""")
    library = sdk_root() / "OPEN_R" / "lib"
    subprocess.run(
        [
            str(sdk_root() / "bin" / "mipsel-linux-g++"),
            "-Wall",
            "-o",
            "read",
            "read.cc",
            f"-L{library}",
            "-lOPENR",
            f"-Wl,-rpath,{library}",
        ],
        cwd=tmp_path,
        check=True,
    )
    out = subprocess.run(["./read"], cwd=tmp_path, capture_output=True, text=True, check=True).stdout.split("\n")
    assert out[0].split() == [str(len(bytes(message)))] * 2 + ["4", "192"]
    for layer in range(4):
        info = message.GetInfo(layer)
        assert out[1 + layer].split() == [
            str(v) for v in (info.type, 1234, info.dataOffset, info.dataSize, info.width, info.height)
        ]
    h_y, m_hh = message.band(0, openr_bridge.ofbkimageBAND_Y), message.band(1, openr_bridge.ofbkimageBAND_Y_HH)
    c = message.band(3, openr_bridge.ofbkimageBAND_CDT)
    c_band = openr_bridge.OFbkImage(message.GetInfo(3), message.GetData(3), openr_bridge.ofbkimageBAND_CDT)
    assert out[5].split() == [
        str(v)
        for v in (h_y[33, 17], m_hh[7, 5], c[2, 9], 77, c_band.ColorFrequency(openr_bridge.ocdtCHANNEL1), 5 * 208)
    ]
    assert out[6].split() == ["192", str(192 + 8 * 144), "256"]
    assert out[7].split() == ["0", "1", "2", "16"]


API_EDGES = r"""
#include <stdio.h>
#include <OPENR/OPENRAPI.h>
#include <OPENR/ObjcommEvent.h>
#include <OPENR/RCRegion.h>
int main() {
    OPrimitiveID id = 7;
    OStatus status = OPENR::OpenPrimitive(0, &id);
    printf("%d %x\n", (int)status, (unsigned)id);
    MemoryRegionID memID;
    OCommandVectorData* commands = 0;
    OSoundVectorData* sound = 0;
    printf("%d %d\n", (int)OPENR::NewCommandVectorData((size_t)1 << 40, &memID, &commands),
           (int)OPENR::NewSoundVectorData(2, ~(size_t)0 / 2, &memID, &sound));
    char name[] = "Ctl.Out.int.S";
    printf("%d %d %d\n", OControlEvent(0, name, objcommCMD_ADDOBSERVER_V22).IsAddObserver(),
           OControlEvent(0, name, objcommCMD_REMOVEOBSERVER_V22).IsRemoveObserver(),
           OControlEvent(0, name, objcommCMD_ADDOBSERVER_V22).IsRemoveObserver());
    RCRegion* first = new RCRegion(16);
    RCRegion* second = new RCRegion(32);
    ONotifyEvent event;
    event.SetNumOfData(2);
    event.SetData(0, first);
    event.SetData(1, second);
    const void** data = event.Data();
    printf("%d %d\n", data[0] == first->Base(), data[1] == second->Base());
    first->RemoveReference();
    second->RemoveReference();
    return 0;
}
"""


def test_the_api_edges_sony_documents(tmp_path):
    """Level2 Reference Guide: OpenPrimitive gives oprimitiveID_UNDEF when it fails (NULL left the id
    as it was); NewCommandVectorData and NewSoundVectorData say oNO_MEMORY (sizes beyond memory
    crashed on bad_alloc or wrapped round); ONotifyEvent's Data(void) (missing: no compile); a
    subject's Control entry sees an observer added or removed (observers connect with the _V22
    commands, which IsAddObserver did not count)."""
    (tmp_path / "edges.cc").write_text(API_EDGES)
    library = sdk_root() / "OPEN_R" / "lib"
    compiler = str(sdk_root() / "bin" / "mipsel-linux-g++")
    subprocess.run(
        [compiler, "-Wall", "-o", "edges", "edges.cc", f"-L{library}", "-lOPENR", f"-Wl,-rpath,{library}"],
        cwd=tmp_path,
        check=True,
    )
    out = subprocess.run(["./edges"], cwd=tmp_path, capture_output=True, text=True, check=True).stdout
    assert out == "4 ffffffff\n5 5\n1 1 0\n1 1\n"  # oINVALID_ARG, oNO_MEMORY


def test_effector_plays_each_vector_and_asks_for_the_next_after_its_last_frame(objects, tmp_path):
    stick = make_stick(tmp_path / "ms", objects, ["JPROBE"], JOINT_PROBE)
    result = run_stick(stick, 0.3, tmp_path / "out", lambda r: (r.time_ms, r.sim.servos.command[PAN]))
    lines = result.lines("JointProbe")
    readies = [line for line in lines if line.startswith("ready")]
    # The effector's first ready (at boot) comes before the program's DoStart, as on the robot;
    # DoStart primes two vectors and the ready effector takes the first at once. Each later ready
    # comes after a vector's last frame: that vector's region is given back (one reference left:
    # the program's) and the subject sends the other (two: the program's and the one the subject
    # holds until it is played; the effector takes its own when the notification arrives).
    assert readies == [
        "ready before start",
        "ready assert refs 1 2",
        "ready assert refs 2 1",
        "ready assert refs 1 2",
        "ready assert refs 2 1",
        "ready assert refs 1 2",
        "ready assert refs 1 1",
    ]
    assert "no free region" not in lines
    # Sony's manual: a disabled gain reads as zeros with oGAIN_DISABLED; no key is ovrsynckeyUNDEF
    assert "gain before enabled 4108: 0 0 0 0 0 0" in lines
    assert "cancel undefined sync key 4107" in lines
    # Set-points: vector v's frame k is 10 + 4v + k degrees, one frame each, without a gap; then held.
    set_points = np.round(np.degrees([command for _, command in result.frames]), 6)
    expected = [10 + 4 * (k // 4) + k % 4 for k in range(24)] + [33] * (len(set_points) - 24)
    assert np.allclose(set_points, expected, atol=1e-5)
    sensors = [line.split() for line in lines if line.startswith("sensor")]
    assert [int(s[1]) for s in sensors] == list(range(0, 36, 4))  # 4 frames a vector, every 32 ms
    assert {s[2] for s in sensors} == {"4"}
    assert abs(np.degrees(int(sensors[-1][6]) / 1e6) - 33) < 1.5  # the pan got there
    # Each OCommandInfo's frameNumber, written by the effector: the frame its vector started in
    # (Sony's Level2 reference); vector v, from region v % 2, starts in frame 4v.
    assert started_frames(lines) == [4 * v for v in range(6)]
    # The command vectors' optional data reach the sensor vectors (Level2 Reference Guide,
    # ODataVectorInfo): the sensor vector of frames 4v .. 4v + 3 comes after vector v started.
    assert [s[-3:] for s in sensors] == [["4", "1", chr(ord("A") + min(v, 5))] for v in range(9)]


def started_frames(lines: list[str]) -> list[int]:
    """After each ready, the frame that the vector just played started in, as the effector (or the
    speaker) wrote it into its region's info: the probe prints both regions', vector k's is k % 2."""
    started = [int(line.split()[-1]) for line in lines if line.startswith("started region")]
    return [started[2 * k + k % 2] for k in range(len(started) // 2)]


def test_a_vectors_wait_delays_it_by_as_many_frames(objects, tmp_path):
    """ODataVectorInfo::wait "delays commands and the output of sound, for the number of frames
    (in units of 8msec) specified by 'wait'" (Sony's Level2 reference): it was ignored."""
    stick = make_stick(
        tmp_path / "ms", objects, ["JPROBE"], JOINT_PROBE, {"JOINTPROBE_MODE": "MODE.TXT"}, {"MODE.TXT": "wait"}
    )
    result = run_stick(stick, 0.5, tmp_path / "out", lambda r: r.sim.servos.command[PAN])
    # vector 2 waits 25 frames: the pan holds vector 1's last set-point (17 degrees) meanwhile
    expected = [10 + k for k in range(8)] + [17] * 25 + [18 + k for k in range(16)]
    assert np.allclose(np.degrees(result.frames[: len(expected)]), expected, atol=1e-5)
    lines = result.lines("JointProbe")
    assert started_frames(lines) == [0, 4, 33, 37, 41, 45]


@pytest.mark.parametrize("mode", ["nopower", "nogain"])
def test_joints_stay_limp_without_motor_power_or_gain(objects, tmp_path, mode):
    stick = make_stick(
        tmp_path / "ms", objects, ["JPROBE"], JOINT_PROBE, {"JOINTPROBE_MODE": "MODE.TXT"}, {"MODE.TXT": mode}
    )
    result = run_stick(stick, 0.3, tmp_path / "out", lambda r: r.sim.joint_positions()[PAN])
    assert result.lines("JointProbe")[:2] == ["ready before start", f"mode [{mode}]"]
    assert abs(np.degrees(result.frames[-1])) < 2  # commanded to 33 degrees, it did not move


def test_a_closed_primitive_has_no_value_to_get(objects, tmp_path):
    """GetSensorValue and GetJointValue answer oINVALID_PRIMITIVE_ID for a closed primitive, as
    ControlPrimitive does (they read it as open before)."""
    stick = make_stick(
        tmp_path / "ms", objects, ["JPROBE"], JOINT_PROBE, {"JOINTPROBE_MODE": "MODE.TXT"}, {"MODE.TXT": "closed"}
    )
    lines = run_stick(stick, 0.05, tmp_path / "out").lines("JointProbe")
    assert lines[1:3] == ["mode [closed]", "open 0 0 closed 4096 4096"]  # oINVALID_PRIMITIVE_ID


def test_a_vector_that_overruns_its_region_is_not_played_and_its_sender_named(objects, tmp_path):
    """A numData past maxNumData crashed the robot's own OVirtualRobotComm, which was blamed."""
    stick = make_stick(
        tmp_path / "ms", objects, ["JPROBE"], JOINT_PROBE, {"JOINTPROBE_MODE": "MODE.TXT"}, {"MODE.TXT": "overfull"}
    )
    result = run_stick(stick, 0.3, tmp_path / "out")
    assert (
        "OVirtualRobotComm: [ERROR] a command vector from JointProbe: numData 100000 is more than its maxNumData 1: "
        "not played" in result.console
    )
    assert "ready assert" in result.console  # the next vectors are asked for and played


def test_files_are_the_memory_stick_and_the_runs_folder(objects, tmp_path):
    stick = make_stick(
        tmp_path / "ms",
        objects,
        ["FPROBE"],
        design_data={"PROBE_TEXT": "TEXT.TXT"},
        data={"TEXT.TXT": "hello design\n"},
    )
    out = tmp_path / "out"
    result = run_stick(stick, 1.0, out)
    assert result.run.time_ms == 0  # OPENR::Shutdown in DoStart ended the run before its first frame
    lines = result.lines("FileProbe")
    assert lines[:5] == [
        "design ERS-7",
        "design data 13 bytes: hello design",
        "missing design data: 6",
        "write /ms/open-r/mw/data/p/probe.txt: ok",
        "read /MS/OPEN-R/MW/DATA/P/PROBE.TXT: on the stick",
    ]
    assert "write here.txt: ok" in lines and "read /MS/OPEN-R/MW/DATA/P/STREAM.TXT: through a C++ stream" in lines
    assert ["printf 7", "two parts", "puts", "c"] == [
        line for line in lines if line in ("printf 7", "two parts", "puts", "c")
    ]
    for refused in (
        "write /MS/OPEN-R/MW/DATA/P/longer_name.txt: refused (errno 13)",
        "read /etc/hostname: refused (errno 13)",
        "write ../escape.txt: refused (errno 13)",
        "write /MS/../escape.txt: refused (errno 13)",
    ):
        assert refused in lines
    assert "[ERROR] refused to open /etc/hostname: not on the memory stick (/MS)" in lines
    data = stick / "OPEN-R" / "MW" / "DATA" / "P"
    assert sorted(p.name for p in data.iterdir()) == ["PROBE.TXT", "STREAM.TXT", "TEXT.TXT", "UNCLOSED.TXT"]
    assert (data / "UNCLOSED.TXT").read_text() == "written when the object's process ends\n"  # never closed
    assert (out / "here.txt").read_text() == "in the run's folder\n"
    assert not list(tmp_path.rglob("escape.txt")) and not list(tmp_path.rglob("longer_name.txt"))


def test_an_object_opens_no_file_through_a_symbolic_link(objects, tmp_path):
    """Links planted in --out and on the stick (a FAT stick has none) lead nowhere: the object's
    open is refused and logged, what they point to untouched."""
    stick = make_stick(tmp_path / "ms", objects, ["FPROBE"])
    out, victim = tmp_path / "out", tmp_path / "victim.txt"
    victim.write_text("theirs\n")
    out.mkdir()
    (out / "here.txt").symlink_to(victim)
    data = stick / "OPEN-R" / "MW" / "DATA" / "P"
    data.mkdir(parents=True, exist_ok=True)
    (data / "PROBE.TXT").symlink_to(victim)
    lines = run_stick(stick, 1.0, out).lines("FileProbe")
    for path in ("here.txt", "/ms/open-r/mw/data/p/probe.txt"):
        assert f"write {path}: refused (errno 13)" in lines
        assert (
            f"[ERROR] refused to open {path}: a symbolic link (followed by no object: a FAT memory stick has none)"
            in lines
        )
    assert "read /MS/OPEN-R/MW/DATA/P/PROBE.TXT: refused (errno 13)" in lines
    assert victim.read_text() == "theirs\n"


def test_colour_tables_fill_the_cdt_layer_of_the_next_frames(objects, tmp_path):
    stick = make_stick(tmp_path / "ms", objects, ["CDTPROBE"], f"{IMAGE} CdtProbe.Image.OFbkImageVectorData.O\n")
    result = run_stick(stick, 0.1, tmp_path / "out")
    lines = result.lines("CdtProbe")
    # oINVALID_ARG for a channel the ERS-7 lacks and for a channel given twice; the first tables stay
    assert lines[:3] == ["SetCdtVectorData 0", "channel 7 4", "channel 0 twice 4"]
    # The same frames, encoded here with the same tables: the C layer the object read is ours.
    tables = OCdtVectorData.of(pink_ball_cdt(), orange_ball_cdt())
    expected = []
    for index, frame in enumerate(result.images[:3]):
        message = openr_bridge.encode_ycrcb(
            frame.ycrcb, frame_number=frame.frame_number, field_counter=frame.index, cdt=tables
        )
        layer_c = message.band(3, openr_bridge.ofbkimageBAND_CDT)[:-1]
        rows, columns = np.nonzero(layer_c & openr_bridge.ocdtCHANNEL1)
        c = openr_bridge.OFbkImage(message.GetInfo(3), message.GetData(3), openr_bridge.ofbkimageBAND_CDT)
        expected.append(
            f"image {index} frame {frame.frame_number} field {index} camera 1 C 104x80 orange "
            f"{len(rows)} {columns.sum()} {rows.sum()} freq {c.ColorFrequency(openr_bridge.ocdtCHANNEL0)} "
            f"{c.ColorFrequency(openr_bridge.ocdtCHANNEL1)} "
            f"Y(10,20) {message.band(0, openr_bridge.ofbkimageBAND_Y)[20, 10]}"
        )
    assert lines[3:6] == expected
    assert int(expected[0].split()[11]) > 50  # the orange ball is in view: the table finds it


TALKER = (
    f"{SENSOR} Talker.Sensor.OSensorFrameVectorData.O\n{SENSOR} Listener.Sensor.OSensorFrameVectorData.O\n"
    + "".join(f"Talker.Count.int.S Listener.{name}.int.O\n" for name in ("Newest", "Skip", "Pair"))
)


def stop_then_destroy(seconds: float) -> list[str]:
    """Talker's and Listener's console lines when the runtime stops at ``seconds``: every
    object's DoStop, then every object's DoDestroy (Programmer's Guide 2.4)."""
    return [f"[{seconds:9.3f} s] {name}: {entry}" for entry in ("stop", "destroy") for name in ("Talker", "Listener")]


def test_observers_get_data_as_their_buffer_settings_say(objects, tmp_path):
    stick = make_stick(tmp_path / "ms", objects, ["TALKER", "LISTENER"], TALKER)
    result = run_stick(stick, 0.6, tmp_path / "out")
    assert result.lines("Talker")[:12] == [f"sent {n}" for n in range(1, 13)]  # one each 32 ms
    heard = result.lines("Listener")

    def got(name):
        return [line.split(":")[1].split() for line in heard if line.startswith(name)]

    # Sony's default (one unit held): asking again every 4th vector, the newest value, none stale
    assert got("newest") == [["1"], ["4"], ["8"], ["12"]]
    assert got("skip") == [[str(n)] for n in range(1, 13, 2)]  # SetSkip(1): one in two
    assert got("pair") == [[str(n), str(n + 1)] for n in range(1, 13, 2)]  # min 2: two units a notification
    assert all(" data 2 notify 2:" in line for line in heard if line.startswith("pair"))
    stops = [line for line in result.console.splitlines() if line.endswith(("stop", "destroy"))]
    assert stops == stop_then_destroy(0.6)


def test_a_signal_ends_a_run_after_its_objects_stop(objects, tmp_path):
    stick = make_stick(tmp_path / "ms", objects, ["TALKER", "LISTENER"], TALKER)

    def interrupt_at_200_ms(run):
        if run.time_ms == 200:
            signal.raise_signal(signal.SIGINT)

    with pytest.raises(KeyboardInterrupt):
        run_stick(stick, 5.0, tmp_path / "out", interrupt_at_200_ms)
    assert (tmp_path / "out" / "console.log").read_text().splitlines()[-4:] == stop_then_destroy(0.2)


def test_a_memory_stick_in_a_match_stops_its_objects_after_ctrl_c(objects, tmp_path):
    stick = make_stick(tmp_path / "ms", objects, ["TALKER", "LISTENER"], TALKER)
    robots = [
        RobotSpec("red", 1, None, str(stick)),
        RobotSpec("blue", 1, None, str(ROOT / "controllers" / "ball_tracker.py")),
    ]
    with pytest.raises(KeyboardInterrupt):
        run_match(robots, duration=60, out=tmp_path / "out", progress=False, frame_listeners=[ctrl_c_at(0.2)])
    console = (tmp_path / "out" / "robot1" / "console.log").read_text().splitlines()
    untimed = [line.split("] ", 1)[1] for line in console[-4:]]  # the robots stop at their next frame
    assert untimed == [line.split("] ", 1)[1] for line in stop_then_destroy(0.2)]


def test_a_crashing_object_is_named_with_the_signal_and_the_time(objects, tmp_path):
    stick = make_stick(tmp_path / "ms", objects, ["CRASH"], f"{SENSOR} Crash.Sensor.OSensorFrameVectorData.O\n")
    with pytest.raises(
        OpenRObjectCrashed,
        match=r"^OPEN-R object Crash \(entry 7\) crashed \(SIGSEGV: Segmentation fault\) at "
        r"simulated t = 0\.088 s$",
    ):
        run_stick(stick, 1.0, tmp_path / "out")


@pytest.mark.parametrize(
    "how, who",
    [
        # the runtime died between messages: a BrokenPipeError, exit 2, named nothing
        ("thread", r"(the OPEN-R runtime|OPEN-R object Crash \(entry 7\))"),
        # its handler could not run on the overflowed stack: the entry comes from the shared status
        ("stack", r"OPEN-R object Crash \(entry 7\)"),
        # 'OPEN-R object the runtime' before
        ("load", r"OPEN-R object CRASH \(while loading\)"),
    ],
)
def test_a_crash_anywhere_is_named_with_its_object_and_signal(objects, tmp_path, monkeypatch, how, who):
    monkeypatch.setenv("CRASH_HOW", how)
    stick = make_stick(tmp_path / "ms", objects, ["CRASH"], f"{SENSOR} Crash.Sensor.OSensorFrameVectorData.O\n")
    with pytest.raises(OpenRObjectCrashed, match=rf"^{who} crashed \(SIGSEGV: Segmentation fault\) at simulated t = "):
        run_stick(stick, 2.0, tmp_path / "out")


@pytest.mark.parametrize("how", ["fatal", "fatal init", "fatal load"])
def test_openr_fatal_powers_the_robot_off_and_fails_the_run(objects, tmp_path, monkeypatch, how):
    """Sony: Fatal "sounds a warning sound ... and turns off power". It was a Shutdown: DoStop ran,
    the run was done; after Fatal in DoInit the objects' entries ran on (and crashed)."""
    monkeypatch.setenv("CRASH_HOW", how)
    stick = make_stick(tmp_path / "ms", objects, ["CRASH"], f"{SENSOR} Crash.Sensor.OSensorFrameVectorData.O\n")
    code, at = {"fatal": ("ofatalUNDEF", "0.088"), "fatal init": ("ofatalMEMORY_STICK", "0.000")}.get(
        how, ("ofatalPAUSE_SW", "0.000")
    )
    who = "CRASH" if how == "fatal load" else "Crash"  # while loading, an object has its file's name
    out = tmp_path / "out"
    assert main(["run", str(stick), "--duration", "1", "--out", str(out)]) == 1
    error = f"OPEN-R object {who} called OPENR::Fatal({code}) at simulated t = {at} s: the robot's power went off"
    assert json.loads((out / "run.json").read_text())["error"] == f"memory stick ms: {error}"
    console = [line.split("] ", 1)[1] for line in (out / "console.log").read_text().splitlines()]
    off = who + ": [ERROR] OPENR::Fatal({}): the robot's power goes off"  # and no entry runs after it
    if how == "fatal":
        assert console == ["Crash: DoStart", *(f"Crash: sensor vector {n}" for n in (1, 2, 3)), off.format(2**32 - 1)]
    elif how == "fatal init":
        assert console == [off.format(0), "Crash: [WARNING] DoInit returned 2"]
    else:  # DoInit did not run: no service registered, yet no CONNECT.CFG error
        assert console == [off.format(1)]


def test_after_a_fatal_while_loading_no_other_object_is_loaded(objects, tmp_path, monkeypatch):
    """The power is off: the next object's constructors ran before (its output on the console)."""
    monkeypatch.setenv("CRASH_HOW", "fatal load")
    monkeypatch.setenv("JPROBE_SAY", "1")
    stick = make_stick(
        tmp_path / "ms", objects, ["CRASH", "JPROBE"], f"{SENSOR} Crash.Sensor.OSensorFrameVectorData.O\n"
    )
    out = tmp_path / "out"
    assert main(["run", str(stick), "--duration", "1", "--out", str(out)]) == 1
    console = [line.split("] ", 1)[1] for line in (out / "console.log").read_text().splitlines()]
    assert console == ["CRASH: [ERROR] OPENR::Fatal(1): the robot's power goes off"]
    stick = make_stick(
        tmp_path / "ms2", objects, ["JPROBE", "CRASH"], f"{SENSOR} Crash.Sensor.OSensorFrameVectorData.O\n"
    )
    assert main(["run", str(stick), "--duration", "1", "--out", str(tmp_path / "out2")]) == 1
    console = [line.split("] ", 1)[1] for line in (tmp_path / "out2" / "console.log").read_text().splitlines()]
    assert console == ["JPROBE: made", "CRASH: [ERROR] OPENR::Fatal(1): the robot's power goes off"]


def test_get_system_time_is_the_simulated_time_since_boot(objects, tmp_path, monkeypatch):
    monkeypatch.setenv("CRASH_HOW", "clock")  # SystemTime.h and MCOOP.h's GetSystemTime were missing
    stick = make_stick(tmp_path / "ms", objects, ["CRASH"], f"{SENSOR} Crash.Sensor.OSensorFrameVectorData.O\n")
    result = run_stick(stick, 1.1, tmp_path / "out")
    lines = [line for line in result.console.splitlines() if "system time" in line]
    times = [line.split(", ")[0] for line in lines]
    assert times[:2] == ["[    0.024 s] Crash: system time 0.024000", "[    0.056 s] Crash: system time 0.056000"]
    assert times[-1] == "[    1.080 s] Crash: system time 1.080000" and len(times) == 34
    # the robot's sizes (its time_t is 32 bits): 16 and 24 bytes before
    assert lines[0].endswith(", OTime 8 bytes, OBootCondition 16")


def test_an_object_cut_short_or_named_twice_is_refused_naming_its_object_cfg_line(objects, tmp_path, monkeypatch):
    """A truncated .BIN crashed the loader (SIGBUS); a second object of one name never got its data."""
    monkeypatch.setenv("CRASH_HOW", "live")
    connect = f"{SENSOR} Crash.Sensor.OSensorFrameVectorData.O\n"
    stick = make_stick(tmp_path / "ms", objects, ["CRASH", "JPROBE"], connect)
    objs = stick / "OPEN-R" / "MW" / "OBJS"
    whole = gzip.decompress((objs / "JPROBE.BIN").read_bytes())
    (objs / "JPROBE.BIN").write_bytes(whole[:5000])
    with pytest.raises(ConfigError, match=r"OBJECT\.CFG:2: /MS/OPEN-R/MW/OBJS/JPROBE\.BIN is cut short: its headers "):
        run_stick(stick, 0.1, tmp_path / "out")
    relocatable = tmp_path / "x.o"  # a .o copied where the .bin goes: no program headers at all
    subprocess.run(["cc", "-c", "-x", "c", "-", "-o", str(relocatable)], input=b"int x;\n", check=True)
    (objs / "JPROBE.BIN").write_bytes(relocatable.read_bytes())
    with pytest.raises(ConfigError, match=r"OBJECT\.CFG:2: /MS/OPEN-R/MW/OBJS/JPROBE\.BIN: cannot load: "):
        run_stick(stick, 0.1, tmp_path / "out")
    shutil.copy(objs / "CRASH.BIN", objs / "CRASH2.BIN")
    (stick / "OPEN-R" / "MW" / "CONF" / "OBJECT.CFG").write_text(
        "/MS/OPEN-R/MW/OBJS/CRASH.BIN\n/MS/OPEN-R/MW/OBJS/CRASH2.BIN\n"
    )
    with pytest.raises(
        ConfigError,
        match=r"OBJECT\.CFG:2: /MS/OPEN-R/MW/OBJS/CRASH2\.BIN is an object named Crash, as "
        r"/MS/OPEN-R/MW/OBJS/CRASH\.BIN on line 1 is: each object's name must be its own$",
    ):
        run_stick(stick, 0.1, tmp_path / "out2")


def test_what_an_objects_constructor_prints_is_stamped_with_its_name(objects, tmp_path, monkeypatch):
    """The stub names the object once its file is loaded, after its globals were constructed:
    their output, stamped "system" before, is stamped with the file's name (CRASH.BIN)."""
    monkeypatch.setenv("CRASH_HOW", "say")
    stick = make_stick(tmp_path / "ms", objects, ["CRASH"], f"{SENSOR} Crash.Sensor.OSensorFrameVectorData.O\n")
    result = run_stick(stick, 0.05, tmp_path / "out")
    assert result.console.splitlines()[0] == "[    0.000 s] CRASH: made"


@pytest.mark.parametrize(
    "how, status, who, at",
    [
        ("exit", 3, r"Crash \(entry 7\)", "0.088"),
        ("exit load", 5, r"CRASH \(while loading\)", "0.000"),  # in its constructor: named by nothing before
    ],
)
def test_an_object_that_calls_exit_is_named(objects, tmp_path, monkeypatch, how, status, who, at):
    monkeypatch.setenv("CRASH_HOW", how)
    stick = make_stick(tmp_path / "ms", objects, ["CRASH"], f"{SENSOR} Crash.Sensor.OSensorFrameVectorData.O\n")
    with pytest.raises(
        OpenRObjectCrashed,
        match=rf"^the OPEN-R runtime exited with status {status} in OPEN-R object {who} at simulated t = {at} s$",
    ):
        run_stick(stick, 1.0, tmp_path / "out")


def test_an_object_that_never_returns_is_announced_and_one_signal_ends_it(objects, tmp_path, monkeypatch, capfd):
    monkeypatch.setattr(host_protocol, "WAIT_NOTICE_S", 0.2)
    stick = make_stick(tmp_path / "ms", objects, ["SPIN"], f"{SENSOR} Spin.Sensor.OSensorFrameVectorData.O\n")
    timer = threading.Timer(0.1, signal.raise_signal, [signal.SIGINT])  # a Ctrl-C once the notice is out
    announce = host.MemoryStickRun._waiting

    def announce_then_interrupt(run, seconds):
        announce(run, seconds)
        if timer.ident is None:  # not started yet
            timer.start()

    monkeypatch.setattr(host.MemoryStickRun, "_waiting", announce_then_interrupt)
    try:
        with pytest.raises(KeyboardInterrupt):
            run_stick(stick, 5.0, tmp_path / "out")
    finally:
        timer.cancel()
    err = capfd.readouterr().err
    assert (
        "aibo-sim: waiting for OPEN-R object Spin (entry 7): no answer for 0.2 s of wall time (simulated time stays "
        "at t = 0.056 s)" in err
    )
    assert "SIGINT: stopped, with its process group; its objects' Stop entries did not run\n" in err
    # its prompt (no newline yet) was on the console and in the log as it printed it
    assert (tmp_path / "out" / "console.log").read_text().endswith("Spin: spinning> ")

    # In DoInit, before the objects have told their names: named by its file.
    monkeypatch.setenv("CRASH_HOW", "init")
    stick = make_stick(tmp_path / "ms2", objects, ["CRASH"], f"{SENSOR} Crash.Sensor.OSensorFrameVectorData.O\n")
    timer = threading.Timer(0.1, signal.raise_signal, [signal.SIGINT])  # started by the patched announcement
    try:
        with pytest.raises(KeyboardInterrupt):
            run_stick(stick, 5.0, tmp_path / "out2")
    finally:
        timer.cancel()
    assert (
        "aibo-sim: waiting for OPEN-R object /MS/OPEN-R/MW/OBJS/CRASH.BIN (entry 0): no answer"
        in capfd.readouterr().err
    )


def test_an_object_stuck_in_its_stop_entry_after_a_signal_is_named_as_what_did_not_return(
    objects, tmp_path, capfd, monkeypatch
):
    """The closing line said the Stop entries did not run, when they had and one never returned."""
    stick = make_stick(tmp_path / "ms", objects, ["CRASH"], f"{SENSOR} Crash.Sensor.OSensorFrameVectorData.O\n")

    def interrupt_at_200_ms(run):
        if run.time_ms == 200:
            signal.raise_signal(signal.SIGINT)

    monkeypatch.setenv("CRASH_HOW", "stop")
    with pytest.raises(KeyboardInterrupt):
        run_stick(stick, 5.0, tmp_path / "out", interrupt_at_200_ms)
    assert re.search(
        r"SIGINT: stopped, with its process group; OPEN-R object Crash \(entry \d+\) did not return: what came after "
        r"it did not run\n",
        capfd.readouterr().err,
    )


def test_runs_are_deterministic(objects, tmp_path):
    stick = make_stick(
        tmp_path / "ms",
        objects,
        ["JPROBE", "CDTPROBE"],
        JOINT_PROBE + f"{IMAGE} CdtProbe.Image.OFbkImageVectorData.O\n",
    )
    runs = [run_stick(stick, 0.2, tmp_path / f"out{k}", lambda r: r.sim.data.qpos.copy(), seed=5) for k in range(2)]
    assert runs[0].console == runs[1].console and "CdtProbe: image 4" in runs[0].console
    assert np.array_equal(np.array(runs[0].frames), np.array(runs[1].frames))


def test_frame_numbers_wrap_to_one_after_oframe_max_number(objects, tmp_path):
    stick = make_stick(tmp_path / "ms", objects, ["JPROBE"], JOINT_PROBE)
    original = host.MemoryStickRun._start

    def start_late(self, libraries):
        self.sim.world.frame = openr_bridge.ers7_camera.oframeMAX_NUMBER - 5  # the world counts frames
        self.end_ms = self.time_ms + 100
        original(self, libraries)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(host.MemoryStickRun, "_start", start_late)
        result = run_stick(stick, 0.1, tmp_path / "out")
    numbers = [int(line.split()[1]) for line in result.lines("JointProbe") if line.startswith("sensor")]
    maximum = openr_bridge.ers7_camera.oframeMAX_NUMBER
    assert numbers == [maximum - 5, maximum - 1, 3]  # frames maximum - 1, maximum, 1, 2; then 3, 4, 5, 6


def test_connect_cfg_naming_an_unregistered_service_names_its_line(objects, tmp_path):
    stick = make_stick(
        tmp_path / "ms",
        objects,
        ["JPROBE"],
        JOINT_PROBE + "# the next line's observer has no such service\n"
        f"{SENSOR} JointProbe.Sensors.OSensorFrameVectorData.O\n",
    )
    with pytest.raises(
        ConfigError,
        match=r"CONNECT\.CFG:4: JointProbe has no service "
        r"JointProbe\.Sensors\.OSensorFrameVectorData\.O \(it registers ",
    ):
        run_stick(stick, 0.1, tmp_path / "out")


def test_connect_cfg_naming_an_object_without_services_says_it_has_none(objects, tmp_path):
    """Such an object was left out of the objects listed, and said not to be there."""
    line = "FileProbe.Talk.OSensorFrameVectorData.S JointProbe.Sensor.OSensorFrameVectorData.O\n"
    stick = make_stick(tmp_path / "ms", objects, ["JPROBE", "FPROBE"], JOINT_PROBE + line)
    message = r"CONNECT\.CFG:3: FileProbe has no service FileProbe\.Talk\.OSensorFrameVectorData\.S \("
    with pytest.raises(ConfigError, match=message):
        run_stick(stick, 0.1, tmp_path / "out")


def test_an_object_that_is_not_built_for_this_machine_is_refused(objects, tmp_path):
    stick = make_stick(tmp_path / "ms", objects, ["JPROBE"], JOINT_PROBE)
    (stick / "OPEN-R" / "MW" / "OBJS" / "JPROBE.BIN").write_bytes(b"\x1f\x8b" + bytes(20))
    with pytest.raises(ConfigError, match=r"OBJECT\.CFG:1: /MS/OPEN-R/MW/OBJS/JPROBE\.BIN is a damaged gzip file"):
        run_stick(stick, 0.1, tmp_path / "out")
    (stick / "OPEN-R" / "MW" / "OBJS" / "JPROBE.BIN").unlink()
    with pytest.raises(
        ConfigError,
        match=r"OBJECT\.CFG:1: cannot read /MS/OPEN-R/MW/OBJS/JPROBE\.BIN: No such file .*"
        r"\(not built\? run make install",
    ):
        run_stick(stick, 0.1, tmp_path / "out")
    # What Sony's SDK builds for the robot: a 32-bit little-endian MIPS ELF (e_machine 8), gzipped.
    mips = b"\x7fELF\x01\x01\x01" + bytes(11) + (8).to_bytes(2, "little") + bytes(32)
    (stick / "OPEN-R" / "MW" / "OBJS" / "JPROBE.BIN").write_bytes(gzip.compress(mips))
    with pytest.raises(
        ConfigError,
        match=r"OBJECT\.CFG:1: /MS/OPEN-R/MW/OBJS/JPROBE\.BIN is not an object built for this machine "
        r"\(a Sony SDK build for the robot\? rebuild with OPENRSDK_ROOT=\$\(aibo-sim openr sdk\)\)$",
    ):
        run_stick(stick, 0.1, tmp_path / "out")


def test_names_that_are_not_8_3_are_refused_as_the_robot_refuses_them(objects, tmp_path):
    """Sony's Programmer's Guide (A.1): a file name must have 8+3 format. An existing long name was
    found and opened, and OBJECT.CFG could name one, where the robot refuses both."""
    stick = make_stick(tmp_path / "ms", objects, ["FPROBE"], data={"longer_name.txt": "already there\n"})
    lines = run_stick(stick, 1.0, tmp_path / "out").lines("FileProbe")
    assert "write /MS/OPEN-R/MW/DATA/P/longer_name.txt: refused (errno 13)" in lines
    assert "write /MS/OPEN-R/MW/DATA/P/A+B.TXT: refused (errno 13)" in lines
    assert not (stick / "OPEN-R" / "MW" / "DATA" / "P" / "A+B.TXT").exists()
    assert (stick / "OPEN-R" / "MW" / "DATA" / "P" / "longer_name.txt").read_text() == "already there\n"
    objs = stick / "OPEN-R" / "MW" / "OBJS"
    (objs / "FPROBE.BIN").rename(objs / "fileprobe.bin")
    (stick / "OPEN-R" / "MW" / "CONF" / "OBJECT.CFG").write_text("/MS/OPEN-R/MW/OBJS/fileprobe.bin\n")
    with pytest.raises(
        ConfigError,
        match=r"OBJECT\.CFG:1: '/MS/OPEN-R/MW/OBJS/fileprobe\.bin': 'fileprobe\.bin' is not an 8\.3 name of letters",
    ):
        run_stick(stick, 0.1, tmp_path / "out")
    (objs / "fileprobe.bin").rename(objs / "F+PROBE.BIN")
    (stick / "OPEN-R" / "MW" / "CONF" / "OBJECT.CFG").write_text("/MS/OPEN-R/MW/OBJS/F+PROBE.BIN\n")
    with pytest.raises(ConfigError, match=r"OBJECT\.CFG:1: .*'F\+PROBE\.BIN' is not an 8\.3 name of letters, digits"):
        run_stick(stick, 0.1, tmp_path / "out")


def test_a_compile_error_names_the_file_and_line(tmp_path):
    program = tmp_path / "Broken"
    program.mkdir()
    (program / "Broken.cc").write_text("#include <OPENR/OObject.h>\nint f() { return undefined_name; }\n")
    (program / "Makefile").write_text(
        "OPENRSDK_ROOT?=/usr/local/OPEN_R_SDK\nall:\n\t$(OPENRSDK_ROOT)/bin/mipsel-linux-g++ -c Broken.cc\n"
    )
    with pytest.raises(AssertionError, match=r"Broken\.cc:2:\d+: error: .undefined_name. was not declared"):
        make(program)


def test_a_networking_program_is_told_that_networking_is_not_emulated(tmp_path):
    program = tmp_path / "Net"
    program.mkdir()
    (program / "Net.cc").write_text("#include <OPENR/OObject.h>\n#include <ant.h>\n#include <TCPEndpointMsg.h>\n")
    (program / "Makefile").write_text(
        "OPENRSDK_ROOT?=/usr/local/OPEN_R_SDK\nall:\n\t$(OPENRSDK_ROOT)/bin/mipsel-linux-g++ "
        "-I$(OPENRSDK_ROOT)/OPEN_R/include/MCOOP -c Net.cc\n"
    )
    with pytest.raises(
        AssertionError,
        match=r"ant\.h:2:2: error: #error \"MCOOP/ant\.h: aibo-sim's host OPEN-R SDK does "
        r"not emulate networking",
    ):
        make(program)


def test_sensor_vector_values_are_the_simulators_state(objects, tmp_path):
    """JointProbe prints the pan's four values of each sensor vector: the joint's angle at each
    frame, in micro-radians, as the simulator had it at that frame's start."""
    stick = make_stick(tmp_path / "ms", objects, ["JPROBE"], JOINT_PROBE)
    angles = {}  # tick -> the pan's value sent for that frame (at boot, then at frame 0, for tick 0)
    original = host.SensorFrame.at

    def at(self, tick):
        values = original(self, tick)
        angles[tick] = struct.unpack_from("<i", values, self.joints.index(PAN) * 16)[0]
        return values

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(host.SensorFrame, "at", at)
        result = run_stick(stick, 0.2, tmp_path / "out", lambda r: r.sim.joint_positions()[PAN])
    sensors = [line.split() for line in result.lines("JointProbe") if line.startswith("sensor")]
    for line in sensors:
        first = int(line[1])
        assert [int(v) for v in line[3:7]] == [angles[first + k] for k in range(4)]
    assert angles[4] == round(result.frames[3] * 1e6)  # the state after frame 3 is frame 4's


def test_power_status_its_observers_and_the_face_lights(objects, tmp_path):
    stick = make_stick(tmp_path / "ms", objects, ["PPROBE"])
    result = run_stick(stick, 0.1, tmp_path / "out")
    lines = result.lines("PowerProbe")
    battery = host.BATTERY
    status = (
        f"robot 0x{battery['robotStatus']:08x} battery 0x{battery['batteryStatus']:04x} capacity "
        f"{battery['remainingCapacity']} temperature {battery['temperature']} full "
        f"{battery['fullyChargedCapacity']} voltage {battery['voltage']} current {battery['current']}"
    )
    powered = status.replace(f"robot 0x{battery['robotStatus']:08x}", f"robot 0x{battery['robotStatus'] | 2:08x}")
    assert lines == [
        f"status {status}",
        "observe 0",
        "observe again 4101",  # oALREADY_REGISTERED
        f"notified {powered}",
        "unobserve 0",
    ]
    # the face lights it lit: the B face's colours and spots where it asked for B (Model
    # Information 3.1.1 and A.2): B1 green on the left, B14 a blue pair at the bottom, A13 a red pair
    model = result.run.sim.model
    for name, colour in (
        ("led_face_bottom_outer_l", ers7.LED_BY_NAME["led_mode_g"].colour),
        ("led_face_lowest_outer_l", (0.2, 0.4, 1.0)),
        ("led_face_lowest_outer_r", (0.2, 0.4, 1.0)),
        ("led_face_upper_inner_l", (1.0, 0.1, 0.1)),
        ("led_face_upper_inner_r", (1.0, 0.1, 0.1)),
        ("led_face_bottom_outer_r", ers7.LED_OFF_RGBA[:3]),
        ("led_face_top_outer_l", ers7.LED_OFF_RGBA[:3]),  # A14's spot
    ):
        assert np.allclose(model.geom(name).rgba, [*colour, 1.0]), name


def test_the_speaker_plays_sound_vectors_one_after_the_other_into_a_wav_file(objects, tmp_path):
    stick = make_stick(
        tmp_path / "ms",
        objects,
        ["SPROBE"],
        "SoundProbe.Speaker.OSoundVectorData.S OVirtualRobotAudioComm.Speaker.OSoundVectorData.O\n",
    )
    out, victims = tmp_path / "out", [tmp_path / "victim.wav", tmp_path / "victim.log"]
    out.mkdir()
    for victim in victims:
        victim.write_bytes(b"theirs")
    (out / "speaker.wav").symlink_to(victims[0])  # links planted where the run writes: neither followed
    os.link(victims[1], out / "console.log")
    result = run_stick(stick, 0.5, out)
    assert [victim.read_bytes() for victim in victims] == [b"theirs", b"theirs"]
    assert not (out / "speaker.wav").is_symlink() and (out / "console.log").stat().st_nlink == 1
    lines = result.lines("SoundProbe")
    readies = [line for line in lines if line.startswith("ready")]
    # The boot's ready before DoStart, which fills both regions (as Sony's SoundPlay); then after
    # each vector the region it played is free again (SoundPlay takes it, and had none without).
    assert readies[:3] == ["ready 1 refs 1 1 before start", "ready 2 refs 1 2", "ready 3 refs 2 1"]
    assert len(readies) == 11 and "no free region" not in readies  # the boot's, then one after each of ten
    with wave.open(str(tmp_path / "out" / "speaker.wav")) as sound:
        assert (sound.getframerate(), sound.getnchannels(), sound.getsampwidth()) == (16000, 1, 2)
        samples = np.frombuffer(sound.readframes(sound.getnframes()), "<i2").astype(int)
    tone = np.trunc(10000 * np.sin(2 * np.pi * 1000 * np.arange(5120) / 16000)).astype(int)
    assert len(samples) == 5120 and np.abs(samples - tone).max() <= 1  # from t = 0, without a gap
    assert started_frames(lines) == [4 * k for k in range(10)]  # each OSoundInfo's frameNumber


def test_the_sound_so_far_is_kept_when_a_run_ends_early_and_a_link_at_its_temporary_file_is_refused_first(
    objects, tmp_path
):
    """A signal, a crash or a frame not written threw the sound away; a link at .speaker.wav.tmp
    was found only after the whole run."""
    stick = make_stick(
        tmp_path / "ms",
        objects,
        ["SPROBE"],
        "SoundProbe.Speaker.OSoundVectorData.S OVirtualRobotAudioComm.Speaker.OSoundVectorData.O\n",
    )

    def stop_at_frame_60(run):
        if run.sim.frame == 60:  # the ten vectors, 40 frames of sound, are played by then
            raise RuntimeError("stopped")

    with pytest.raises(RuntimeError, match="stopped"):
        run_stick(stick, 10.0, tmp_path / "out", stop_at_frame_60)
    with wave.open(str(tmp_path / "out" / "speaker.wav")) as sound:
        assert sound.getnframes() == 5120
    planted = tmp_path / "planted"
    planted.mkdir()
    (planted / ".speaker.wav.tmp").symlink_to(tmp_path / "victim")
    with pytest.raises(SymlinkRefused):
        run_stick(stick, 0.5, planted)
    assert not (tmp_path / "victim").exists() and not (planted / "console.log").exists()


def test_a_sound_vectors_wait_delays_its_output(objects, tmp_path):
    """The third vector waits 10 frames (ODataVectorInfo::wait): 1280 samples of silence at 16 kHz
    before it, its frameNumber 10 frames later, the vectors after it as much later."""
    stick = make_stick(
        tmp_path / "ms",
        objects,
        ["SPROBE"],
        "SoundProbe.Speaker.OSoundVectorData.S OVirtualRobotAudioComm.Speaker.OSoundVectorData.O\n",
        {"SOUNDPROBE_MODE": "MODE.TXT"},
        {"MODE.TXT": "wait"},
    )
    result = run_stick(stick, 0.6, tmp_path / "out")
    with wave.open(str(tmp_path / "out" / "speaker.wav")) as sound:
        samples = np.frombuffer(sound.readframes(sound.getnframes()), "<i2").astype(int)
    tone = np.trunc(10000 * np.sin(2 * np.pi * 1000 * np.arange(5120) / 16000)).astype(int)
    expected = np.concatenate([tone[:1024], np.zeros(1280, int), tone[1024:]])
    assert len(samples) == len(expected) and np.abs(samples - expected).max() <= 1
    assert started_frames(result.lines("SoundProbe")) == [0, 4, 18, 22, 26, 30, 34, 38, 42, 46]


def test_a_link_at_the_console_log_is_refused_before_the_run(objects, tmp_path):
    stick = make_stick(tmp_path / "ms", objects, ["JPROBE"], JOINT_PROBE)
    (tmp_path / "console.log").symlink_to(tmp_path / "victim")
    sim = Simulation()
    try:
        with pytest.raises(SymlinkRefused, match="console.log is a symbolic link"):
            MemoryStickRun(sim, load_memory_stick(stick), tmp_path, log_path=tmp_path / "console.log")
    finally:
        sim.close()
    assert not (tmp_path / "victim").exists()


def test_foretold_frames_change_nothing_but_the_number_of_messages(objects, tmp_path):
    """The runtime's lookahead (host_protocol: frames stepped without a message) gives the run of
    a message every frame: the same joints, set-points, console and sound, frame for frame,
    with sensor vectors, images, effector and speaker ready events and power events."""
    stick = make_stick(
        tmp_path / "ms",
        objects,
        ["JPROBE", "CDTPROBE", "SPROBE", "PPROBE"],
        JOINT_PROBE
        + f"{IMAGE} CdtProbe.Image.OFbkImageVectorData.O\n"
        + "SoundProbe.Speaker.OSoundVectorData.S OVirtualRobotAudioComm.Speaker.OSoundVectorData.O\n",
    )
    runs, messages = [], []
    for ahead in (host_protocol.LOOKAHEAD_FRAMES, 0):
        sent = []
        original = host.MemoryStickRun._send

        def send(self, kind, payload, sent=sent, original=original):
            sent.append(kind)
            original(self, kind, payload)

        with pytest.MonkeyPatch.context() as patch:
            patch.setattr(host.protocol, "LOOKAHEAD_FRAMES", ahead)
            patch.setattr(host.MemoryStickRun, "_send", send)
            out = tmp_path / f"out{ahead}"
            runs.append(
                run_stick(
                    stick,
                    0.6,
                    out,
                    lambda r: np.concatenate([r.sim.data.qpos, r.sim.servos.command, r.sim.data.ctrl]),
                    seed=7,
                )
            )
            runs[-1].sound = (out / "speaker.wav").read_bytes()
        messages.append(sent.count(host_protocol.MESSAGES["FRAME"]))
    foretold, plain = runs
    assert len(plain.frames) == 75 and messages[1] == 75  # a message every frame without lookahead
    assert messages[0] < 0.6 * messages[1]  # most frames need none (31 of 75 messages when written)
    assert foretold.console == plain.console and foretold.sound == plain.sound
    for name in ("JointProbe", "CdtProbe", "SoundProbe", "PowerProbe"):
        assert foretold.lines(name)
    assert np.array_equal(np.array(foretold.frames), np.array(plain.frames))


def test_the_runtimes_image_messages_are_the_encoders(objects, tmp_path):
    """The runtime makes the messages of the ers7 sensor's frames itself (RAW_IMAGE): every one
    is encode_ycrcb's, byte for byte, colour tables, tag and all (but for the region and
    primitive IDs, which the runtime sets on every image), and the run is the one in which this
    process encodes them."""
    stick = make_stick(tmp_path / "ms", objects, ["CDTPROBE"], f"{IMAGE} CdtProbe.Image.OFbkImageVectorData.O\n")
    tables = OCdtVectorData.of(pink_ball_cdt(), orange_ball_cdt())
    made = []  # (camera frame, the message's bytes in the shared memory after the runtime's answer)
    events, reply = host.MemoryStickRun._events, host.MemoryStickRun._reply

    def record_events(self):
        flags, extra = events(self)
        self.raw_frame = None
        if flags & host_protocol.FRAME_FLAGS["RAW_IMAGE"]:
            self.raw_frame = (self.sim.camera.frame(), self._image_slot)
        return flags, extra

    def read_image(self, expected):
        payload = reply(self, expected)
        if getattr(self, "raw_frame", None) is not None:
            frame, slot = self.raw_frame
            assert slot < host_protocol.IMAGE_SLOTS  # CdtProbe gives every image back
            start = host_protocol.SHM_HEADER + slot * host_protocol.MAX_IMAGE_BYTES
            made.append((frame, bytes(self._memory[start : start + 270720])))
            self.raw_frame = None
        return payload

    def normalised(message: bytes) -> bytes:
        data = bytearray(message)
        data[0:4] = bytes(4)  # memRegionID
        for layer in range(4):
            start = 192 + 32 * layer + 4  # primitiveID
            data[start : start + 4] = bytes(4)
        return bytes(data)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(host.MemoryStickRun, "_events", record_events)
        patch.setattr(host.MemoryStickRun, "_reply", read_image)
        made_here = run_stick(stick, 0.3, tmp_path / "out", lambda r: r.sim.data.qpos.copy())
    assert len(made) == 9
    for frame, message in made:
        encoded = bytes(
            openr_bridge.encode_ycrcb(
                frame.ycrcb, frame_number=frame.frame_number, field_counter=frame.index, cdt=tables
            )
        )
        assert normalised(message) == normalised(encoded)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(host.MemoryStickRun, "_runtime_encodes", lambda self, frame: False)
        encoded_here = run_stick(stick, 0.3, tmp_path / "out2", lambda r: r.sim.data.qpos.copy())
    assert made_here.console == encoded_here.console and "CdtProbe: image 8" in made_here.console
    assert np.array_equal(np.array(made_here.frames), np.array(encoded_here.frames))
