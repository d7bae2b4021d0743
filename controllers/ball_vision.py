"""Finding the orange ball in a camera image (RGB, 3 bytes a pixel), shared by the examples."""

import math

import numpy as np


def find_ball(image, width, height):
    """(x, y, pixel count) of the orange pixels' centroid, or None when fewer than 4 are seen."""
    rgb = np.asarray(image, dtype=np.int16).reshape(height, width, 3)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    mask = (r > 110) & (r > 3 * g // 2 + 10) & (g > 3 * b // 2)
    ys, xs = np.nonzero(mask)
    if len(xs) < 4:
        return None
    return float(xs.mean()), float(ys.mean()), len(xs)


def pixel_angles(x, y, width, height, fov):
    """Angles (rad) of a pixel from the optical axis: (to the left, upwards)."""
    focal = (width / 2) / math.tan(fov / 2)
    return math.atan((width / 2 - x - 0.5) / focal), math.atan((height / 2 - y - 0.5) / focal)
