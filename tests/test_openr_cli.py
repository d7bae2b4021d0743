"""Memory sticks on the command line: aibo-sim run and dump with the run family's options, exit
statuses and run.json, aibo-sim openr sdk, aibo-sim build-ms."""

import errno
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import cv2
import pytest
from openr_support import build_programs, make_stick

from aibo_sim import runner
from aibo_sim.cli import main
from aibo_sim.dump import load_dump
from aibo_sim.openr import host

pytestmark = pytest.mark.slow  # heavy: run by CI and by python -m pytest -m slow

ROOT = Path(__file__).resolve().parents[1]
SENSOR = "OVirtualRobotComm.Sensor.OSensorFrameVectorData.S"
IMAGE_PROBE = "OVirtualRobotComm.FbkImageSensor.OFbkImageVectorData.S CdtProbe.Image.OFbkImageVectorData.O\n"
JOINT_PROBE = (
    "JointProbe.Move.OCommandVectorData.S OVirtualRobotComm.Effector.OCommandVectorData.O\n"
    f"{SENSOR} JointProbe.Sensor.OSensorFrameVectorData.O\n"
)


@pytest.fixture(scope="module")
def objects(tmp_path_factory):
    return build_programs(tmp_path_factory.mktemp("openr"))


def test_openr_sdk_prints_a_root_that_sonys_makefiles_use(capsys):
    assert main(["openr", "sdk"]) == 0
    root = Path(capsys.readouterr().out.strip())
    for tool in (
        "bin/mipsel-linux-g++",
        "bin/mipsel-linux-strip",
        "OPEN_R/bin/stubgen2",
        "OPEN_R/bin/mkbin",
        "OPEN_R/lib/libOPENR.so",
        "OPEN_R/lib/libObjectComm.so",
        "OPEN_R/include/OPENR/OObject.h",
    ):
        assert (root / tool).exists(), tool
    assert (root / "OPEN_R" / "include" / "R4000").is_dir()


def test_run_writes_frames_console_and_run_json(objects, tmp_path, capfd):
    stick = make_stick(tmp_path / "program" / "MS", objects, ["JPROBE", "CDTPROBE"], JOINT_PROBE + IMAGE_PROBE)
    out = tmp_path / "out"
    assert (
        main(
            [
                "run",
                str(stick.parent),
                "--duration",
                "0.2",
                "--out",
                str(out),
                "--seed",
                "3",
                "--ball-type",
                "pink",
                "--camera-profile",
                "ideal",
            ]
        )
        == 0
    )
    printed = capfd.readouterr().out  # the objects' console is the runtime's standard output
    assert "JointProbe: sensor 0 4 " in printed and "ran memory stick program/MS on the host OPEN-R runtime" in printed
    run = json.loads((out / "run.json").read_text())
    assert (run["controller"], run["backend"], run["status"], run["seed"], run["ball_type"]) == (
        str(stick),
        "memory stick",
        "done",
        3,
        "pink",
    )
    assert run["camera"]["profile"] == "ideal" and run["simulated_s"] == 0.2
    # the frames CdtProbe observed, at joint frames 0, 5, 9, ..., 21: layer H
    assert len(list((out / "frames").glob("*.png"))) == run["camera_frames"] == 6
    assert cv2.imread(str(out / "frames" / "000000.png")).shape == (160, 208, 3)
    console = (out / "console.log").read_text()
    assert [line for line in console.splitlines() if "JointProbe" in line][:2] == [
        "[    0.000 s] JointProbe: ready before start",
        "[    0.000 s] JointProbe: mode []",
    ]


def test_a_crash_exits_1_keeping_the_frames_and_saying_so_in_run_json(objects, tmp_path, capsys):
    connect = f"{SENSOR} Crash.Sensor.OSensorFrameVectorData.O\n" + IMAGE_PROBE
    stick = make_stick(tmp_path / "ms", objects, ["CRASH", "CDTPROBE"], connect)
    out = tmp_path / "out"
    assert main(["run", str(stick), "--out", str(out)]) == 1
    assert capsys.readouterr().err.strip() == (
        "aibo-sim: memory stick ms: OPEN-R object Crash (entry 7) crashed "
        "(SIGSEGV: Segmentation fault) at simulated t = 0.088 s"
    )
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "failed" and run["simulated_s"] == 0.088 and run["camera_frames"] == 3
    assert len(list((out / "frames").glob("*.png"))) == 3


@pytest.mark.parametrize(
    "arguments, message",
    [
        (["--backend", "openr"], "--backend applies to controllers: {stick} is a memory stick"),
        (["--mtn-mode", "webots"], "--mtn-mode applies to controllers: {stick} is a memory stick"),
    ],
)
def test_a_controllers_options_are_refused_with_a_stick(objects, tmp_path, capsys, arguments, message):
    stick = make_stick(tmp_path / "ms", objects, ["JPROBE"], JOINT_PROBE)
    assert main(["run", str(stick), *arguments, "--out", str(tmp_path / "out")]) == 2
    assert (
        capsys.readouterr().err.strip() == f"aibo-sim: error: {message.format(stick=stick)}, whose OPEN-R "
        "objects run as on the robot"
    )
    assert not (tmp_path / "out").exists()


