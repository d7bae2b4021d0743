"""What a trusted tool must never do (issue 39): write or read through a link planted where it
writes, leave a controller running after one SIGTERM or a SIGKILL, let two runs share a folder,
start more dump workers than memory holds, break on a controller thread that reads the camera;
and the smaller promises (a scene that starts the robot in a wall, wait notices for Python
controllers, a closed socket, memory after closing envs, long arguments, run.json's status)."""

import ctypes
import errno
import fnmatch
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from aibo_sim import runner
from aibo_sim.cbind import serve
from aibo_sim.cli import main
from aibo_sim.config import CameraConfig
from aibo_sim.dump import DumpError, dump, load_dump
from aibo_sim.dump.writing import FolderLock
from aibo_sim.runner import ControllerFailed, FrameWriter, run_controller

ROOT = Path(__file__).resolve().parents[1]
SCRIPTED = ROOT / "tests" / "controllers" / "scripted_head.py"
TRACKER = ROOT / "controllers" / "ball_tracker.py"
VICTIM = b"a file of the user's, not aibo-sim's\n"
STARTUP_S = 60  # a subprocess's imports, a compile and its first frames, on a loaded machine
GONE_S = 10  # a stopped controller is gone within this (child.GRACE_S, 2 s, and the stop)
needs_cc = pytest.mark.skipif(not shutil.which("cc"), reason="needs cc")


@pytest.fixture(autouse=True)
def own_cache(tmp_path_factory, monkeypatch):
    """C controllers compile into this session's cache (the user's is left alone)."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path_factory.getbasetemp() / "cache"))


def one_error_line(capsys, *words) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err[:2000]
    assert all(word in err for word in words), err
    return err


def _alive(pid: int) -> bool:
    """The process exists and is not a zombie."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] not in "ZX"
    except (OSError, IndexError):
        return False


def _wait_for(predicate, timeout_s: float, what: str):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.02)
    raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "aibo_sim.cli", *args]


# ---------------------------------------------------------------- 1. links planted where we write


def _plant(link: Path, victim: Path) -> None:
    victim.write_bytes(VICTIM)
    link.parent.mkdir(parents=True, exist_ok=True)
    link.symlink_to(victim)


def _small_dump(out: Path, frames: int = 3) -> None:
    assert (
        main(
            [
                "dump",
                str(SCRIPTED),
                "--out",
                str(out),
                "--steps",
                str(frames),
                "--formats",
                "rgb",
                "--camera-profile",
                "ideal",
            ]
        )
        == 0
    )


def _cut_to_first_frame(out: Path) -> None:
    """frames.jsonl as a killed dump leaves it: one frame listed."""
    lines = (out / "frames.jsonl").read_bytes().splitlines(keepends=True)
    (out / "frames.jsonl").write_bytes(lines[0])


PLACES = {  # what is planted (relative to --out), how the folder is made first, the command
    "dump lock": (".dump.lock", None, ["dump", str(SCRIPTED), "--steps", "2", "--formats", "rgb"]),
    "dump frames.jsonl on --resume": (
        "frames.jsonl",
        _small_dump,
        ["dump", str(SCRIPTED), "--steps", "3", "--formats", "rgb", "--camera-profile", "ideal", "--resume"],
    ),
    "dump leftover temporary frame on --resume": (
        "rgb/.tmp.000001.png",
        lambda out: (_small_dump(out), _cut_to_first_frame(out)),
        ["dump", str(SCRIPTED), "--steps", "3", "--formats", "rgb", "--camera-profile", "ideal", "--resume"],
    ),
    "run lock": (".run.lock", None, ["run", str(SCRIPTED), "--duration", "0.1"]),
    "run's temporary run.json": (".run.json.tmp", None, ["run", str(SCRIPTED), "--duration", "0.1"]),
    "run's frames folder": ("frames", None, ["run", str(SCRIPTED), "--duration", "0.1"]),
    "render's temporary picture": (".head_camera.png.tmp", None, ["render", "--settle", "0"]),
}


@pytest.mark.parametrize("place", PLACES)
def test_a_link_planted_where_aibo_sim_writes_is_refused_naming_it(tmp_path, capsys, place):
    """Exit 2 with one line naming the link; what it points to is left as it was."""
    name, prepare, command = PLACES[place]
    out, victim = tmp_path / "out", tmp_path / "victim"
    if prepare is not None:
        prepare(out)
        (out / name).unlink(missing_ok=True)
    if name == "frames":  # a link to a folder of the user's, holding a file named like a frame
        (tmp_path / "theirs").mkdir()
        victim = tmp_path / "theirs" / "000000.png"
        victim.write_bytes(VICTIM)
        out.mkdir()
        (out / name).symlink_to(tmp_path / "theirs")
    else:
        _plant(out / name, victim)
    capsys.readouterr()
    assert main(command + ["--out", str(out)]) == 2
    one_error_line(capsys, f"{out / name} is a symbolic link: refusing to follow it")
    assert victim.read_bytes() == VICTIM and (out / name).is_symlink()


