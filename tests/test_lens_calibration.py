"""OpenCV's own calibration, run on head-camera frames of a checkerboard, recovers the lens the
simulator claims (``LENSES["tekkotsu"]``, what ``describe_camera`` writes to run.json and
meta.json): findChessboardCorners, cornerSubPix and calibrateCamera with the standard model
(k1, k2, p1, p2, k3), nothing of ours in the loop but the frames.

The board: 9 x 7 inner corners, 20 mm squares, a plane with MuJoCo's checker texture (texture
filtering draws its edges anti-aliased: drawn as box geoms, the head camera's render, without
multisampling, leaves each corner up to ~0.5 px off and 0.15-0.4 px rms) on a white plate, a
mocap body placed in the camera's frame. 54 shots: 9 aims (the image's corners, edges and
centre; the board pushed against the aimed border), 6 tilts of 15-35 degrees each. The claimed
lens frames the shots and tells OpenCV's two corner orders of the symmetric board apart, for
the comparison of corners; the calibration sees the frames alone.

What the frames show (numbers in the pixels of each size; std: OpenCV's own estimate), at
416 x 320 (``ideal`` profile with the tekkotsu lens, and ``ers7``) and at 208 x 160 (``ers7``,
the default):

- corners found where the recorded lens projects the board's corners: mean offset at most
  0.013 px, rms 0.04-0.08 px. What is left is the bilinear remap from the pinhole render to
  the lens's image (OpenCV's remap for ``ideal``, the sensor's two-pass ``lens.Warp`` for
  ``ers7``): an offset of a few hundredths of a pixel, periodic in the sub-pixel phase at
  which the remap samples the render;
- fx, fy within 0.05 %, cx, cy within 0.12 px (std 0.05-0.12), the whole mapping from rays
  to pixels within 0.32-0.41 px of the recorded one over the whole image, edges included.

The render's principal point sits a whole number of pixels from the lens's
(``Lens.render_pinhole``), so the remap samples the render at its pixel centres around the
image centre. Before, it sampled 0.81 px off them in x, everywhere near the centre: the
remap's pattern then moved edges the same way all over the centre, and this calibration at
208 x 160 found cx 0.68 px to the right, p2 0.0015 instead of 0.0001 and a camera turned by
0.21 degrees (the mapping 0.8 px off throughout, 1.1 px at most).
"""

import math
import time

import cv2
import mujoco
import numpy as np
import pytest
from test_camera import emissive, target_scene

from aibo_sim.camera import LENSES, PROFILES, Lens
from aibo_sim.config import CameraConfig
from aibo_sim.sim import Simulation

COLUMNS, ROWS, SQUARE = 9, 7, 0.02  # inner corners, metres
BORDER = (
    1.0  # white plate beyond the outer squares, in squares (at 0.7, OpenCV put one outer corner 11 px off in one view)
)
PATTERN = (COLUMNS, ROWS)
OBJECT_POINTS = np.array(
    [
        ((c - (COLUMNS - 1) / 2) * SQUARE, (r - (ROWS - 1) / 2) * SQUARE, 0.0)
        for r in range(ROWS)
        for c in range(COLUMNS)
    ],
    np.float32,
)
# What must be inside the picture: the squares and 0.2 square of white around them.
_HALF_X, _HALF_Y = (COLUMNS + 1.2) / 2 * SQUARE, (ROWS + 1.2) / 2 * SQUARE
OUTLINE = np.array([(x, y, 0.0) for x in np.linspace(-_HALF_X, _HALF_X, 9) for y in np.linspace(-_HALF_Y, _HALF_Y, 9)])
AIMS = ((-1, -1), (1, -1), (-1, 1), (1, 1), (0, 0), (-1, 0), (1, 0), (0, -1), (0, 1))
TILT_AXES = ((1, 0, 0), (1, -1, 0), (0, 1, 0), (-1, -1, 0), (-1, 0, 0), (-1, 1, 0), (0, -1, 0), (1, 1, 0))
CHECKER = (
    '<texture name="checker" type="2d" builtin="checker" rgb1="0 0 0" rgb2="1 1 1" width="512" height="512"/>'
    f'<material name="checker" texture="checker" texrepeat="{(COLUMNS + 1) / 2} {(ROWS + 1) / 2}" emission="1" '
    'specular="0"/>'
)
_MUJOCO_TO_OPENCV = np.diag([1.0, -1.0, -1.0])
# Board distances (m; the centred shots, the others) and cornerSubPix's half window by width:
# squares of ~17-26 px at 416 x 320, ~16-20 px at 208 x 160.
SHOTS = {416: (0.3, 0.42, 7), 208: (0.2, 0.24, 4)}


