"""The head camera's lens: intrinsics, radial-tangential distortion, projection and the
remap that turns a wider pinhole render into the distorted picture.

Coordinates follow OpenCV (and Bouguet's toolbox, which Tekkotsu's calibration used): pixel
centres at integers, (0, 0) the centre of the top-left pixel, x right, y down, z forward;
distortion on normalised coordinates (x, y) = (X / Z, Y / Z) with r^2 = x^2 + y^2:

    x_d = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2)
    y_d = y (1 + k1 r^2 + k2 r^4 + k3 r^6) + p1 (r^2 + 2 y^2) + 2 p2 x y
    u = fx x_d + cx,  v = fy y_d + cy

Lenses (``LENSES``), all at layer H's 208 x 160 and scaled for 416 x 320:
- ``tekkotsu`` (the ``ers7`` profile's default): Tekkotsu's Bouguet calibration of a real
  ERS-7 (fx 198.807, fy 200.333, principal point 102.689, 85.0399, k1 -0.147005, k2 0.38485,
  p1 -0.00347777, p2 0.00012873): the only measured lens of the robot. Its focal lengths
  alone give 55.2 x 43.5 deg, 3 % narrower than Sony's 56.9 x 45.2 deg (a nominal figure);
  with its distortion the picture spans 55.75 x 44.03 deg between the outer pixel edges
  (``Lens.field_of_view_deg``).
- ``sony``: Sony's field of view in the focal lengths (fx 191.9, fy 192.2, centred) with
  Tekkotsu's distortion, which widens the picture to 57.36 x 45.78 deg edge to edge.
- ``pinhole``: Sony's field of view without distortion, the ``ideal`` profile's lens (what
  the model's camera renders directly): 56.9 x 45.2 deg.

``camera_get_fov()`` answers Sony's 56.9 deg (0.993092 rad) with every lens, as the OPEN-R
wrapper does on the robot: it is the wrapper's constant, not a measurement.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from openr_bridge import HORIZONTAL_FOV_DEG, LAYER_SIZE, VERTICAL_FOV_DEG

LAYER_WIDTH, LAYER_HEIGHT = LAYER_SIZE[0]


@dataclass(frozen=True)
class Lens:
    """Pinhole intrinsics and OpenCV distortion (k1, k2, p1, p2, k3) at ``width`` x ``height``."""

    name: str
    fx: float
    fy: float
    cx: float
    cy: float
    distortion: tuple[float, float, float, float, float] = (0.0, 0.0, 0.0, 0.0, 0.0)
    width: int = LAYER_WIDTH
    height: int = LAYER_HEIGHT

    @property
    def distorted(self) -> bool:
        """Whether any distortion coefficient is non-zero."""
        return any(self.distortion)

    def scaled(self, width: int, height: int) -> Lens:
        """The same lens on an image of another size (pixel edges, not centres, scale)."""
        sx, sy = width / self.width, height / self.height
        return replace(
            self,
            fx=self.fx * sx,
            fy=self.fy * sy,
            cx=(self.cx + 0.5) * sx - 0.5,
            cy=(self.cy + 0.5) * sy - 0.5,
            width=width,
            height=height,
        )

    def camera_matrix(self) -> np.ndarray:
        """The 3x3 pinhole camera matrix (OpenCV's K)."""
        return np.array([[self.fx, 0, self.cx], [0, self.fy, self.cy], [0, 0, 1.0]])

    def field_of_view_deg(self) -> tuple[float, float]:
        """Angles between the outer pixel edges through the principal point's row and column."""
        left, right = self.undistort([[-0.5, self.cy], [self.width - 0.5, self.cy]])[:, 0]
        top, bottom = self.undistort([[self.cx, -0.5], [self.cx, self.height - 0.5]])[:, 1]
        return (math.degrees(math.atan(right) - math.atan(left)), math.degrees(math.atan(bottom) - math.atan(top)))

    def distort(self, normalised) -> np.ndarray:
        """Pixels (n, 2) of ideal normalised coordinates (n, 2)."""
        x, y = np.asarray(normalised, dtype=np.float64).reshape(-1, 2).T
        return np.stack(self._pixel(x, y), axis=-1)

    def _pixel(self, x, y):
        """(u, v) of ideal normalised (x, y): arrays, or Python floats (one point costs ~1 us
        that way, ~40 us through arrays)."""
        k1, k2, p1, p2, k3 = self.distortion
        r2 = x * x + y * y
        radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
        xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
        yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
        return self.fx * xd + self.cx, self.fy * yd + self.cy

    def undistort(self, pixels, iterations: int = 100) -> np.ndarray:
        """Ideal normalised coordinates (n, 2) of pixels (n, 2): the fixed-point iteration of
        OpenCV's ``undistortPoints``, run until it settles (to ~1e-12 on this lens's image)."""
        points = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
        xd, yd = (points[:, 0] - self.cx) / self.fx, (points[:, 1] - self.cy) / self.fy
        if not self.distorted:
            return np.stack([xd, yd], axis=-1)
        k1, k2, p1, p2, k3 = self.distortion
        x, y = xd.copy(), yd.copy()
        for _ in range(iterations):
            r2 = x * x + y * y
            radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
            x_new = (xd - 2 * p1 * x * y - p2 * (r2 + 2 * x * x)) / radial
            y_new = (yd - p1 * (r2 + 2 * y * y) - 2 * p2 * x * y) / radial
            settled = max(np.abs(x_new - x).max(initial=0), np.abs(y_new - y).max(initial=0)) < 1e-13
            x, y = x_new, y_new
            if settled:
                break
        return np.stack([x, y], axis=-1)

    def project(self, points_camera) -> tuple[np.ndarray, np.ndarray]:
        """Pixels (n, 2) and depths (n,) of points (n, 3) in the camera frame (x right, y
        down, z forward); pixels of points behind the camera are NaN."""
        points = np.asarray(points_camera, dtype=np.float64).reshape(-1, 3)
        depth = points[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            normalised = points[:, :2] / depth[:, np.newaxis]
        pixels = self.distort(normalised)
        pixels[depth <= 0] = np.nan
        return pixels, depth

    def project_point(self, x: float, y: float, z: float) -> tuple[float, float] | None:
        """``project`` of one point in the camera frame, in Python floats: its pixel (u, v), or
        None behind the camera."""
        return self._pixel(x / z, y / z) if z > 0 else None

    def render_pinhole(self, margin: float = 1.5) -> PinholeRender:
        """The square-pixel pinhole render that covers every pixel of this lens's image with
        ``margin`` pixels to spare on each side, at the lens's own pixel density (fx): no wider
        than that, its principal point off-centre as the lens's is. Its principal point sits a
        whole number of pixels from the lens's, so that around the image centre the remap
        samples the render at its pixel centres: with a fractional offset there, the bilinear
        remap of the (aliased) render moves edges by a few hundredths of a pixel, the same way
        all over the centre, and OpenCV's calibration of the frames reads that as a principal
        point ~0.7 px away."""
        u, v = np.meshgrid(np.arange(-0.5, self.width, 0.5), np.arange(-0.5, self.height, 0.5))
        border = (u == -0.5) | (v == -0.5) | (u >= self.width - 0.5) | (v >= self.height - 0.5)
        ideal = self.undistort(np.stack([u[border], v[border]], axis=-1))
        focal, lowest, highest = self.fx, ideal.min(axis=0), ideal.max(axis=0)
        # Render pixel i spans i - 0.5 .. i + 0.5: the principal point far enough from the first
        # pixel's outer edge for the left (top) extent, the size reaching past the right (bottom).
        centre = tuple(c + math.ceil(margin - 0.5 - focal * low - c) for c, low in zip((self.cx, self.cy), lowest))
        width, height = (math.ceil(c + focal * high + margin + 0.5) for c, high in zip(centre, highest))
        return PinholeRender(width, height, focal, centre)

    def render_maps(self, render: PinholeRender) -> tuple[np.ndarray, np.ndarray]:
        """Where each pixel of this lens's image lies in the pinhole ``render``: x and y,
        float64 (height, width)."""
        u, v = np.meshgrid(np.arange(self.width, dtype=np.float64), np.arange(self.height, dtype=np.float64))
        ideal = self.undistort(np.stack([u.ravel(), v.ravel()], axis=-1))
        return (
            (ideal[:, 0] * render.focal + render.centre[0]).reshape(self.height, self.width),
            (ideal[:, 1] * render.focal + render.centre[1]).reshape(self.height, self.width),
        )


@dataclass(frozen=True)
class PinholeRender:
    """A pinhole render's size, focal length (px) and principal point (px, pixel centres at
    integers, as OpenCV)."""

    width: int
    height: int
    focal: float
    centre: tuple[float, float]


def _sony_focal(size: int, fov_deg: float) -> float:
    return size / 2 / math.tan(math.radians(fov_deg) / 2)


TEKKOTSU_DISTORTION = (-0.147005, 0.38485, -0.00347777, 0.00012873, 0.0)
LENSES = {
    "tekkotsu": Lens("tekkotsu", 198.807, 200.333, 102.689, 85.0399, TEKKOTSU_DISTORTION),
    "sony": Lens(
        "sony",
        _sony_focal(LAYER_WIDTH, HORIZONTAL_FOV_DEG),
        _sony_focal(LAYER_HEIGHT, VERTICAL_FOV_DEG),
        (LAYER_WIDTH - 1) / 2,
        (LAYER_HEIGHT - 1) / 2,
        TEKKOTSU_DISTORTION,
    ),
    "pinhole": Lens(
        "pinhole",
        _sony_focal(LAYER_WIDTH, HORIZONTAL_FOV_DEG),
        _sony_focal(LAYER_HEIGHT, VERTICAL_FOV_DEG),
        (LAYER_WIDTH - 1) / 2,
        (LAYER_HEIGHT - 1) / 2,
    ),
}


@dataclass(frozen=True)
class Warp:
    """A remap (output pixel (u, v) reads the render at ``map_x``, ``map_y``) as Catmull and
    Smith's two 1-D passes: pass 1 resamples each render column x at the row where the map's
    row v crosses x (``rows_*``: (h, render width)), pass 2 resamples each output row along x
    (``columns_*``: (h, w)). A pass stores, per sample, the fraction past the first of its
    source pixels (``*_frac``); ``*_runs`` (row pointers, then (start, end, offset) triples)
    split each row into runs where the source is the destination shifted by one constant
    offset (pass 1: the source row; pass 2: the source column less the destination column),
    so that every run is a contiguous slice. The lens's mild barrel keeps both passes
    single-valued and smooth (a few runs per row). The fractions carry ``slack`` zero columns
    past each row's end (what ``kernels`` reads past a run)."""

    rows_frac: np.ndarray
    rows_runs: tuple[np.ndarray, np.ndarray]
    columns_frac: np.ndarray
    columns_runs: tuple[np.ndarray, np.ndarray]

    @classmethod
    def from_maps(cls, map_x: np.ndarray, map_y: np.ndarray, render_width: int, slack: int = 0) -> Warp:
        """The two passes of the remap ``map_x``, ``map_y`` (each (h, w)) of a render ``render_width``
        pixels wide, with ``slack`` zero columns past each row of fractions.

        :raises ValueError: ``map_x`` decreases along a row.
        """
        height, width = map_x.shape
        if np.any(np.diff(map_x, axis=1) < 0):
            raise ValueError("a two-pass warp needs a map that never decreases along a row")
        columns = np.arange(render_width, dtype=np.float64)
        row_at_column = np.stack([np.interp(columns, map_x[v], map_y[v]) for v in range(height)])
        rows_base = np.floor(row_at_column).astype(np.int64)
        columns_base = np.floor(map_x).astype(np.int64)
        rows_frac, columns_frac = (
            np.pad((position - base).astype(np.float32), ((0, 0), (0, slack)))
            for position, base in ((row_at_column, rows_base), (map_x, columns_base))
        )
        return cls(rows_frac, _runs(rows_base), columns_frac, _runs(columns_base - np.arange(width)))


def _runs(key: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Row pointers and (start, end, key) of the runs of each row of ``key`` where it stays the
    same: pass 1's source row, pass 2's source column less the destination column."""
    rows, width = key.shape
    starts_run = np.ones(key.shape, bool)
    starts_run[:, 1:] = key[:, 1:] != key[:, :-1]
    row, start = np.divmod(np.flatnonzero(starts_run), width)
    pointers = np.concatenate([[0], np.cumsum(np.bincount(row, minlength=rows))])
    end = np.append(start[1:], width)
    end[pointers[1:] - 1] = width  # each row's last run ends at the row's end
    return pointers.astype(np.int64), np.stack([start, end, key[row, start]], axis=1).astype(np.int64)