SWAPPING = """# Test controller: after 0.1 s it moves {folder!r} away and puts a link to {theirs!r} in its place.
import os
from aibo_sim.controller import *  # noqa: F403


def init():
    camera_enable(robot_get_device("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1"), 32)


def run(ms):
    # In a match only the robot whose folder it is swaps it: its frames are written in its thread,
    # never between the rename and the link (another robot's could find no folder there).
    if robot_get_name() in ("ERS-7", "blue 1") and robot_get_time() > 0.1 and not os.path.islink({folder!r}):
        os.rename({folder!r}, {moved!r})
        os.symlink({theirs!r}, {folder!r})
    return 32


robot_live(init)
robot_run(run)
"""


@pytest.mark.parametrize(
    "folder, options",
    [
        ("frames", []),
        ("robot2", ["--robot", "red:1", "--robot", "blue:1"]),
        ("rgb", ["dump"]),
        ("", ["dump"]),
    ],
    ids=["a run's frames", "a match's robot folder", "a dump's format folder", "a dump's folder"],
)
def test_a_folder_swapped_for_a_link_during_a_run_is_not_written_through(tmp_path, capsys, folder, options):
    """The folders are reached without following a link at each write: the run ends, exit 2, naming
    the link; the folder it points to gets nothing, and loses nothing (files named as the dump's
    temporary files, which a refused dump removes in its own folders)."""
    out, theirs, controller = tmp_path / "out", tmp_path / "theirs", tmp_path / "swapping.py"
    theirs_files = {theirs / ".tmp.meta.json", theirs / ".tmp.000010.png", theirs / "rgb" / ".tmp.000010.png"}
    for path in theirs_files:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(VICTIM)
    moved = tmp_path / "moved"
    controller.write_text(SWAPPING.format(folder=str(out / folder), moved=str(moved), theirs=str(theirs)))
    if options[:1] == ["dump"]:
        command = ["dump", str(controller), "--steps", "40", "--formats", "rgb", "--camera-profile", "ideal"]
    else:
        command = ["run", str(controller), "--duration", "0.6", *options]
    assert main(command + ["--out", str(out)]) == 2
    one_error_line(capsys, f"{out / folder} is a symbolic link: refusing to follow it")
    assert {p for p in theirs.rglob("*") if p.is_file()} == theirs_files
    assert all(p.read_bytes() == VICTIM for p in theirs_files)
    assert (out / folder).is_symlink() and moved.is_dir()
    if folder == "robot2":  # the match's run.json is written all the same
        assert json.loads((out / "run.json").read_text())["status"] == "failed"


def _no_permission_override() -> None:
    """Run in a child before its exec: root loses the capabilities that let it ignore permissions."""
    libc = ctypes.CDLL(None, use_errno=True)
    for capability in (1, 2):  # CAP_DAC_OVERRIDE, CAP_DAC_READ_SEARCH
        libc.prctl(24, capability, 0, 0, 0)  # PR_CAPBSET_DROP: fails, harmlessly, where not root


def test_folders_on_the_way_need_no_read_permission_and_one_not_made_is_named_whole(tmp_path):
    """Folders above are only passed through, as a path's are (shared storage often has
    drwx--x--x folders above a user's own): reading them each was "Permission denied"."""
    above = tmp_path / "above"
    (above / "mine").mkdir(parents=True)
    (above / "theirs").mkdir()
    (above / "theirs").chmod(0o555)
    above.chmod(0o311)
    code = f"""
import os
from pathlib import Path
from aibo_sim.files import make_folder, write_file_atomic
try:
    os.listdir({str(above)!r})
    print("permissions not enforced")
except PermissionError:
    write_file_atomic(make_folder(Path({str(above / "mine")!r}) / "out") / "frame.png", b"picture")
    make_folder(Path({str(above / "theirs")!r}) / "robot1")
"""
    try:
        child = subprocess.run(
            [sys.executable, "-c", code],
            preexec_fn=_no_permission_override,
            capture_output=True,
            text=True,
            cwd=tmp_path,
        )
    finally:
        above.chmod(0o755)
    if "permissions not enforced" in child.stdout:
        pytest.skip("this process reads any folder (root without a way to drop the capability)")
    assert child.stderr.strip().endswith(
        f"PermissionError: [Errno 13] Permission denied: '{above / 'theirs' / 'robot1'}'"
    )
    assert (above / "mine" / "out" / "frame.png").read_bytes() == b"picture"


def test_a_folder_in_place_of_the_temporary_file_is_named(tmp_path):
    from aibo_sim.files import write_file_atomic

    (tmp_path / ".frame.png.tmp" / "sub").mkdir(parents=True)
    with pytest.raises(
        OSError,
        match=f"^cannot write {re.escape(str(tmp_path / 'frame.png'))}: "
        f"{re.escape(str(tmp_path / '.frame.png.tmp'))}: Is a directory$",
    ):
        write_file_atomic(tmp_path / "frame.png", b"picture")


def test_no_folder_is_made_through_a_link_above_it(tmp_path):
    from aibo_sim.files import SymlinkRefused, make_folder

    (tmp_path / "theirs").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "theirs")
    with pytest.raises(SymlinkRefused, match=f"^{re.escape(str(tmp_path / 'link'))} is a symbolic link"):
        make_folder(tmp_path / "link" / "robot1" / "frames")
    assert list((tmp_path / "theirs").iterdir()) == []
    assert make_folder(tmp_path / "mine" / "frames").is_dir()