def test_a_bad_connect_cfg_exits_2_naming_its_line(objects, tmp_path, capsys):
    stick = make_stick(tmp_path / "ms", objects, ["JPROBE"], JOINT_PROBE + "Nobody.X.Y.S JointProbe.Z.Y.O\n")
    out = tmp_path / "out"
    assert main(["run", str(stick), "--duration", "0.1", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    message = (
        f"{stick}/OPEN-R/MW/CONF/CONNECT.CFG:3: no object named 'Nobody' "
        "registers Nobody.X.Y.S (the objects: JointProbe, OVirtualRobotAudioComm, OVirtualRobotComm"
    )
    assert err.startswith(f"aibo-sim: error: {message}")
    run_json = json.loads((out / "run.json").read_text())  # found as the objects start: the run failed
    assert run_json["status"] == "failed" and run_json["error"].startswith(message)


def test_one_sigterm_ends_a_stick_run_with_143_and_an_honest_run_json(objects, tmp_path):
    stick = make_stick(tmp_path / "ms", objects, ["JPROBE"], JOINT_PROBE)
    out = tmp_path / "out"
    run = subprocess.Popen(
        [sys.executable, "-m", "aibo_sim.cli", "run", str(stick), "--duration", "100000", "--out", str(out)],
        cwd=ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        deadline = time.monotonic() + 120
        while not list((out / "frames").glob("*.png")) and time.monotonic() < deadline:
            time.sleep(0.1)
        run.send_signal(signal.SIGTERM)
        assert run.wait(60) == 143
    finally:
        run.kill()
    assert "aibo-sim: terminated (SIGTERM)" in run.stderr.read()
    record = json.loads((out / "run.json").read_text())
    assert record["status"] == "interrupted" and record["camera_frames"] == len(list((out / "frames").glob("*.png")))


@pytest.mark.parametrize("signals", [1, 2])
def test_a_match_whose_sticks_hang_ends_at_a_signal_leaving_no_scratch_folder(objects, tmp_path, signals):
    """Their threads are not waited for (os._exit): the runtimes' folders in /tmp were left."""
    stick = make_stick(tmp_path / "ms", objects, ["SPIN"], f"{SENSOR} Spin.Sensor.OSensorFrameVectorData.O\n")
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    command = [sys.executable, "-m", "aibo_sim.cli", "run", str(stick), "--robot", "red:1", "--robot", "blue:1"]
    run = subprocess.Popen(
        command + ["--duration", "100", "--out", str(tmp_path / "out")],
        env={**os.environ, "TMPDIR": str(scratch)},
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        deadline = time.monotonic() + 120
        while len(list(scratch.glob("aibo-sim-openr-*/*.so"))) < 2 and time.monotonic() < deadline:
            time.sleep(0.1)
        time.sleep(1)  # both Spin objects spinning
        for _ in range(signals):
            run.send_signal(signal.SIGTERM)
            time.sleep(0.5)
        assert run.wait(60) == 143
    finally:
        run.kill()
    assert "terminated (SIGTERM)" in run.stderr.read() and list(scratch.iterdir()) == []


def test_a_full_disk_ends_a_stick_run_with_exit_2_and_run_json_failed(objects, tmp_path, monkeypatch, capsys):
    """The frame writer ends the run (SimulationEnd) as in a controller's: it reached the caller
    as a bare traceback; in a match it was a failure with an empty error."""
    real = runner.write_file_atomic

    def full_from_frame_3(path, *args, **kwargs):
        if path.name.endswith(".png") and int(path.stem) >= 3:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
        return real(path, *args, **kwargs)

    monkeypatch.setattr(runner, "write_file_atomic", full_from_frame_3)
    stick = make_stick(tmp_path / "ms", objects, ["JPROBE", "CDTPROBE"], JOINT_PROBE + IMAGE_PROBE)
    for match in ([], ["--robot", f"red:1:0,0,0:{stick}"]):
        out = tmp_path / f"out{len(match)}"
        assert main(["run", str(stick), *match, "--duration", "1", "--out", str(out)]) == 2
        error = capsys.readouterr().err
        assert error.startswith("aibo-sim: error: ") and error.count("\n") == 1 and "No space left" in error
        record = json.loads(((out / "robot1") if match else out).joinpath("run.json").read_text())
        assert record["status"] == "failed" and "No space left" in record["error"]


def test_a_console_log_the_disk_refuses_ends_a_stick_run_with_exit_2(objects, tmp_path, monkeypatch, capsys):
    """The runtime went on without its log (a full disk), every later line lost and the run "done"."""
    monkeypatch.setattr(host, "create_file", lambda path: os.open("/dev/full", os.O_WRONLY))
    stick = make_stick(tmp_path / "ms", objects, ["JPROBE"], JOINT_PROBE)
    for match in ([], ["--robot", f"red:1:0,0,0:{stick}"]):
        out = tmp_path / f"out{len(match)}"
        assert main(["run", str(stick), *match, "--duration", "1", "--out", str(out)]) == 2
        log = (out / "robot1" if match else out) / "console.log"
        assert capsys.readouterr().err == f"aibo-sim: error: cannot write {log}: No space left on device\n"
        record = json.loads(log.with_name("run.json").read_text())
        assert record["status"] == "failed" and "No space left on device" in record["error"]
        assert json.loads((out / "run.json").read_text())["simulated_s"] < 0.1  # ended at the first line


def test_dump_of_a_stick_records_frames_and_resumes(objects, tmp_path, capsys):
    stick = make_stick(tmp_path / "ms", objects, ["JPROBE"], JOINT_PROBE)
    out = tmp_path / "dump"
    assert main(["dump", str(stick), "--steps", "6", "--out", str(out), "--formats", "rgb"]) == 0
    dump = load_dump(out)
    assert dump.meta["parameters"]["backend"] == "memory stick" and len(dump) == 6
    assert main(["dump", str(stick), "--steps", "6", "--out", str(out), "--formats", "rgb", "--resume"]) == 0
    assert "0 written now" in capsys.readouterr().out


def test_build_ms_bad_input_exits_2(tmp_path, capsys):
    assert main(["build-ms", str(tmp_path / "nothing.c"), "--out", str(tmp_path / "project")]) == 2
    assert (
        capsys.readouterr().err.strip() == f"aibo-sim: error: controller {tmp_path / 'nothing.c'}: no such file "
        "or folder"
    )


def test_console_input_comes_from_standard_input_and_its_end_ends_the_object(objects, tmp_path):
    """gets() reads standard input. On the robot it waits for the console's next line; a program
    asking again (as Sony's PIDControl7 does) spun here once input ended, writing its prompt to the
    console and console.log without end: now the object is ended, as a crash (exit 1)."""
    stick = make_stick(tmp_path / "ms", objects, ["ASKER"])
    command = [sys.executable, "-m", "aibo_sim.cli", "run", str(stick), "--duration", "0.1"]
    answered = subprocess.run(
        [*command, "--out", str(tmp_path / "answered")],
        cwd=ROOT,
        input="n\ny\n",
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert answered.returncode == 0, answered.stderr
    prompts = [line.split(" Asker: ", 1)[1] for line in answered.stdout.splitlines() if " Asker: " in line]
    assert prompts == ["go on? (y/n) go on? (y/n) going on"]
    ended = subprocess.run(
        [*command, "--out", str(tmp_path / "ended")], cwd=ROOT, input="n\n", capture_output=True, text=True, timeout=300
    )
    assert ended.returncode == 1
    assert "aibo-sim: gets(): the console's input (standard input) has ended" in ended.stderr
    assert "OPEN-R object Asker (entry 1) crashed (SIGABRT" in ended.stderr
    assert (tmp_path / "ended" / "console.log").read_text().count("go on?") == 2


def test_a_console_reader_that_left_ends_no_object_and_the_log_keeps_every_line(objects, tmp_path):
    """`aibo-sim run STICK | head -2`: the runtime died of SIGPIPE, reported as an object's crash,
    and console.log stopped at the lines the reader took. Now the objects run on, the log is whole
    and aibo-sim ends quietly as a process whose reader left (141)."""
    stick = make_stick(tmp_path / "ms", objects, ["CRASH"], f"{SENSOR} Crash.Sensor.OSensorFrameVectorData.O\n")
    read, write = os.pipe()
    os.close(read)  # the reader has left before the first line
    try:
        run = subprocess.run(
            [
                sys.executable,
                "-m",
                "aibo_sim.cli",
                "run",
                str(stick),
                "--duration",
                "0.5",
                "--out",
                str(tmp_path / "o"),
            ],
            cwd=ROOT,
            stdout=write,
            stderr=subprocess.PIPE,
            text=True,
            env={**os.environ, "CRASH_HOW": "live"},
            timeout=300,
        )
    finally:
        os.close(write)
    assert run.returncode == 141 and run.stderr == ""
    log = (tmp_path / "o" / "console.log").read_text().splitlines()
    assert [line.split("] ", 1)[1] for line in log] == [f"Crash: sensor vector {n}" for n in range(1, 16)]
    assert json.loads((tmp_path / "o" / "run.json").read_text())["status"] == "done"
