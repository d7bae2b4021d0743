"""Dumps and ``run --out`` that survive kills and concurrency (issue 15): workers die with a
killed dump, one writer per folder, byte-identical resumes, folders that are not a dump left
alone, corrupt files named with their line; ``run --out`` temporary names, reused folders and
a full disk."""

import fnmatch
import json
import os
import re
import resource
import shutil
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from rename_support import watch_renames

from aibo_sim.cli import main
from aibo_sim.config import WorldConfig
from aibo_sim.dump import FORMATS, DumpError, dump, load_dump
from aibo_sim.dump.writing import LOCK_NAME, FolderLock
from aibo_sim.runner import run_controller

ROOT = Path(__file__).resolve().parents[1]
TRACKER = ROOT / "controllers" / "ball_tracker.py"
NO_VIDEO = tuple(f for f in FORMATS if f != "mp4")
STARTUP_S = 30  # a subprocess's imports and first frames, on a loaded machine
GONE_S = 5  # a killed dump's workers are gone within this


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "aibo_sim.cli", *args]


def _snapshot(folder: Path, lock: bool = True) -> dict:
    """Every entry below ``folder``: its bytes (files), with its modification time; without the
    lock file unless ``lock`` (a writer refused after taking the lock has written its name there)."""
    return {
        str(p.relative_to(folder)): (p.read_bytes() if p.is_file() else None, p.stat().st_mtime_ns)
        for p in sorted(folder.rglob("*"))
        if lock or p.name != LOCK_NAME
    }


def _alive(pid: int) -> bool:
    """Any thread of the process still running (a zombie waiting for a reaper is not; a killed
    process's other threads may outlive its main thread's turning zombie, holding its files)."""
    try:
        tasks = os.listdir(f"/proc/{pid}/task")
    except OSError:
        return False
    for task in tasks:
        try:
            if Path(f"/proc/{pid}/task/{task}/stat").read_text().rsplit(")", 1)[1].split()[0] not in "ZX":
                return True
        except (OSError, IndexError):
            pass
    return False


def _wait_for(predicate, timeout_s: float, what: str):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(0.01)
    raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")


def _holder_pid(folder: Path) -> int | None:
    try:
        return json.loads((folder / LOCK_NAME).read_text())["pid"]
    except (OSError, ValueError, KeyError):
        return None


def _lines(folder: Path) -> int:
    try:
        return (folder / "frames.jsonl").read_bytes().count(b"\n")
    except OSError:
        return 0


@pytest.fixture(scope="module")
def small_dump(tmp_path_factory):
    out = tmp_path_factory.mktemp("small") / "dump"
    dump(out, controller=TRACKER, frames=4, formats=("rgb", "yuv420"))
    return out