@pytest.mark.parametrize(
    "command",
    [
        ["run", str(SCRIPTED), "--duration", "0.1"],
        ["run", str(SCRIPTED), "--duration", "0.1", "--robot", "red:1", "--robot", "blue:1"],
        ["dump", str(SCRIPTED), "--steps", "2", "--formats", "rgb"],
        ["dump", str(SCRIPTED), "--steps", "2", "--formats", "rgb", "--robot", "red:1", "--robot", "blue:1"],
        ["render", "--settle", "0"],
        ["build-ms", str(ROOT / "controllers" / "ball_tracker_c")],
    ],
)
def test_an_out_that_is_a_link_to_nothing_is_refused_and_nothing_made_through_it(tmp_path, capsys, command):
    out, target = tmp_path / "out", tmp_path / "missing" / "target"
    out.symlink_to(target)
    assert main(command + ["--out", str(out)]) == 2
    one_error_line(capsys, f"--out {out}: a link to {target}, which does not exist")
    assert main(command + ["--out", str(out / "inside")]) == 2  # a folder above it
    one_error_line(capsys, f"--out {out / 'inside'}: a link (its folder {out}) to {target}, which does not exist")
    assert not (tmp_path / "missing").exists()


@pytest.mark.parametrize(
    "command",
    [
        ["run", str(SCRIPTED), "--duration", "0.1"],
        ["run", str(SCRIPTED), "--duration", "0.1", "--robot", "red:1", "--robot", "blue:1"],
        ["dump", str(SCRIPTED), "--steps", "2", "--formats", "rgb"],
        ["render", "--settle", "0"],
    ],
    ids=["run", "match", "dump", "render"],
)
def test_an_out_under_a_link_to_a_folder_is_written_there(tmp_path, capsys, command, monkeypatch):
    """``--out`` is resolved once: a link the user put on its way is followed (only links met
    later, under it, are refused)."""
    (tmp_path / "real").mkdir()
    (tmp_path / "link").symlink_to("real")
    monkeypatch.chdir(tmp_path)
    assert main(command + ["--out", "link/out"]) == 0, capsys.readouterr().err
    written = sorted(p.name for p in (tmp_path / "real" / "out").rglob("*.png"))
    assert written and written == sorted(p.name for p in (tmp_path / "link" / "out").rglob("*.png"))
    if command[0] == "dump":  # and read back through the link, resumed through it
        assert len(load_dump("link/out")) == 2
        _cut_to_first_frame(tmp_path / "link" / "out")
        assert main(command + ["--resume", "--out", "link/out"]) == 0
        assert len(load_dump(tmp_path / "link" / "out")) == 2


def test_the_writers_and_readers_of_the_python_api_follow_a_link_the_user_chose(tmp_path, monkeypatch):
    from aibo_sim.dump import Dump

    (tmp_path / "real").mkdir()
    (tmp_path / "link").symlink_to("real")
    monkeypatch.chdir(tmp_path)
    _small_dump(tmp_path / "real" / "dump")
    assert len(Dump("link/dump")) == 3
    writer = FrameWriter(Path("link/run"), controller=SCRIPTED, backend="sim")
    try:
        writer(0, np.zeros((160, 208, 3), np.uint8))
    finally:
        writer.lock.release()
    assert (tmp_path / "real" / "run" / "frames" / "000000.png").is_file() and writer.count == 1


def test_a_motion_file_is_written_through_a_link_to_its_folder(tmp_path):
    from aibo_sim.motions import motions
    from aibo_sim.mtn import read_mtn, write_mtn

    (tmp_path / "real").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "real")
    motion = motions()["SIT.MTN"]
    write_mtn(motion, tmp_path / "link" / "SIT.MTN")
    assert read_mtn(tmp_path / "real" / "SIT.MTN") == motion


def test_a_match_refused_at_a_later_robots_folder_leaves_the_earlier_ones_as_they_were(tmp_path, capsys):
    out, elsewhere = tmp_path / "out", tmp_path / "elsewhere"
    args = ["run", str(SCRIPTED), "--robot", "red:1", "--robot", "blue:1", "--duration", "0.1", "--out", str(out)]
    assert main(args) == 0
    before = {p: p.read_bytes() for p in (out / "robot1").rglob("*") if p.is_file() and p.name != ".run.lock"}
    shutil.rmtree(out / "robot2")
    elsewhere.mkdir()
    (out / "robot2").symlink_to(elsewhere)
    assert main(args) == 2
    one_error_line(capsys, f"{out / 'robot2'} is a symbolic link: refusing to follow it")
    assert {p: p.read_bytes() for p in (out / "robot1").rglob("*") if p.is_file() and p.name != ".run.lock"} == before
    assert list(elsewhere.iterdir()) == []


def test_a_match_refused_at_a_robots_folder_makes_none_of_the_others(tmp_path, capsys):
    out, elsewhere = tmp_path / "out", tmp_path / "elsewhere"
    out.mkdir()
    elsewhere.mkdir()
    (out / "robot2").symlink_to(elsewhere)
    args = ["run", str(SCRIPTED), "--robot", "red:1", "--robot", "blue:1", "--duration", "0.1", "--out", str(out)]
    assert main(args) == 2
    one_error_line(capsys, f"{out / 'robot2'} is a symbolic link: refusing to follow it")
    assert [p.name for p in out.iterdir()] == ["robot2"] and list(elsewhere.iterdir()) == []


