"""``aibo-sim run --view``: MuJoCo's viewer on the running simulation, on a virtual display."""

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

from aibo_sim import cli

ROOT = Path(__file__).resolve().parents[1]
CONTROLLER = ROOT / "controllers" / "ball_tracker.py"


def read_xwd(data: bytes) -> np.ndarray:
    """RGB pixels of an X window dump (``xwd``) of a 24/32-bit TrueColor screen."""
    header = struct.unpack(">25I", data[:100])
    header_size, width, height, bytes_per_line, colormap_entries = header[0], header[4], header[5], header[12], header[19]
    offset = header_size + 12 * colormap_entries
    rows = np.frombuffer(data[offset:offset + bytes_per_line * height], np.uint8).reshape(height, bytes_per_line)
    return rows[:, :4 * width].reshape(height, width, 4)[..., 2::-1]  # B, G, R, x in memory


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


@pytest.mark.skipif(not (shutil.which("Xvfb") and shutil.which("xwd")), reason="needs Xvfb and xwd (CI installs them)")
def test_view_shows_the_robot_on_a_virtual_display(tmp_path):
    read_fd, write_fd = os.pipe()
    xvfb = subprocess.Popen(["Xvfb", "-displayfd", str(write_fd), "-screen", "0", "1280x800x24", "-nolisten", "tcp"],
                            pass_fds=(write_fd,), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.close(write_fd)
    display = ":" + os.read(read_fd, 16).decode().strip()
    os.close(read_fd)
    env = {**os.environ, "DISPLAY": display}
    run = subprocess.Popen([sys.executable, "-m", "aibo_sim.cli", "run", str(CONTROLLER), "--duration", "30", "--view"],
                           env=env, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        blob, screen, deadline = 0, None, time.monotonic() + 60
        while blob < 1000 and time.monotonic() < deadline and run.poll() is None:
            time.sleep(1)
            dump = subprocess.run(["xwd", "-root", "-silent", "-display", display], capture_output=True)
            if dump.returncode == 0:  # the server may refuse a dump while a client sets up its window
                screen = read_xwd(dump.stdout)
                blob = largest_white_blob(screen)
        assert screen is not None, f"xwd never dumped the screen: {dump.stderr.decode()}"
        cv2.imwrite(str(tmp_path / "screenshot.png"), screen[..., ::-1])
        assert run.poll() is None, run.communicate()[1].decode()
        assert blob >= 1000, f"no robot on the screen (largest white patch {blob} px): {tmp_path / 'screenshot.png'}"
    finally:
        run.terminate()
        run.communicate(timeout=30)
        xvfb.terminate()
        xvfb.wait(timeout=30)