# ---------------------------------------------------------------- workers die with the dump


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM], ids=["SIGKILL", "SIGTERM"])
def test_a_killed_sharded_dump_takes_its_workers_along(tmp_path, capsys, sig):
    out = tmp_path / "dump"
    command = [str(TRACKER), "--out", str(out), "--steps", "3000", "--workers", "2", "--formats", "rgb"]
    parent = subprocess.Popen(_cli("dump", *command), cwd=ROOT, stderr=subprocess.PIPE, text=True)

    def worker_pids():  # each worker names itself in its shard's lock file
        pids = [_holder_pid(out / f"shard_{k}") for k in range(2)]
        return all(pids) and pids

    try:
        workers = _wait_for(worker_pids, STARTUP_S, "both workers' locks")
        for pid in workers:
            assert Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[1] == str(parent.pid)
        children = Path(f"/proc/{parent.pid}/task/{parent.pid}/children")  # multiprocessing's resource tracker too
        workers += [int(pid) for pid in children.read_text().split()] if children.exists() else []
        _wait_for(lambda: _lines(out / "shard_0") >= 2, STARTUP_S, "frames")
        # One writer per folder: a second dump is refused, naming the holder.
        capsys.readouterr()
        assert main(["dump", *command, "--resume"]) == 2
        error = capsys.readouterr().err
        assert error.count("\n") == 1 and f"is being written by another dump (pid {parent.pid}, started " in error
        assert "--workers 2" in error
        parent.send_signal(sig)
        status = parent.wait(GONE_S)
    finally:
        if parent.poll() is None:
            parent.kill()
            parent.wait()
    _wait_for(lambda: not any(_alive(pid) for pid in workers), GONE_S, f"the dump's processes {workers} to end")
    if sig == signal.SIGTERM:  # stopped cleanly: the message, no temporary files, the locks free
        assert status == 143 and "terminated (SIGTERM)" in parent.stderr.read()
        assert not list(out.rglob(".tmp.*"))
    else:
        assert status == -signal.SIGKILL
    for folder in (out, out / "shard_0", out / "shard_1"):
        FolderLock(folder).release()
    frames = len(load_dump(out))
    assert 2 <= frames < 3000


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_a_worker_without_prctl_watches_its_parent(tmp_path):
    """The portable fallback alone (as on macOS): the worker ends once its parent is gone."""
    child = textwrap.dedent("""
        import os, sys, time
        sys.platform = "darwin"  # no PR_SET_PDEATHSIG: the watchdog thread alone
        from aibo_sim.dump.shards import die_with_parent
        die_with_parent(os.getppid())
        print(os.getpid(), flush=True)
        time.sleep(60)
    """)
    parent = textwrap.dedent(f"""
        import subprocess, sys, time
        subprocess.Popen([sys.executable, "-c", {child!r}])
        time.sleep(60)
    """)
    process = subprocess.Popen([sys.executable, "-c", parent], cwd=ROOT, stdout=subprocess.PIPE, text=True)
    try:
        pid = int(process.stdout.readline())
        assert _alive(pid)
    finally:
        process.kill()
        process.wait()
    _wait_for(lambda: not _alive(pid), GONE_S, "the orphaned worker to end")


def test_a_ray_tasks_process_ends_with_the_dumps_command(tmp_path):
    """A Ray task is no child of the dump's command: killed (SIGKILL), the command left its tasks
    writing into the dump. Its worker now watches the command's process, as end_with_process does."""
    dumper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    worker = textwrap.dedent(f"""
        import time
        from aibo_sim.dump.shards import end_with_process
        end_with_process({dumper.pid})
        print("watching", flush=True)
        time.sleep(60)
    """)
    watching = subprocess.Popen([sys.executable, "-c", worker], cwd=ROOT, stdout=subprocess.PIPE, text=True)
    try:
        assert watching.stdout.readline() == "watching\n"
        time.sleep(1)
        assert watching.poll() is None  # the command still runs: so does the task
        dumper.kill()
        dumper.wait()
        assert watching.wait(GONE_S) == 1
    finally:
        for process in (dumper, watching):
            process.kill()
            process.wait()


def test_what_ray_init_writes_to_stderr_shows_unless_it_failed(capfd):
    """Refused by a cluster that authenticates, Ray's C++ client logged each of its ~20 retries
    on stderr before the dump's one line."""
    from aibo_sim.dump.shards import _stderr_kept_unless_failed

    with pytest.raises(RuntimeError), _stderr_kept_unless_failed():
        os.write(2, b"retrying\n" * 20)
        raise RuntimeError("refused")
    assert capfd.readouterr().err == ""
    with _stderr_kept_unless_failed():
        os.write(2, b"connected\n")
    assert capfd.readouterr().err == "connected\n"


# ---------------------------------------------------------------- one writer per folder


def test_a_locked_folder_is_refused_naming_the_holder_and_nothing_changes(small_dump, tmp_path, capsys):
    out = tmp_path / "dump"
    shutil.copytree(small_dump, out)
    lock = FolderLock(out, command="aibo-sim dump elsewhere --out somewhere")
    try:
        before = _snapshot(out)
        assert (
            main(["dump", str(TRACKER), "--out", str(out), "--steps", "4", "--formats", "rgb,yuv420", "--resume"]) == 2
        )
        error = capsys.readouterr().err
        assert error.count("\n") == 1
        assert f"(pid {os.getpid()}, started " in error and "command: aibo-sim dump elsewhere --out somewhere" in error
        assert _snapshot(out) == before
    finally:
        lock.release()
    assert dump(out, controller=TRACKER, frames=4, formats=("rgb", "yuv420"), resume=True).new_frames == 0