@pytest.mark.parametrize("match", [False, True], ids=["one robot", "a match"])
@pytest.mark.parametrize("planted", ["link", "folder"])
def test_a_rerun_refused_at_its_run_json_leaves_the_earlier_run_whole(tmp_path, capsys, match, planted):
    """The earlier run's frames were removed before run.json was written: its run.json, still
    "done", then listed frames that were gone."""
    out = tmp_path / "out"
    args = ["run", str(SCRIPTED), "--duration", "0.1", "--out", str(out)]
    args += ["--robot", "red:1", "--robot", "blue:1"] if match else []
    assert main(args) == 0
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file() and p.name != ".run.lock"}
    temp = out / "robot1" / ".run.json.tmp" if match else out / ".run.json.tmp"
    if planted == "link":
        temp.symlink_to(tmp_path / "victim")
        error = f"{temp} is a symbolic link: refusing to follow it"
    else:
        temp.mkdir()
        error = f"cannot write {temp.with_name('run.json')}: {temp}: Is a directory"
    capsys.readouterr()
    assert main(args) == 2
    one_error_line(capsys, error)
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file() and p.name != ".run.lock"} == before
    assert not (tmp_path / "victim").exists()


@pytest.mark.parametrize("partial", [False, True], ids=["whole lines", "a partial last line"])
def test_a_hard_link_in_place_of_a_dumps_frames_jsonl_is_refused_on_resume(tmp_path, capsys, partial):
    out, victim = tmp_path / "out", tmp_path / "victim.jsonl"
    assert main(["dump", str(SCRIPTED), "--out", str(out), "--steps", "4", "--formats", "rgb"]) == 0
    lines = (out / "frames.jsonl").read_bytes()
    victim.write_bytes(lines[: lines.index(b"\n") + 1] + (b'{"index": 1' if partial else b""))
    before = victim.read_bytes()
    (out / "frames.jsonl").unlink()
    os.link(victim, out / "frames.jsonl")
    assert main(["dump", str(SCRIPTED), "--out", str(out), "--steps", "4", "--formats", "rgb", "--resume"]) == 2
    one_error_line(capsys, f"{out / 'frames.jsonl'} is a hard link to another file: refusing to write it")
    assert victim.read_bytes() == before


def test_a_hard_link_in_place_of_a_lock_is_refused_and_left_as_it_was(tmp_path, capsys):
    out, victim = tmp_path / "out", tmp_path / "victim"
    out.mkdir()
    victim.write_bytes(VICTIM)
    os.link(victim, out / ".run.lock")
    assert main(["run", str(SCRIPTED), "--duration", "0.1", "--out", str(out)]) == 2
    one_error_line(capsys, f"{out / '.run.lock'} is a hard link to another file: refusing to write it")
    assert victim.read_bytes() == VICTIM


def no_space_after(calls: int, write, names: str = "*"):
    """``write`` (a file writer) that fails as a full disk does after ``calls`` calls for files
    whose names match ``names``."""
    count = iter(range(calls))

    def failing(path, *args, **kwargs):
        if fnmatch.fnmatch(Path(path).name, names) and next(count, None) is None:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
        return write(path, *args, **kwargs)

    return failing


def test_a_full_disk_in_a_match_is_exit_2_and_each_run_json_says_so(tmp_path, monkeypatch, capsys):
    """A frame that could not be written ended its robot's run as its end does: the match said
    done, exit 0."""
    monkeypatch.setattr(runner, "write_file_atomic", no_space_after(5, runner.write_file_atomic, "*.png"))
    out = tmp_path / "out"
    args = ["run", str(SCRIPTED), "--robot", "red:1", "--robot", "blue:1", "--duration", "0.5", "--out", str(out)]
    assert main(args) == 2
    error = capsys.readouterr().err
    assert error.startswith("aibo-sim: error: ") and "No space left on device" in error and error.count("\n") == 1
    match = json.loads((out / "run.json").read_text())
    assert match["status"] == "failed" and "No space left on device" in str(match["robots"])
    assert "failed" in [json.loads((out / f"robot{k}" / "run.json").read_text())["status"] for k in (1, 2)]
    assert main(args) == 2 and "No space left" in capsys.readouterr().err  # the folders' locks were released


def test_a_build_ms_that_fails_leaves_no_half_project(tmp_path, monkeypatch, capsys):
    """Whole or nothing, the error naming the project (not the source file being copied)."""
    from aibo_sim.openr import build_ms

    monkeypatch.setattr(build_ms.shutil, "copyfile", no_space_after(3, shutil.copyfile))
    out = tmp_path / "project"
    assert main(["build-ms", str(ROOT / "controllers" / "ball_tracker_c"), "--out", str(out)]) == 2
    assert capsys.readouterr().err == f"aibo-sim: error: cannot write {out}: No space left on device\n"
    assert sorted(tmp_path.iterdir()) == []
    monkeypatch.undo()
    out.mkdir()  # an empty folder given: the project goes there
    assert main(["build-ms", str(ROOT / "controllers" / "ball_tracker_c"), "--out", str(out)]) == 0
    assert (out / "MS" / "OPEN-R" / "MW" / "CONF" / "OBJECT.CFG").is_file() and sorted(tmp_path.iterdir()) == [out]