def checkerboard() -> str:
    """The board as a mocap body, its corners at ``OBJECT_POINTS`` (board frame: x along the
    columns, y along the rows, z into the board, away from a camera that sees it): a textured
    plane facing -z on a white plate 0.1 mm behind it."""
    width, height = (COLUMNS + 1 + 2 * BORDER) * SQUARE / 2, (ROWS + 1 + 2 * BORDER) * SQUARE / 2
    plate = emissive("box", (0, 0, 0.0011), (width, height, 0.001), (1, 1, 1))
    squares = (
        f'<geom type="plane" size="{(COLUMNS + 1) * SQUARE / 2} {(ROWS + 1) * SQUARE / 2} 0.01" quat="0 1 0 0" '
        'material="checker" contype="0" conaffinity="0"/>'
    )
    return f'<body name="board" mocap="true" pos="1 0 0">{plate}{squares}</body>'


def board_scene(tmp_path):
    """The robot floating before the board, no other light (``test_camera.target_scene``)."""
    scene = target_scene(tmp_path, checkerboard())
    scene.write_text(scene.read_text().replace("<asset>", "<asset>" + CHECKER, 1))
    return scene


def rotation(axis, degrees: float) -> np.ndarray:
    return cv2.Rodrigues(np.asarray(axis, float) / np.linalg.norm(axis) * math.radians(degrees))[0]