# ---------------------------------------------------------------- resume


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    """The reference: every format but the video (a resume renders only the frames it writes), ers7 camera."""
    out = tmp_path_factory.mktemp("reference") / "dump"
    dump(out, controller=TRACKER, frames=30, formats=NO_VIDEO, world=WorldConfig(seed=2))
    return out


@pytest.mark.slow
def test_resume_after_a_kill_is_byte_identical_whatever_the_formats(uninterrupted, tmp_path):
    out = tmp_path / "dump"
    process = subprocess.Popen(
        _cli("dump", str(TRACKER), "--out", str(out), "--steps", "30", "--seed", "2", "--formats", ",".join(NO_VIDEO)),
        cwd=ROOT,
        stderr=subprocess.DEVNULL,
    )
    try:
        _wait_for(lambda: _lines(out) >= 6 or process.poll() is not None, STARTUP_S, "six frames")
        process.kill()
    finally:
        process.wait()
    assert process.returncode == -signal.SIGKILL, "the dump ended before it could be killed"
    complete = len(load_dump(out))
    assert 6 <= complete < 30
    (out / "seg" / "000003.png").unlink()  # a listed frame's file lost: rewritten, its line kept
    summary = dump(out, controller=TRACKER, frames=30, formats=NO_VIDEO, resume=True, world=WorldConfig(seed=2))
    assert (summary.frames, summary.new_frames, summary.repaired_frames) == (30, 30 - complete, 1)
    reference = _snapshot(uninterrupted)
    resumed = _snapshot(out)
    assert sorted(resumed) == sorted(reference)
    for name, (data, _) in reference.items():
        assert resumed[name][0] == data, name


def test_resume_refuses_a_changed_controller_file(tmp_path):
    for name in ("ball_tracker.py", "ball_vision.py"):
        shutil.copy(ROOT / "controllers" / name, tmp_path / name)
    controller, out = tmp_path / "ball_tracker.py", tmp_path / "dump"
    dump(out, controller=controller, frames=2, formats=("rgb",))
    assert len(json.loads((out / "meta.json").read_text())["parameters"]["controller_sha256"]) == 64
    assert dump(out, controller=controller, frames=2, formats=("rgb",), resume=True).new_frames == 0
    before = _snapshot(out, lock=False)
    with pytest.raises(DumpError, match=r"other parameters \(formats\)"):
        dump(out, controller=controller, frames=2, formats=("rgb", "seg"), resume=True)
    controller.write_text(controller.read_text() + "\nGAIN = 0.7\n")
    with pytest.raises(DumpError, match=r"cannot resume, the controller file .*ball_tracker\.py changed"):
        dump(out, controller=controller, frames=2, formats=("rgb",), resume=True)
    assert _snapshot(out, lock=False) == before