def test_a_signal_right_after_a_temporary_file_is_made_leaves_none(tmp_path, monkeypatch):
    """Ctrl-C or SIGTERM lands between bytecodes, here just after the temporary file was made."""
    from aibo_sim import files

    create = files.create_file

    def create_then_interrupt(temp, *folder):
        os.close(create(temp, *folder))
        raise KeyboardInterrupt

    monkeypatch.setattr(files, "create_file", create_then_interrupt)
    with pytest.raises(KeyboardInterrupt):
        files.write_file_atomic(tmp_path / "frame.png", b"picture")
    assert list(tmp_path.iterdir()) == []


def test_a_frame_that_is_a_link_is_not_complete_on_resume_nor_read(tmp_path):
    """A frame's file replaced by a link to a copy elsewhere: load_dump does not read it, and
    --resume rewrites it as a file of the dump's own, leaving the copy alone."""
    out = tmp_path / "out"
    _small_dump(out)
    frame, copy = out / "rgb" / "000001.png", tmp_path / "copy.png"
    original = frame.read_bytes()
    shutil.move(frame, copy)
    frame.symlink_to(copy)
    with pytest.raises(DumpError, match=f"^{re.escape(str(frame))} is a symbolic link: refusing to follow it"):
        _ = load_dump(out)[1].rgb
    summary = dump(out, controller=SCRIPTED, frames=3, formats=("rgb",), resume=True, camera=CameraConfig("ideal"))
    assert (summary.new_frames, summary.repaired_frames) == (0, 1)
    assert not frame.is_symlink() and frame.read_bytes() == original == copy.read_bytes()


def test_load_dump_reads_no_file_outside_the_dump(tmp_path):
    out = tmp_path / "out"
    _small_dump(out)
    meta = json.loads((out / "meta.json").read_text())
    meta["files"]["rgb"]["path"] = "../elsewhere/{index:06d}.png"
    (out / "meta.json").write_text(json.dumps(meta))
    with pytest.raises(DumpError, match=r'"files"\."rgb"\."path" must be a file name pattern inside the dump'):
        load_dump(out)
    shutil.rmtree(out)
    _small_dump(out)
    shutil.move(out / "rgb", tmp_path / "rgb")
    (out / "rgb").symlink_to(tmp_path / "rgb")
    with pytest.raises(DumpError, match=f"^{re.escape(str(out / 'rgb'))} is a symbolic link"):
        load_dump(out)


def test_mujocos_warnings_go_to_the_log_not_through_a_link_in_the_working_folder(tmp_path, monkeypatch, caplog, capfd):
    """MuJoCo's own handler appends its warnings to MUJOCO_LOG.TXT in the working folder (through
    a link found there) and prints them on stdout; aibo-sim logs them instead."""
    import numpy as np

    from aibo_sim.sim import Simulation, SimulationDiverged

    victim = tmp_path / "victim"
    _plant(tmp_path / "MUJOCO_LOG.TXT", victim)
    monkeypatch.chdir(tmp_path)
    sim = Simulation()
    sim.data.qpos[0] = np.nan
    with pytest.raises(SimulationDiverged):
        sim.step_frame()
    sim.close()
    assert victim.read_bytes() == VICTIM and capfd.readouterr().out == ""
    assert [r.getMessage() for r in caplog.records if r.name == "aibo_sim.mujoco"] == [
        "MuJoCo: Nan, Inf or huge value in QPOS at DOF 0. The simulation is unstable. Time = 0.0000."
    ]


# ---------------------------------------------------------------- 2. one signal ends any controller

SPINNER = r"""#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>
#include <device/robot.h>
static void bye(void) { fclose(fopen("die.txt", "w")); }
int main(void) {
  robot_live(0); robot_die(bye); robot_step(8);
  pid_t grandchild = fork();
  if (grandchild == 0) { for (;;) pause(); }
  FILE *f = fopen("pids.txt", "w");
  fprintf(f, "%d %d\n", (int)getpid(), (int)grandchild);
  fclose(f);
  for (volatile unsigned long i = 0;; i++) {}
}
"""


def _start_spinner(tmp_path) -> tuple[subprocess.Popen, Path, list[int]]:
    """aibo-sim running a C controller that forked a child and computes forever between calls."""
    source, out = tmp_path / "spin.c", tmp_path / "out"
    source.write_text(SPINNER)
    run = subprocess.Popen(
        _cli("run", str(source), "--duration", "100000", "--out", str(out)), cwd=ROOT, stderr=subprocess.PIPE, text=True
    )
    _wait_for(
        lambda: (out / "pids.txt").exists() and (out / "pids.txt").read_text().endswith("\n"),
        STARTUP_S,
        "the controller's pids",
    )
    pids = [int(p) for p in (out / "pids.txt").read_text().split()]
    assert all(map(_alive, pids))
    return run, out, pids


@pytest.mark.slow
@needs_cc
@pytest.mark.parametrize("signal_name, status", [("SIGTERM", 143), ("SIGINT", 130)])
def test_one_signal_ends_a_c_controller_that_computes_forever_and_its_group(tmp_path, signal_name, status):
    """As ``timeout`` or systemd sends it: once. The controller makes no further call, so its
    robot_die cannot run: it is stopped with its process group (its forked child too), the run
    says so and exits as the signal says, run.json says "interrupted"."""
    run, out, pids = _start_spinner(tmp_path)
    try:
        run.send_signal(getattr(signal, signal_name))
        err = run.communicate(timeout=STARTUP_S)[1]
    finally:
        run.kill()
    assert run.returncode == status, err
    assert (
        f"aibo-sim: controller spin.c made no call for 2 s after {signal_name}: stopped, with its process group; "
        "its robot_die functions could not run"
    ) in err
    assert json.loads((out / "run.json").read_text())["status"] == "interrupted" and not (out / "die.txt").exists()
    _wait_for(lambda: not any(map(_alive, pids)), GONE_S, "the controller and its child to end")