def views() -> list[tuple[np.ndarray, tuple[int, int]]]:
    """(board rotation in the camera frame, aim) of each shot: at each of the 9 aims, 6 tilts of
    15-35 degrees about axes in the board's plane, turned 5 degrees either way about its normal."""
    shots = []
    for k in range(6 * len(AIMS)):
        tilt = rotation(TILT_AXES[(k * 3) % len(TILT_AXES)], 15 + 5 * ((k * 7) % 5))
        shots.append((tilt @ rotation((0, 0, 1), 5 if k % 2 else -5), AIMS[k // 6]))
    return shots


def framed(lens: Lens, turn: np.ndarray, aim: tuple[int, int], distance: float, margin: float = 2.0) -> np.ndarray:
    """The board's position in the camera frame that pushes its outline against the image's
    border ``margin`` px in (the aimed side; centred along an axis aimed 0), stepping back
    while it does not fit."""
    position = np.array([0.0, 0.0, distance])
    low = np.array([margin - 0.5, margin - 0.5])
    high = np.array([lens.width - 0.5 - margin, lens.height - 0.5 - margin])
    aim = np.array(aim)
    target = np.where(aim < 0, low, np.where(aim > 0, high, (low + high) / 2))
    for _ in range(60):
        pixels, _ = lens.project(OUTLINE @ turn.T + position)
        now = np.where(aim < 0, pixels.min(0), np.where(aim > 0, pixels.max(0), (pixels.min(0) + pixels.max(0)) / 2))
        position[:2] += 0.7 * (target - now) / (lens.fx, lens.fy) * position[2]
        pixels, _ = lens.project(OUTLINE @ turn.T + position)
        if np.any(pixels.min(0) < low - 0.5) or np.any(pixels.max(0) > high + 0.5):
            position[2] *= 1.01
    return position


def place_board(sim: Simulation, turn: np.ndarray, position: np.ndarray) -> None:
    """Put the board at ``position`` turned ``turn`` in the head camera's OpenCV frame (x right,
    y down, z forward) of the current exposure."""
    frame = sim.camera.frame()
    to_world = frame.xmat @ _MUJOCO_TO_OPENCV
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, (to_world @ turn).ravel())
    mocap = sim.model.body("board").mocapid[0]
    sim.data.mocap_pos[mocap] = frame.position + to_world @ position
    sim.data.mocap_quat[mocap] = quat
    mujoco.mj_forward(sim.model, sim.data)
    sim.camera.moved()


def recorded_lens(sim: Simulation) -> Lens:
    """The lens as run.json / meta.json record it (``describe_camera``)."""
    d = sim.camera.describe()
    return Lens(d["lens"], d["fx"], d["fy"], d["cx"], d["cy"], tuple(d["distortion"]), d["width"], d["height"])


def shoot_and_calibrate(sim: Simulation, new_frame_each_shot: bool = False) -> dict:
    """Shoot every view, find and refine its corners with OpenCV, calibrate: the result, the
    corners and where the recorded lens projects the board's corners (for the comparison)."""
    lens = recorded_lens(sim)
    near, far, window = SHOTS[lens.width]
    found, expected = [], []
    for index, (turn, aim) in enumerate(views()):
        if new_frame_each_shot:  # a new exposure: new noise
            sim.step_frames(sim.frames_to_camera_frame())
        position = framed(lens, turn, aim, near if aim == (0, 0) else far)
        place_board(sim, turn, position)
        frame = sim.camera.frame()
        luma = np.ascontiguousarray(frame.ycrcb[..., 0])
        flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
        ok, corners = cv2.findChessboardCorners(luma, PATTERN, flags=flags)
        if not ok:  # 416x320's noise (twice layer H's a pixel) in a dark corner: found as calibrators do, smoothed
            ok, corners = cv2.findChessboardCorners(cv2.GaussianBlur(luma, (3, 3), 0), PATTERN, flags=flags)
        assert ok, f"view {index} (aim {aim}): no chessboard found"
        corners = cv2.cornerSubPix(
            luma, corners, (window, window), (-1, -1), (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 100, 1e-4)
        ).reshape(-1, 2)
        world = frame.position + (OBJECT_POINTS @ turn.T + position) @ (frame.xmat @ _MUJOCO_TO_OPENCV).T
        projected, _ = sim.camera.project(world, frame)
        if np.linalg.norm(corners[0] - projected[0]) > np.linalg.norm(corners[-1] - projected[0]):
            corners = corners[::-1].copy()  # the board turned by 180 degrees looks the same: either order
        found.append(corners)
        expected.append(projected)
    points = [OBJECT_POINTS] * len(found)
    image_points = [c.reshape(-1, 1, 2) for c in found]
    size = (lens.width, lens.height)
    rms, matrix, distortion, _, _, std, _, per_view = cv2.calibrateCameraExtended(
        points, image_points, size, None, None
    )
    pinhole_rms = cv2.calibrateCamera(
        points,
        image_points,
        size,
        None,
        None,
        flags=cv2.CALIB_FIX_K1 | cv2.CALIB_FIX_K2 | cv2.CALIB_FIX_K3 | cv2.CALIB_ZERO_TANGENT_DIST,
    )[0]
    return {
        "lens": lens,
        "rms": rms,
        "matrix": matrix,
        "distortion": distortion.ravel()[:5],
        "std": std.ravel()[:4],
        "per_view": per_view.ravel(),
        "pinhole_rms": pinhole_rms,
        "found": np.concatenate(found),
        "expected": np.concatenate(expected),
    }


def mapping_error(lens: Lens, matrix: np.ndarray, distortion, turned: bool = False) -> tuple[np.ndarray, float]:
    """How far (px, over a grid covering the whole image, edges included) another camera (OpenCV
    ``matrix``, ``distortion``) puts the rays that ``lens`` puts at each grid point; with
    ``turned``, after turning that camera by the rotation that fits best (Gauss-Newton on
    projectPoints' Jacobian). Also the turn, degrees."""
    u, v = np.meshgrid(np.linspace(-0.5, lens.width - 0.5, 105), np.linspace(-0.5, lens.height - 0.5, 81))
    pixels = np.stack([u.ravel(), v.ravel()], axis=-1)
    rays = np.hstack([lens.undistort(pixels), np.ones((len(pixels), 1))])
    distortion = np.asarray(distortion, float)
    turn = np.zeros(3)
    for _ in range(10 if turned else 1):
        other, jacobian = cv2.projectPoints(rays, turn, np.zeros(3), matrix, distortion)
        residual = (other.reshape(-1, 2) - pixels).ravel()
        if turned:
            turn -= np.linalg.lstsq(jacobian[:, :3], residual, rcond=None)[0]
    other, _ = cv2.projectPoints(rays, turn, np.zeros(3), matrix, distortion)
    return np.linalg.norm(other.reshape(-1, 2) - pixels, axis=1), math.degrees(np.linalg.norm(turn))


def displacement_error(lens: Lens, matrix: np.ndarray, distortion) -> np.ndarray:
    """The distortion alone: how far (px) the two displacement fields (each camera's distorted
    minus undistorted projection of the same normalised points, each with its own matrix) differ."""
    u, v = np.meshgrid(np.linspace(-0.5, lens.width - 0.5, 105), np.linspace(-0.5, lens.height - 0.5, 81))
    rays = np.hstack([lens.undistort(np.stack([u.ravel(), v.ravel()], axis=-1)), np.ones((u.size, 1))])

    def field(k, d):
        def project(dist):
            return cv2.projectPoints(rays, np.zeros(3), np.zeros(3), k, dist)[0].reshape(-1, 2)

        return project(np.asarray(d, float)) - project(np.zeros(5))

    return np.linalg.norm(field(matrix, distortion) - field(lens.camera_matrix(), lens.distortion), axis=1)


def report(name: str, result: dict, started: float) -> str:
    lens, matrix, k = result["lens"], result["matrix"], result["distortion"]
    offsets = result["found"] - result["expected"]
    strict, _ = mapping_error(lens, matrix, k)
    turned, degrees = mapping_error(lens, matrix, k, turned=True)
    return (
        f"\n{name} {lens.width}x{lens.height}, {len(result['per_view'])} views: rms {result['rms']:.3f} px"
        f" (worst view {result['per_view'].max():.3f}; pinhole model {result['pinhole_rms']:.3f});"
        f" fx {matrix[0, 0]:.3f} / {lens.fx:.3f}, fy {matrix[1, 1]:.3f} / {lens.fy:.3f},"
        f" cx {matrix[0, 2]:.3f} / {lens.cx:.3f}, cy {matrix[1, 2]:.3f} / {lens.cy:.3f}"
        f" (std {np.round(result['std'], 3).tolist()});"
        f" distortion {np.round(k, 5).tolist()} / {list(lens.distortion)};"
        f" mapping max {strict.max():.3f} px, mean {strict.mean():.3f}; turned by {degrees:.3f} deg: max"
        f" {turned.max():.3f}, mean {turned.mean():.3f}; displacement fields max"
        f" {displacement_error(lens, matrix, k).max():.3f}; corners - recorded projection: mean"
        f" {np.round(offsets.mean(0), 4).tolist()}, rms {np.sqrt((offsets**2).sum(1).mean()):.3f};"
        f" {time.perf_counter() - started:.2f} s"
    )


def assert_not_vacuous(result: dict) -> None:
    """The frames tell the distorted lens from a pinhole and from Sony's field of view."""
    lens, matrix, distortion = result["lens"], result["matrix"], result["distortion"]
    to_layer_h = LENSES["tekkotsu"].width / lens.width
    assert result["pinhole_rms"] > 2 * result["rms"]
    without_distortion, _ = mapping_error(lens, lens.camera_matrix(), np.zeros(5))
    assert without_distortion.max() * to_layer_h > 1.0
    sony, _ = mapping_error(LENSES["sony"].scaled(lens.width, lens.height), matrix, distortion)
    assert sony.max() * to_layer_h > 3.0


@pytest.mark.slow
@pytest.mark.parametrize("profile, full", [("ideal", True), ("ers7", True), ("ers7", False)])
def test_opencv_calibration_recovers_the_recorded_lens(tmp_path, profile, full):
    """``ideal`` with the tekkotsu lens (no sensor effects), and the full ``ers7`` (noise,
    vignetting, softness; each shot a new exposure), at 416 x 320 and at layer H's 208 x 160."""
    started = time.perf_counter()
    camera = PROFILES["ideal"].with_options(lens="tekkotsu") if profile == "ideal" else PROFILES["ers7"]
    sim = Simulation(board_scene(tmp_path), camera=CameraConfig(camera, full=full))
    try:
        result = shoot_and_calibrate(sim, new_frame_each_shot=profile == "ers7")
    finally:
        sim.close()
    print(report(profile, result, started))
    lens, matrix, distortion = result["lens"], result["matrix"], result["distortion"]
    assert lens == LENSES["tekkotsu"].scaled(416, 320) if full else LENSES["tekkotsu"]
    half_layer_h_pixel = 0.5 * lens.width / LENSES["tekkotsu"].width  # in this image's pixels

    # The corners are where the recorded lens projects the board's corners.
    offsets = result["found"] - result["expected"]
    assert np.all(np.abs(offsets.mean(axis=0)) < 0.02) and np.sqrt((offsets**2).sum(1).mean()) < 0.15

    # OpenCV's calibration: every view fits, and the intrinsics are the recorded ones.
    assert result["rms"] < 0.15 and result["per_view"].max() < 0.2
    assert matrix[0, 0] == pytest.approx(lens.fx, rel=0.005) and matrix[1, 1] == pytest.approx(lens.fy, rel=0.005)
    assert abs(matrix[0, 2] - lens.cx) < half_layer_h_pixel and abs(matrix[1, 2] - lens.cy) < half_layer_h_pixel

    # Intrinsics and distortion together put every ray within half a layer-H pixel of where the
    # recorded lens puts it, over the whole image (compared as a mapping: k1, k2 and k3 trade off);
    # at layer H itself the sensor's noise moves the fit by more at the far corners: 0.44-0.55 px
    # over seeds 0-4, whichever noise draws (so 0.6 there).
    error, _ = mapping_error(lens, matrix, distortion)
    assert error.max() < (0.6 / 0.5 if profile == "ers7" and not full else 1.0) * half_layer_h_pixel
    assert_not_vacuous(result)