@pytest.mark.skipif(not shutil.which("cc"), reason="needs cc")
def test_resume_refuses_a_c_controller_whose_own_header_changed(tmp_path, monkeypatch):
    """Only the sources were hashed: a changed ball_vision.h resumed with the changed controller."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    controller, out = tmp_path / "tracker", tmp_path / "dump"
    shutil.copytree(ROOT / "controllers" / "ball_tracker_c", controller)
    (controller / "ball_tracker_c.c").rename(controller / "tracker.c")
    dump(out, controller=controller, frames=2, formats=("rgb",))
    header = controller / "ball_vision.h"
    header.write_text(header.read_text() + "\n#define CHANGED 1\n")
    with pytest.raises(DumpError, match=r"cannot resume, the controller .* changed"):
        dump(out, controller=controller, frames=2, formats=("rgb",), resume=True)


# ---------------------------------------------------------------- folders that are not a dump


@pytest.mark.parametrize("resume", [False, True], ids=["new", "resume"])
def test_a_folder_that_is_not_a_dump_is_refused_and_untouched(tmp_path, capsys, resume):
    out = tmp_path / "mine"
    (out / "notes" / "deep").mkdir(parents=True)
    (out / "frames.jsonl").write_text('{"a user\'s": "lines"}\n')
    (out / "notes" / "deep" / ".tmp.keep").write_text("mine")
    (out / "rgb").mkdir()
    (out / "rgb" / ".tmp.000001.png").write_text("also mine")
    before = _snapshot(out)
    argv = ["dump", str(TRACKER), "--out", str(out), "--steps", "2"] + ["--resume"] * resume
    assert main(argv) == 2
    error = capsys.readouterr().err
    assert (
        error == f"aibo-sim: error: {out} is not empty and is not a dump (no meta.json): refusing to write into "
        "it; choose a new or empty folder for --out\n"
    )
    (out / "meta.json").write_text('{"not": "a dump"}')
    before = _snapshot(out)
    assert main(argv) == 2
    assert "meta.json: not an aibo-sim dump's meta.json" in capsys.readouterr().err
    assert _snapshot(out) == before


def test_only_the_dumps_own_temporary_files_are_removed(small_dump, tmp_path):
    out = tmp_path / "dump"
    shutil.copytree(small_dump, out)
    own = [
        out / ".tmp.video.mp4",
        out / ".tmp.meta.json",
        out / "rgb" / ".tmp.000002.png",
        out / "yuv420" / ".tmp.000009.yuv",
    ]
    others = [
        out / ".tmp.notes",
        out / "rgb" / ".tmp.notes.txt",
        out / "rgb" / ".tmp.000002.jpg",
        out / "extra" / ".tmp.000001.png",
        out / "extra" / "rgb" / ".tmp.000001.png",
    ]
    for path in own + others:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("partial")
    assert dump(out, controller=TRACKER, frames=4, formats=("rgb", "yuv420"), resume=True).new_frames == 0
    assert [p for p in own if p.exists()] == [] and all(p.read_text() == "partial" for p in others)


# ---------------------------------------------------------------- corrupt files


def test_corrupt_meta_and_frames_name_the_file_and_line(small_dump, tmp_path, capsys):
    out = tmp_path / "dump"
    shutil.copytree(small_dump, out)
    lines = (out / "frames.jsonl").read_bytes().splitlines(keepends=True)
    lines[2] = lines[2][:30] + b"\x00garbage\n"
    (out / "frames.jsonl").write_bytes(b"".join(lines))
    with pytest.raises(DumpError, match=r"frames\.jsonl: line 3: not valid JSON"):
        load_dump(out)
    argv = ["dump", str(TRACKER), "--out", str(out), "--steps", "4", "--formats", "rgb,yuv420", "--resume"]
    before = _snapshot(out, lock=False)
    assert main(argv) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and f"{out / 'frames.jsonl'}: line 3: not valid JSON" in error
    assert _snapshot(out, lock=False) == before
    lines[2] = b'{"no index": 1}\n'
    (out / "frames.jsonl").write_bytes(b"".join(lines))
    with pytest.raises(DumpError, match=r"frames\.jsonl: line 3: not a frame record"):
        load_dump(out)
    meta = (out / "meta.json").read_text().splitlines(keepends=True)
    (out / "meta.json").write_text("".join(meta[:3]) + "  oops\n" + "".join(meta[3:]))
    with pytest.raises(DumpError, match=r"meta\.json: line 4 column 3: not valid JSON"):
        load_dump(out)
    assert main(argv) == 2
    assert f"{out / 'meta.json'}: line 4 column 3: not valid JSON" in capsys.readouterr().err
    (out / "meta.json").write_bytes(b'{"format": "\xff"}')
    with pytest.raises(DumpError, match=r"meta\.json: not UTF-8"):
        load_dump(out)


def test_resume_rewrites_fixed_size_files_of_the_wrong_size(tmp_path, capsys):
    formats = ("rgb", "yuv420", "openr", "depth")
    reference = tmp_path / "reference"
    dump(reference, controller=TRACKER, frames=10, formats=formats)
    out = tmp_path / "dump"
    shutil.copytree(reference, out)
    for name in ("openr/000009.ofbk", "yuv420/000003.yuv", "depth/000003.npy"):
        with open(out / name, "r+b") as file:
            file.truncate(100)
    argv = ["dump", str(TRACKER), "--out", str(out), "--steps", "10", "--formats", ",".join(formats), "--resume"]
    assert main(argv) == 0
    assert "(0 written now, 2 with missing or damaged files rewritten)" in capsys.readouterr().out
    assert {k: v[0] for k, v in _snapshot(out).items()} == {k: v[0] for k, v in _snapshot(reference).items()}


def test_load_dump_names_a_damaged_file(small_dump, tmp_path):
    out = tmp_path / "dump"
    shutil.copytree(small_dump, out)
    yuv, png = out / "yuv420" / "000001.yuv", out / "rgb" / "000002.png"
    with open(yuv, "r+b") as file:
        file.truncate(0)
    png.write_bytes(b"not a PNG")
    frames = load_dump(out)
    with pytest.raises(
        DumpError, match=f"^{re.escape(str(yuv))}: 0 bytes, expected 49920; the file is truncated or corrupt$"
    ):
        _ = frames[1].yuv420
    with pytest.raises(DumpError, match=f"^{re.escape(str(png))}: not a readable PNG; the file is corrupt$"):
        _ = frames[2].rgb
    assert frames[2].yuv420[0].shape == frames[1].rgb.shape[:2]


# ---------------------------------------------------------------- run --out


def test_run_frames_are_written_under_names_no_frame_pattern_matches(tmp_path, monkeypatch):
    renamed = watch_renames(monkeypatch)
    summary = run_controller(TRACKER, duration=0.2, out=tmp_path)
    frames = [(s, t) for s, t in renamed if t.parent == tmp_path / "frames"]
    assert len(frames) == summary.camera_frames >= 3
    for source, target in frames:
        assert source.parent == target.parent and fnmatch.fnmatch(target.name, "*.png")
        assert not fnmatch.fnmatch(source.name, "*.png") and not source.match("*.png")
    assert sorted(p.name for p in (tmp_path / "frames").iterdir()) == sorted(t.name for _, t in frames)


def test_a_reused_run_folder_holds_one_run(tmp_path, capsys):
    out = tmp_path / "run"
    long = run_controller(TRACKER, duration=0.5, out=out)
    (out / "notes.txt").write_text("the controller's or the user's: kept")
    short = run_controller(TRACKER, duration=0.2, out=out)
    assert long.camera_frames > short.camera_frames
    assert len(list((out / "frames").iterdir())) == short.camera_frames
    assert json.loads((out / "run.json").read_text())["camera_frames"] == short.camera_frames
    assert (out / "notes.txt").exists()
    # A killed run (run.json still says "incomplete", a temporary frame left) is an earlier run too.
    (out / "run.json").write_text(json.dumps({"controller": str(TRACKER), "backend": "sim", "status": "incomplete"}))
    (out / "frames" / ".000099.png.tmp").write_bytes(b"partial")
    (out / "frames" / "000099.partial.png").write_bytes(b"partial")  # an earlier version's temporary name
    assert run_controller(TRACKER, duration=0.2, out=out).camera_frames == short.camera_frames
    assert len(list((out / "frames").iterdir())) == short.camera_frames
    # Folders that hold something else are refused, untouched.
    refused = {
        "foreign run.json": {"run.json": '{"mine": true}'},
        "frames without run.json": {"frames/000001.png": "ffmpeg's"},
        "foreign file in frames": {
            "run.json": json.dumps({"controller": "x", "backend": "sim"}),
            "frames/000001.png": "",
            "frames/notes.txt": "mine",
        },
    }
    for case, files in refused.items():
        folder = tmp_path / case.replace(" ", "_")
        for name, text in files.items():
            (folder / name).parent.mkdir(parents=True, exist_ok=True)
            (folder / name).write_text(text)
        before = _snapshot(folder)
        capsys.readouterr()
        assert main(["run", str(TRACKER), "--duration", "0.1", "--out", str(folder)]) == 2, case
        error = capsys.readouterr().err
        assert error.startswith("aibo-sim: error: ") and error.count("\n") == 1 and "refusing" in error, case
        assert _snapshot(folder) == before, case


@pytest.mark.slow
@pytest.mark.skipif(not hasattr(resource, "RLIMIT_FSIZE"), reason="needs RLIMIT_FSIZE")
def test_run_out_on_a_full_disk_is_exit_2_naming_the_file(tmp_path):
    """A write the system refuses (here the file-size limit: EFBIG, as ENOSPC on a full disk)."""

    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))  # run.json's start fits, no frame does
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)

    out = tmp_path / "run"
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1", "MESA_SHADER_CACHE_DISABLE": "true"}
    result = subprocess.run(
        _cli("run", str(TRACKER), "--duration", "0.3", "--out", str(out)),
        cwd=ROOT,
        env=env,
        preexec_fn=limit,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 2, result.stderr
    assert result.stderr == f"aibo-sim: error: cannot write {out / 'frames' / '000000.png'}: File too large\n"
    assert list((out / "frames").iterdir()) == []  # no partial file
    record = json.loads((out / "run.json").read_text())  # small enough for the limit: says why the run ended
    assert (record["status"], record["camera_frames"]) == ("failed", 0)
    assert record["error"] == f"cannot write {out / 'frames' / '000000.png'}: File too large"


def test_resume_refuses_a_scene_whose_model_changed(tmp_path):
    models = tmp_path / "models"
    shutil.copytree(ROOT / "models", models)
    scene = models / "scene.xml"
    out = tmp_path / "dump"
    dump(out, controller=TRACKER, frames=3, formats=("rgb",), world=WorldConfig(scene=scene))
    dump(
        out, controller=TRACKER, frames=3, formats=("rgb",), resume=True, world=WorldConfig(scene=scene)
    )  # unchanged: fine
    robot = models / "ers7.xml"
    text = robot.read_text()
    assert 'timestep="0.002"' in text
    robot.write_text(text.replace('timestep="0.002"', 'timestep="0.001"'))
    with pytest.raises(DumpError, match=r"cannot resume, the dump was made with other parameters \(model_sha256\)"):
        dump(out, controller=TRACKER, frames=3, formats=("rgb",), resume=True, world=WorldConfig(scene=scene))


@pytest.mark.slow
def test_a_shards_error_names_the_shard(tmp_path):
    from aibo_sim.runner import ControllerFailed

    bad = tmp_path / "bad.py"
    bad.write_text("from aibo_sim.controller import *\nrobot_step(64)\nraise RuntimeError('lost the ball')\n")
    with pytest.raises(
        ControllerFailed, match=r"^shard_\d: controller bad\.py raised at simulated t = 0\.064 s"
    ) as failed:
        dump(tmp_path / "dump", controller=bad, frames=8, workers=2, formats=("rgb",))
    assert "lost the ball" in str(failed.value)


def test_render_on_a_full_disk_leaves_the_earlier_set_whole(tmp_path, monkeypatch, capsys):
    """render writes its pictures and head_camera.json as one set: a write refused part way (the
    disk full at tracking.png, after head_camera.png is on disk) leaves the earlier set untouched."""
    import errno

    import aibo_sim.files

    out = tmp_path / "render"
    assert main(["render", "--settle", "0", "--out", str(out)]) == 0
    before = _snapshot(out)
    real_create = aibo_sim.files.create_file

    def create_until_full(path, *args, **kwargs):
        if "tracking" in Path(path).name:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real_create(path, *args, **kwargs)

    monkeypatch.setattr(aibo_sim.files, "create_file", create_until_full)
    capsys.readouterr()
    assert main(["render", "--settle", "0", "--seed", "5", "--pose", "0.2", "0", "30", "--out", str(out)]) == 2
    assert capsys.readouterr().err == f"aibo-sim: error: cannot write {out / 'tracking.png'}: No space left on device\n"
    assert _snapshot(out) == before  # no new head_camera.png beside the old tracking.png, no temporary file


def test_a_set_whose_target_is_a_folder_is_not_half_replaced(tmp_path):
    from aibo_sim.files import write_files_atomic

    (tmp_path / "a.png").write_bytes(b"old")
    (tmp_path / "b.png").mkdir()
    with pytest.raises(OSError, match=rf"^cannot write {tmp_path / 'b.png'}: Is a directory$"):
        write_files_atomic({tmp_path / "a.png": b"new", tmp_path / "b.png": b"new"})
    assert (tmp_path / "a.png").read_bytes() == b"old" and sorted(p.name for p in tmp_path.iterdir()) == [
        "a.png",
        "b.png",
    ]


# ---------------------------------------------------------------- bad input refused before anything is written


def _scene(tmp_path: Path, ball: str) -> Path:
    """A scene of the robot on a floor: no ball (``""``), or a ball body without a free joint."""
    from aibo_sim.sim import models_dir

    scene = tmp_path / "scene.xml"
    scene.write_text(f"""<mujoco>
  <include file="{models_dir() / "ers7.xml"}"/>
  <worldbody><geom name="floor" type="plane" size="2 2 0.1"/>{ball}</worldbody>