@pytest.mark.slow
@needs_cc
def test_a_c_controller_dies_with_aibo_sim_killed_by_sigkill(tmp_path):
    run, out, pids = _start_spinner(tmp_path)
    run.kill()
    run.wait()
    _wait_for(lambda: not _alive(pids[0]), GONE_S, "the controller to die with its parent")
    os.kill(pids[1], signal.SIGKILL)  # the grandchild's parent was the controller: no one else stops it


@pytest.mark.slow
@needs_cc
def test_a_child_that_keeps_the_socket_open_does_not_hold_the_run(tmp_path):
    """The controller forks a child that inherits the socket and sleeps, then returns: the run ends
    there (exit 0), and the child is stopped with it."""
    source, out = tmp_path / "forks.c", tmp_path / "out"
    source.write_text(
        "#include <stdio.h>\n#include <unistd.h>\n#include <device/robot.h>\n"
        "int main(void) {\n  robot_live(0); robot_step(8);\n  pid_t child = fork();\n"
        '  if (child == 0) { for (;;) pause(); }\n  FILE *f = fopen("child.txt", "w");\n'
        '  fprintf(f, "%d\\n", (int)child); fclose(f);\n  robot_step(8); return 0;\n}\n'
    )
    run = subprocess.run(
        _cli("run", str(source), "--duration", "10", "--out", str(out)),
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=STARTUP_S,
    )
    assert run.returncode == 0, run.stderr
    assert json.loads((out / "run.json").read_text())["simulated_s"] == 0.016
    _wait_for(lambda: not _alive(int((out / "child.txt").read_text())), GONE_S, "the controller's child to end")


@needs_cc
@pytest.mark.parametrize(
    "reuse",
    ["", "  int s;\n  do s = socket(AF_INET, SOCK_DGRAM, 0); while (s >= 0 && s < fd);\n"],
    ids=["closed", "another socket in its place"],
)
def test_a_c_controller_that_closes_its_socket_is_not_reported_as_exit_70(tmp_path, reuse):
    source = tmp_path / "closes.c"
    source.write_text(
        "#include <stdlib.h>\n#include <unistd.h>\n#include <sys/socket.h>\n#include <device/robot.h>\n"
        'int main(void) {\n  int fd = atoi(getenv("AIBO_SIM_FD"));\n  robot_live(0); robot_step(8);\n  close(fd);\n'
        + reuse
        + "  robot_step(8); return 0;\n}\n"
    )
    with pytest.raises(ControllerFailed) as failed:
        run_controller(source, duration=1)
    message = str(failed.value)
    assert re.fullmatch(
        r"controller closes\.c at simulated t = 0\.008 s: closed its connection to the simulator "
        r"\(descriptor \d+, AIBO_SIM_FD\), then made a call",
        message,
    ), message
    assert failed.value.exit_status is None


# ---------------------------------------------------------------- 3. one run per folder


def test_a_second_run_into_a_folder_being_written_is_refused(tmp_path, capsys):
    out = tmp_path / "out"
    first = FrameWriter(out, controller=SCRIPTED, backend="sim")  # a run writing there now
    try:
        before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
        capsys.readouterr()
        assert main(["run", str(SCRIPTED), "--duration", "0.1", "--out", str(out)]) == 2
        one_error_line(
            capsys,
            f"{out} is being written by another run (pid {os.getpid()}, started ",
            "wait for it to end or stop it, or choose another --out; nothing was changed",
        )
        assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before
    finally:
        first.lock.release()
    assert main(["run", str(SCRIPTED), "--duration", "0.1", "--out", str(out)]) == 0


def test_a_run_into_a_dumps_folder_is_refused_while_the_dump_writes_it_and_after(tmp_path, capsys):
    """The run took only its own lock: a run went on writing frames/ and run.json among a dump's files."""
    from aibo_sim.dump.writing import FolderLock as DumpLock

    out = tmp_path / "dump"
    out.mkdir()
    dumping = DumpLock(out)  # a dump writing there now
    try:
        before = sorted(p.name for p in out.iterdir())
        assert main(["run", str(SCRIPTED), "--duration", "0.1", "--out", str(out)]) == 2
        one_error_line(capsys, f"{out} holds a dump (.dump.lock): a run would mix its frames with the dump's")
        assert sorted(p.name for p in out.iterdir()) == before
    finally:
        dumping.release()
    assert main(["run", str(SCRIPTED), "--duration", "0.1", "--out", str(out)]) == 2  # its files stay a dump's


# ---------------------------------------------------------------- 4. workers within memory


def test_more_dump_workers_than_memory_holds_are_refused_saying_how_many_fit(tmp_path, monkeypatch, capsys):
    from aibo_sim.dump import running

    assert running.available_memory_mb() > 0
    monkeypatch.setattr(running, "available_memory_mb", lambda: 1000.0)
    out = tmp_path / "out"
    assert main(["dump", str(SCRIPTED), "--out", str(out), "--steps", "100", "--workers", "6"]) == 2
    one_error_line(
        capsys, "--workers 6: this machine has memory for 5 workers (1.0 GB available, about 200 MB a worker)"
    )
    assert not out.exists()


