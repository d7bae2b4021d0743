"""``dump --engine ray`` (issue 18): shards as Ray tasks on a real local Ray give the local
engine's bytes, resume, and survive a lost worker; without Ray, one line saying how to get it.
The progress line of long dumps."""

import io
import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from test_dump_reliability import _cli, _lines, _wait_for

from aibo_sim import runner
from aibo_sim.cli import main
from aibo_sim.dump import DumpError, dump
from aibo_sim.dump.writing import LOCK_NAME

pytestmark = pytest.mark.slow  # heavy: run by CI and by python -m pytest -m slow

ROOT = Path(__file__).resolve().parents[1]
TRACKER = ROOT / "controllers" / "ball_tracker.py"
FORMATS = ("rgb", "yuv420", "openr", "seg", "coco", "mp4")
STARTUP_S = 60  # Ray's workers' imports and first frames, on a loaded machine


@pytest.fixture(scope="module")
def ray():
    ray = pytest.importorskip("ray")
    ray.init(num_cpus=2, include_dashboard=False)
    yield ray
    ray.shutdown()


def _files(folder: Path) -> dict:
    return {
        str(p.relative_to(folder)): p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and p.name != LOCK_NAME
    }


@pytest.fixture(scope="module")
def local_dump(tmp_path_factory):
    out = tmp_path_factory.mktemp("local") / "dump"
    dump(out, controller=TRACKER, frames=12, workers=2, formats=FORMATS)
    return out


def test_ray_gives_the_local_engines_bytes_and_resumes(ray, local_dump, tmp_path):
    out = tmp_path / "ray"
    summary = dump(out, controller=TRACKER, frames=12, workers=2, formats=FORMATS, engine="ray")
    assert (summary.frames, summary.new_frames) == (12, 12)
    reference = _files(local_dump)
    assert len(reference) > 20 and _files(out) == reference
    # Interrupted: shard 1 lost its last frames, the top coco.json is missing.
    lines = (out / "shard_1" / "frames.jsonl").read_bytes().splitlines(keepends=True)
    (out / "shard_1" / "frames.jsonl").write_bytes(b"".join(lines[:2]))
    (out / "coco.json").unlink()
    summary = dump(out, controller=TRACKER, frames=12, workers=2, formats=FORMATS, engine="ray", resume=True)
    assert summary.new_frames == 4 and _files(out) == reference
    with pytest.raises(DumpError, match="already holds a dump: pass --resume"):
        dump(out, controller=TRACKER, frames=12, workers=2, formats=FORMATS, engine="ray")


def test_sigterm_stops_a_ray_dump_cleanly_with_143(tmp_path):
    """ray.init puts its own SIGTERM handler (an exit with status 1 at once): the command's is put
    back, so a Ray dump stops as a local one does, saying how to resume."""
    out = tmp_path / "dump"
    command = ["dump", str(TRACKER), "--out", str(out), "--steps", "3000", "--workers", "2", "--formats", "rgb"]
    dumping = subprocess.Popen(_cli(*command, "--engine", "ray"), cwd=ROOT, stderr=subprocess.PIPE, text=True)
    try:
        _wait_for(lambda: _lines(out / "shard_0") >= 2, STARTUP_S, "frames")
        dumping.send_signal(signal.SIGTERM)
        status = dumping.wait(STARTUP_S)
    finally:
        if dumping.poll() is None:
            dumping.kill()
            dumping.wait()
    error = dumping.stderr.read()
    assert status == 143 and "terminated (SIGTERM) (the dump can continue with --resume)" in error, error
    assert not list(out.rglob(".tmp.*"))


RAY_SIGTERM_SCRIPT = """
import os, signal, sys
import ray
from aibo_sim.dump.shards import ray_session

def handler(number, frame):
    raise KeyboardInterrupt("the command's handler")

signal.signal(signal.SIGTERM, handler)
set_handler = ray._private.utils.set_sigterm_handler

def set_then_signal(ray_handler):  # ray.init's first act: a SIGTERM arriving just after it
    set_handler(ray_handler)
    os.kill(os.getpid(), signal.SIGTERM)

ray._private.utils.set_sigterm_handler = set_then_signal
try:
    with ray_session(None):
        pass
except KeyboardInterrupt as exc:
    print("during ray.init:", exc, ray.is_initialized(), flush=True)
ray._private.utils.set_sigterm_handler = set_handler
with ray_session(None):
    pass
try:
    os.kill(os.getpid(), signal.SIGTERM)
except KeyboardInterrupt as exc:
    print("after ray.shutdown:", exc, flush=True)
"""


