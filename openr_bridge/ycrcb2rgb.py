"""Sony's YCrCb2RGB compiled (``colour.ycrcb_to_rgb`` documents the formula and its checks)."""

import numba
import numpy as np


@numba.njit(cache=True, nogil=True, boundscheck=False)
def ycrcb2rgb(ycrcb, rgb):
    """YCrCb2RGB of packed Y, Cr, Cb bytes into packed R, G, B bytes, as the C source computes it."""
    for i in range(ycrcb.shape[0] // 3):  # a stepped range or offsets i + 1 would not vectorise
        y = ycrcb[3 * i] / 255.0
        cr = (np.int32(ycrcb[3 * i + 1]) - 128) / 128.0
        cb = (np.int32(ycrcb[3 * i + 2]) - 128) / 128.0
        rgb[3 * i] = np.uint8(min(max(255.0 * (y + cr), 0.0), 255.0))
        rgb[3 * i + 1] = np.uint8(min(max(255.0 * (y - 0.51 * cr - 0.19 * cb), 0.0), 255.0))
        rgb[3 * i + 2] = np.uint8(min(max(255.0 * (y + cb), 0.0), 255.0))