# ---------------------------------------------------------------- 5. the camera and threads

THREADED = """import threading
from aibo_sim.controller import *
robot_live(None)
camera = robot_get_device("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1")
camera_enable(camera, 32)
robot_step(64)
reader = threading.Thread(target=lambda: camera_get_image(camera), name="reader")
reader.start()
reader.join()
while True:
    robot_step(32)
"""


def test_a_thread_reading_the_camera_ends_the_run_naming_the_rule(tmp_path, capsys):
    controller, out = tmp_path / "threaded.py", tmp_path / "out"
    controller.write_text(THREADED)
    assert main(["run", str(controller), "--duration", "0.2", "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert err.startswith("aibo-sim: controller threaded.py raised in thread 'reader' at simulated t = 0.064 s:\n")
    assert err.rstrip().endswith(
        "DeviceError: camera_get_image called from thread 'reader': the camera renders in "
        "the thread that runs the controller ('MainThread') only; call camera_get_image there"
    )
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "failed" and run["camera_frames"] == len(list((out / "frames").iterdir())) > 0


def test_a_dump_whose_controller_thread_reads_the_camera_stays_consistent(tmp_path, capsys):
    controller, out = tmp_path / "threaded.py", tmp_path / "out"
    controller.write_text(THREADED)
    command = ["dump", str(controller), "--out", str(out), "--steps", "6", "--formats", "rgb"]
    assert main(command) == 1
    assert "call camera_get_image there" in capsys.readouterr().err
    assert len(load_dump(out)) == 6 and not list(out.rglob(".tmp.*"))
    FolderLock(out).release()  # free: the dump can be resumed
    assert main(command + ["--resume"]) == 1


# ---------------------------------------------------------------- 6. the smaller promises


@pytest.mark.parametrize(
    "command",
    [
        ["run", str(SCRIPTED), "--duration", "0.1"],
        ["render", "--settle", "0"],
        ["dump", str(SCRIPTED), "--steps", "3"],
        ["mtn", "play", "STAND.MTN"],
    ],
)
def test_a_scene_whose_robot_starts_inside_a_wall_is_refused(tmp_path, capsys, command):
    from aibo_sim.sim import models_dir

    scene = tmp_path / "walled.xml"
    scene.write_text(f"""<mujoco>
  <include file="{models_dir() / "ers7.xml"}"/>
  <worldbody><geom name="floor" type="plane" size="2 2 0.1"/>
    <geom name="wall_through_the_robot" type="box" pos="0 0 0.15" size="0.02 1 0.15"/></worldbody>
</mujoco>""")
    out = ["--out", str(tmp_path / "out")] if command[0] in ("render", "dump") else []
    assert main(command + out + ["--scene", str(scene)]) == 2
    one_error_line(
        capsys,
        f"--scene {scene}: the robot starts inside wall_through_the_robot (",
        "cm deep); move it in the scene, or place it with --pose",
    )
    assert not (tmp_path / "out").exists()


def test_a_python_controller_that_computes_long_is_announced_as_a_c_one_is(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(serve, "WAIT_NOTICE_S", 0.2)
    controller = tmp_path / "busy.py"
    controller.write_text(
        "import time\nfrom aibo_sim.controller import *\nrobot_live(None)\nrobot_step(40)\n"
        "time.sleep(0.5)\nrobot_step(8)\n"
    )
    assert run_controller(controller, duration=1).simulated_s == 0.048
    err = capsys.readouterr().err
    assert (
        "aibo-sim: waiting for controller busy.py: no API call for 0.2 s of wall time (simulated time stays at "
        "t = 0.040 s)\n"
    ) in err


def test_an_api_call_that_takes_long_is_not_announced_as_the_controllers_wait(tmp_path, monkeypatch, capsys):
    """The simulator's own time inside a call (the first frames compile the camera's passes) is
    not the controller's: no notice."""
    from aibo_sim.robot import Robot

    monkeypatch.setattr(serve, "WAIT_NOTICE_S", 0.2)
    step = Robot.step

    def slow_step(robot, ms):
        time.sleep(0.5)
        step(robot, ms)

    monkeypatch.setattr(Robot, "step", slow_step)
    controller = tmp_path / "quick.py"
    controller.write_text("from aibo_sim.controller import *\nrobot_live(None)\nrobot_step(8)\nrobot_step(8)\n")
    assert run_controller(controller, duration=1).simulated_s == 0.016
    assert "waiting for controller" not in capsys.readouterr().err


def test_closing_an_env_gives_its_memory_back(monkeypatch):
    """glibc keeps what a closed env freed (RSS 282 -> 545 MiB over 80 envs made and closed,
    272 after malloc_trim): closing one trims."""
    import gymnasium

    import aibo_sim  # noqa: F401
    from aibo_sim import sim

    calls = []
    monkeypatch.setattr(sim, "_malloc_trim", calls.append)
    env = gymnasium.make("aibo_sim/HeadTrackBall-v0", camera_profile="ideal")
    env.reset(seed=0)
    assert calls == []
    env.close()
    assert calls == [0]


def test_a_file_given_in_place_of_a_name_is_not_printed_whole(tmp_path, capsys):
    text = "<mujoco>" + "x" * 5000
    assert main(["run", str(SCRIPTED), "--scene", text]) == 2
    err = one_error_line(capsys, "(5008 characters)")
    assert len(err) < 300
    with pytest.raises(SystemExit):
        main(["run", str(SCRIPTED), "--ball", "1" * 5000, "0"])
    err = one_error_line(capsys, "argument --ball", "(5000 characters)")
    assert len(err) < 300


def test_run_json_of_a_run_that_ended_says_done(tmp_path):
    run_controller(SCRIPTED, duration=0.1, out=tmp_path)
    run = json.loads((tmp_path / "run.json").read_text())
    assert list(run)[:3] == ["controller", "backend", "status"] and run["status"] == "done"


def test_the_docs_output_folders_are_ignored_by_git():
    if not (shutil.which("git") and (ROOT / ".git").exists()):
        pytest.skip("needs git and the repository")
    readme = "".join(page.read_text() for page in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))])
    folders = set(re.findall(r"--out ([a-z_]+)", readme)) | {"renders"}  # render's default --out
    tracked = subprocess.run(["git", "ls-files", "--", *folders], cwd=ROOT, capture_output=True, text=True).stdout
    folders -= {line.split("/")[0] for line in tracked.splitlines()}  # models/: written on purpose
    assert {"frames", "sweep", "annex", "dump", "dump_env"} <= folders
    ignored = subprocess.run(
        ["git", "check-ignore", *(f"{f}/x" for f in sorted(folders))], cwd=ROOT, capture_output=True, text=True
    ).stdout.split()
    assert sorted(ignored) == sorted(f"{f}/x" for f in folders)