def test_a_sigterm_while_ray_starts_or_after_it_stopped_reaches_the_commands_handler():
    """Ray's handler (sys.exit(15)) took a SIGTERM during ray.init: exit 15, nothing said; after
    ray.shutdown, which sets SIGTERM's action back to the default, one killed the process."""
    pytest.importorskip("ray")
    done = subprocess.run(
        [sys.executable, "-c", RAY_SIGTERM_SCRIPT], cwd=ROOT, capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout == "during ray.init: the command's handler False\nafter ray.shutdown: the command's handler\n"


def test_a_lost_ray_worker_is_retried(ray, local_dump, tmp_path):
    out = tmp_path / "ray"
    killed = []

    def kill_shard_0_worker():  # the worker names itself in its shard's lock once it has frames
        deadline = time.monotonic() + STARTUP_S
        while time.monotonic() < deadline and not killed:
            try:
                if (out / "shard_0" / "frames.jsonl").read_bytes().count(b"\n") >= 2:
                    pid = json.loads((out / "shard_0" / LOCK_NAME).read_text())["pid"]
                    os.kill(pid, signal.SIGKILL)
                    killed.append(pid)
            except (OSError, ValueError, KeyError):
                time.sleep(0.005)

    killer = threading.Thread(target=kill_shard_0_worker)
    killer.start()
    try:
        summary = dump(out, controller=TRACKER, frames=12, workers=2, formats=FORMATS, engine="ray")
    finally:
        killer.join()
    assert killed and killed[0] != os.getpid(), "the shard ended before its worker could be killed"
    assert summary.frames == 12 and _files(out) == _files(local_dump)
    assert summary.new_frames == 12  # the lost attempt's frames too: the retry counted only its own


def test_engine_ray_without_ray_is_one_line_naming_the_extra(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray -> ImportError
    out = tmp_path / "d"
    assert main(["dump", str(TRACKER), "--out", str(out), "--steps", "4", "--workers", "2", "--engine", "ray"]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "--engine ray needs Ray" in error and "pip install 'aibo-sim[ray]'" in error
    assert not out.exists()


def test_a_bad_ray_address_is_one_line_and_changes_nothing(tmp_path, capsys):
    out = tmp_path / "d"
    assert main(["dump", str(TRACKER), "--out", str(out), "--steps", "4", "--ray-address", "auto"]) == 2
    assert "--ray-address applies to --engine ray" in capsys.readouterr().err
    pytest.importorskip("ray")
    assert (
        main(
            [
                "dump",
                str(TRACKER),
                "--out",
                str(out),
                "--steps",
                "4",
                "--workers",
                "2",
                "--engine",
                "ray",
                "--ray-address",
                "127.0.0.1:1",
            ]
        )
        == 2
    )  # nothing listens on port 1
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "--ray-address 127.0.0.1:1: no Ray cluster answers there" in error
    assert not out.exists()


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_shows_frames_real_time_factor_and_time_left_on_a_terminal_only(monkeypatch):
    clock = iter([0.0, 1.0, 0.0, 1.0])
    monkeypatch.setattr(runner.time, "monotonic", lambda: next(clock))
    terminal, pipe = _Terminal(), io.StringIO()
    for stream in (terminal, pipe):
        progress = runner.Progress(10.0, stream=stream)
        progress.update(0.0, 0)
        progress.update(2.0, 60)
        progress.close()
    assert terminal.getvalue() == f"\r[{'#' * 6:<30}] 60 frames, 2.00 / 10.00 s, 2.0x real time, 4 s left\x1b[K\n"
    assert pipe.getvalue() == ""
