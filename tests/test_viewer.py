"""``aibo-sim run --view``: MuJoCo's viewer on the running simulation, on a virtual display."""

import json
import os
import shutil
import struct
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest
from openr_support import build_programs, make_stick

from aibo_sim import cli

pytestmark = pytest.mark.slow  # heavy: run by CI and by python -m pytest -m slow

ROOT = Path(__file__).resolve().parents[1]
CONTROLLER = ROOT / "controllers" / "ball_tracker.py"


def read_xwd(data: bytes) -> np.ndarray:
    """RGB pixels of an X window dump (``xwd``) of a 24/32-bit TrueColor screen."""
    header = struct.unpack(">25I", data[:100])
    header_size, width, height, bytes_per_line, colormap_entries = (
        header[0],
        header[4],
        header[5],
        header[12],
        header[19],
    )
    offset = header_size + 12 * colormap_entries
    rows = np.frombuffer(data[offset : offset + bytes_per_line * height], np.uint8).reshape(height, bytes_per_line)
    return rows[:, : 4 * width].reshape(height, width, 4)[..., 2::-1]  # B, G, R, x in memory


def largest_white_blob(rgb: np.ndarray) -> int:
    """Area in pixels of the largest connected patch of near-white (the robot's shell)."""
    rgb = rgb.astype(int)
    white = ((rgb.min(axis=2) > 215) & (np.ptp(rgb, axis=2) < 25)).astype(np.uint8)
    _, _, stats, _ = cv2.connectedComponentsWithStats(white)
    return int(stats[1:, cv2.CC_STAT_AREA].max(initial=0))


def test_view_without_a_display_says_so(monkeypatch, capsys):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert cli.main(["run", str(CONTROLLER), "--duration", "0.1", "--view"]) == 2
    assert "--view needs a display" in capsys.readouterr().err


def test_view_with_a_display_that_cannot_be_opened_is_one_line(tmp_path):
    """GLFW's own complaint came first, as a Python warning over two lines."""
    environment = {k: v for k, v in os.environ.items() if k != "WAYLAND_DISPLAY"}
    command = [sys.executable, "-m", "aibo_sim.cli", "run", str(CONTROLLER), "--duration", "0.1", "--view"]
    result = subprocess.run(
        command + ["--out", str(tmp_path / "out")],
        env={**environment, "DISPLAY": ":99"},
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 2 and len(result.stderr.splitlines()) == 1, result.stderr
    assert result.stderr.startswith("aibo-sim: error: --view: cannot open the display ':99' (")
    assert not (tmp_path / "out").exists()


def screen_dump(display: str) -> np.ndarray | None:
    """The virtual screen's pixels, or None while its server refuses (starting, busy)."""
    dump = subprocess.run(["xwd", "-root", "-silent", "-display", display], capture_output=True)
    return read_xwd(dump.stdout) if dump.returncode == 0 else None


@pytest.mark.skipif(not (shutil.which("Xvfb") and shutil.which("xwd")), reason="needs Xvfb and xwd (CI installs them)")
def test_view_shows_the_robot_on_a_virtual_display(tmp_path):
    read_fd, write_fd = os.pipe()
    xvfb = subprocess.Popen(
        ["Xvfb", "-displayfd", str(write_fd), "-screen", "0", "1280x800x24", "-nolisten", "tcp"],
        pass_fds=(write_fd,),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    os.close(write_fd)
    number = b""
    while not number.endswith(b"\n"):  # the whole line: Xvfb dies if the pipe closes while it writes
        chunk = os.read(read_fd, 16)
        assert chunk, f"Xvfb: {xvfb.communicate()[1].decode()}"
        number += chunk
    os.close(read_fd)
    display = ":" + number.decode().strip()
    run = None
    try:
        deadline = time.monotonic() + 30
        while screen_dump(display) is None:  # the server takes connections
            assert time.monotonic() < deadline and xvfb.poll() is None, f"Xvfb {display} did not start"
            time.sleep(0.2)
        run = subprocess.Popen(
            [sys.executable, "-m", "aibo_sim.cli", "run", str(CONTROLLER), "--duration", "30", "--view"],
            env={**os.environ, "DISPLAY": display},
            cwd=tmp_path,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
        )
        blob, screen, deadline = 0, None, time.monotonic() + 60
        while blob < 1000 and time.monotonic() < deadline and run.poll() is None:
            time.sleep(1)
            screen = screen_dump(display)
            blob = 0 if screen is None else largest_white_blob(screen)
        assert run.poll() is None, f"the run ended: {run.communicate()[1].decode()}"
        assert screen is not None, "xwd never dumped the screen"
        cv2.imwrite(str(tmp_path / "screenshot.png"), screen[..., ::-1])
        assert blob >= 1000, f"no robot on the screen (largest white patch {blob} px): {tmp_path / 'screenshot.png'}"

        def watch(*arguments: str) -> None:
            """A short run with --view ends by itself and exits cleanly (GLFW ends after the viewer)."""
            watched = subprocess.run(
                [sys.executable, "-m", "aibo_sim.cli", "run", *arguments, "--duration", "0.3", "--view"],
                env={**os.environ, "DISPLAY": display},
                cwd=tmp_path,
                capture_output=True,
                text=True,
                timeout=120,
            )
            assert watched.returncode == 0, watched.stderr

        watch(str(CONTROLLER))
        # A memory stick's objects, watched the same way.
        watch(str(make_stick(tmp_path / "ms", build_programs(tmp_path / "openr"), ["JPROBE"])), "--out", "stick")
        assert json.loads((tmp_path / "stick" / "run.json").read_text())["backend"] == "memory stick"
        # A match, following robot 2 and showing its camera.
        watch(str(CONTROLLER), "--robot", "red:4", "--robot", "blue:4", "--view-robot", "2", "--out", "match")
        assert json.loads((tmp_path / "match" / "run.json").read_text())["status"] == "done"
    finally:
        if run is not None:
            run.terminate()
            run.communicate(timeout=30)
        xvfb.terminate()
        xvfb.communicate(timeout=30)