@pytest.mark.parametrize("robots", [[], ["--robot", "red:1", "--robot", "blue:1"]], ids=["one robot", "a match"])
@pytest.mark.parametrize("signal_name, status", [("SIGTERM", 143), ("SIGINT", 130)])
def test_a_signal_sent_to_the_process_and_to_its_group_is_one_stop(tmp_path, robots, signal_name, status):
    # `timeout` and `kill -- -PGID` send it twice, a moment apart: the run stops cleanly once, not
    # "again: stopped at once" with run.json left "incomplete".
    ctl = tmp_path / "ctl.py"
    ctl.write_text(
        "import os, signal, threading, time\nfrom aibo_sim.controller import *\n"
        "def twice():\n"
        f"    os.kill(os.getpid(), signal.{signal_name})\n"
        "    time.sleep(0.05)\n"
        f"    os.kill(os.getpid(), signal.{signal_name})\n"
        "robot_die(lambda: time.sleep(0.3))  # still stopping when the second one comes\n"
        "robot_step(16)\n"
        "try:  # the first robot here sends it\n"
        "    os.close(os.open('signalled', os.O_CREAT | os.O_EXCL))\n"
        "    threading.Thread(target=twice).start()\n"
        "except FileExistsError:\n"
        "    pass\n"
        "while True:\n    robot_step(8)\n"
    )
    out = tmp_path / "out"
    command = [sys.executable, "-m", "aibo_sim.cli", "run", str(ctl), *robots, "--camera-profile", "ideal"]
    ended = subprocess.run([*command, "--duration", "30", "--out", str(out)], capture_output=True, text=True, cwd=ROOT)
    assert ended.returncode == status and "again" not in ended.stderr, ended.stderr
    assert json.loads((out / "run.json").read_text())["status"] == "interrupted"


@needs_cc
def test_a_signal_sent_twice_to_a_c_controllers_run_is_one_stop(tmp_path):
    source = tmp_path / "twice.c"
    source.write_text(
        "#include <signal.h>\n#include <unistd.h>\n#include <device/robot.h>\n"
        "static void die(void) { usleep(300000); }\n"
        "int main(void) {\n  robot_live(0); robot_die(die); robot_step(16);\n"
        "  kill(getppid(), SIGTERM); usleep(50000); kill(getppid(), SIGTERM);\n"
        "  for (;;) robot_step(8);\n}\n"
    )
    out = tmp_path / "out"
    command = [sys.executable, "-m", "aibo_sim.cli", "run", str(source), "--duration", "30", "--out", str(out)]
    ended = subprocess.run(command, capture_output=True, text=True, cwd=ROOT)
    assert ended.returncode == 143 and "again" not in ended.stderr, ended.stderr
    assert json.loads((out / "run.json").read_text())["status"] == "interrupted"


CTRL_C_AT_THE_GL_IMPORT = """
import importlib.abc, os, signal, sys
sys.argv[0] = "aibo-sim"


class CtrlC(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name == "aibo_sim._gl":
            os.kill(os.getpid(), signal.SIGINT)


sys.meta_path.insert(0, CtrlC())
import aibo_sim
"""


def test_ctrl_c_while_the_program_loads_its_opengl_module_is_one_line_and_130():
    """The handler came after aibo_sim._gl's import: a Ctrl-C in it was a traceback."""
    done = subprocess.run([sys.executable, "-c", CTRL_C_AT_THE_GL_IMPORT], capture_output=True, text=True, timeout=120)
    assert (done.returncode, done.stderr) == (130, "\naibo-sim: interrupted\n")