</mujoco>""")
    return scene


FIXED_BALL = '<body name="ball" pos="0.5 0 0.042"><geom name="ball" type="sphere" size="0.042"/></body>'


@pytest.mark.parametrize(
    "env, ball, workers",
    [("ReachBall", "", "1"), ("HeadTrackBall", FIXED_BALL, "2")],
    ids=["reach-no-ball", "track-fixed-ball-sharded"],
)
def test_an_env_dump_in_a_scene_whose_ball_cannot_be_placed_writes_nothing(tmp_path, capsys, env, ball, workers):
    scene, out = _scene(tmp_path, ball), tmp_path / "dump"
    argv = [
        "dump",
        "--env",
        f"aibo_sim/{env}-v0",
        "--scene",
        str(scene),
        "--out",
        str(out),
        "--steps",
        "4",
        "--workers",
        workers,
    ]
    assert main(argv) == 2
    error = capsys.readouterr().err
    assert error.startswith(f"aibo-sim: error: --scene {scene}: environment aibo_sim/{env}-v0 places the ball, but ")
    assert error.count("\n") == 1 and not out.exists()


@pytest.mark.slow
def test_a_sharded_controller_dump_in_a_scene_without_a_ball_runs_as_one_worker_does(tmp_path):
    scene = _scene(tmp_path, "")
    dump(tmp_path / "one", controller=TRACKER, frames=4, formats=("rgb",), world=WorldConfig(scene=scene))
    dump(tmp_path / "two", controller=TRACKER, frames=4, formats=("rgb",), workers=2, world=WorldConfig(scene=scene))
    shard = json.loads((tmp_path / "two" / "shard_0" / "meta.json").read_text())["parameters"]
    assert (shard["ball"], shard["seed"], len(load_dump(tmp_path / "two"))) == (None, 0, 4)
    for index in range(2):  # shard 0 is the one-worker dump's start
        name = f"rgb/{index:06d}.png"
        assert (tmp_path / "two" / "shard_0" / name).read_bytes() == (tmp_path / "one" / name).read_bytes()


@pytest.mark.parametrize(
    "argv, message",
    [
        (
            ["--seed", str(2**64 - 1), "--workers", "2"],
            "--seed 18446744073709551615: must be a whole number from 0 to 2**64 - 2 with 2 workers "
            "(shard k uses seed + k)",
        ),
        (["--formats", "all,rgb"], "--formats all,rgb: all (every format) cannot be combined with other names"),
    ],
    ids=["seed", "formats"],
)
def test_options_that_cannot_work_together_are_refused_before_the_folder(tmp_path, capsys, argv, message):
    out = tmp_path / "dump"
    assert main(["dump", str(TRACKER), "--out", str(out), "--steps", "4", *argv]) == 2
    assert capsys.readouterr().err == f"aibo-sim: error: {message}\n"
    assert not out.exists()


@pytest.fixture(scope="module")
def coco_dump(tmp_path_factory):
    out = tmp_path_factory.mktemp("coco") / "dump"
    dump(out, controller=TRACKER, frames=4, formats=("rgb", "coco"))
    return out


BALL = {"category": "ball", "object": "ball", "bbox": [1, 2, 3, 4], "area": 9, "visibility": 1.0}


@pytest.mark.parametrize(
    "change, message",
    [
        ({"objects": None}, '"objects" is not a list of detections'),
        ({"objects": {"a": 1}}, '"objects" is not a list of detections'),
        ({"objects": [1]}, '"objects" is not a list of detections'),
        ({"objects": [{}]}, '"objects" is not a list of detections'),
        ({"objects": [{k: v for k, v in BALL.items() if k != "object"}]}, '"objects" is not a list of detections'),
        ({"objects": [{**BALL, "category": "nope"}]}, '"objects" is not a list of detections'),
        ({"index": 99999999}, "frame index 99999999 is past the dump's frames (its indices are below 4)"),
    ],
    ids=["null", "object", "number", "empty", "no-object", "category", "index"],
)
def test_a_bad_frame_record_is_a_corrupt_line_and_nothing_changes(coco_dump, tmp_path, capsys, change, message):
    out = tmp_path / "dump"
    shutil.copytree(coco_dump, out)
    lines = (out / "frames.jsonl").read_text().splitlines(keepends=True)
    lines[2] = json.dumps({**json.loads(lines[2]), **change}) + "\n"
    (out / "frames.jsonl").write_text("".join(lines))
    with pytest.raises(DumpError, match=f"frames\\.jsonl: line 3: {re.escape(message)}.*; the file is corrupt$"):
        load_dump(out)
    before = _snapshot(out, lock=False)
    assert main(["dump", str(TRACKER), "--out", str(out), "--steps", "4", "--formats", "rgb,coco", "--resume"]) == 2
    error = capsys.readouterr().err
    assert error.startswith(f"aibo-sim: error: {out / 'frames.jsonl'}: line 3: {message}") and error.count("\n") == 1
    assert _snapshot(out, lock=False) == before


def _set(meta: dict, path: str, value) -> None:
    *parents, key = path.split(".")
    for parent in parents:
        meta = meta[parent]
    if value is KeyError:
        del meta[key]
    else:
        meta[key] = value


@pytest.mark.parametrize(
    "path, value, field",
    [
        ("files.rgb.path", KeyError, '"files"."rgb"."path"'),
        ("files.rgb.path", 3, '"files"."rgb"."path"'),
        ("files.rgb.path", "rgb/{frame}.png", '"files"."rgb"."path"'),
        ("files.rgb", "x", '"files"."rgb"'),
        ("files.yuv420.bytes", "x", '"files"."yuv420"."bytes"'),
        ("camera.width", KeyError, '"camera"."width"'),
        ("camera.width", "x", '"camera"."width"'),
        ("camera.height", 0, '"camera"."height"'),
        ("segmentation_classes", 5, '"segmentation_classes"'),
        ("parameters.frames", None, '"parameters"."frames"'),
        ("camera", [], '"camera"'),
    ],
)
def test_load_dump_names_a_damaged_field_of_meta_json(small_dump, tmp_path, path, value, field):
    out = tmp_path / "dump"
    shutil.copytree(small_dump, out)
    meta = json.loads((out / "meta.json").read_text())
    _set(meta, path, value)
    (out / "meta.json").write_text(json.dumps(meta))
    with pytest.raises(
        DumpError, match=f"^{re.escape(str(out / 'meta.json'))}: {re.escape(field)} must be .*; the file is corrupt$"
    ):
        load_dump(out)


@pytest.mark.slow
def test_a_shard_without_meta_json_is_named_as_damaged_with_the_way_out(tmp_path, capsys):
    out = tmp_path / "sharded"
    argv = ["dump", str(TRACKER), "--out", str(out), "--steps", "2", "--workers", "2", "--formats", "rgb"]
    assert main(argv) == 0
    (out / "shard_1" / "meta.json").unlink()
    before = {name: data for name, (data, _) in _snapshot(out, lock=False).items()}
    capsys.readouterr()
    assert main([*argv, "--resume"]) == 2
    shard = out / "shard_1"
    assert (
        capsys.readouterr().err == f"aibo-sim: error: {shard}: this shard of the dump in {out} has no meta.json: "
        f"the shard is damaged; remove {shard} and --resume to write the shard again\n"
    )
    assert {name: data for name, (data, _) in _snapshot(out, lock=False).items()} == before
    shutil.rmtree(shard)
    assert main([*argv, "--resume"]) == 0 and len(load_dump(out)) == 2


def test_a_file_in_place_of_the_controllers_folder_is_named(small_dump, tmp_path, capsys):
    out = tmp_path / "dump"
    shutil.copytree(small_dump, out)
    shutil.rmtree(out / "controller_files")
    (out / "controller_files").write_text("mine")
    assert main(["dump", str(TRACKER), "--out", str(out), "--steps", "4", "--formats", "rgb,yuv420", "--resume"]) == 2
    assert (
        capsys.readouterr().err == f"aibo-sim: error: {out / 'controller_files'}: not a folder (the controller "
        "runs in it): move it away, then --resume\n"
    )
    assert (out / "controller_files").read_text() == "mine"
