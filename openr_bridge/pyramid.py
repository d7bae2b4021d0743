"""The encoder's per-level loops, compiled with numba (``encoder`` imports this module on first
use, so that importing ``openr_bridge`` does not load numba).

A layer is an (h, 6, w) uint8 array: each row's Y, Cr, Cb, Y_LH, Y_HL, Y_HH runs, as the message
lays them out. Its Y bands come from the luma of twice its size, p(2x + X, 2y + Y) = pXY:
Y_LL = (p00 + p10 + p01 + p11 + 2) >> 2, Y_LH = 128 + ((p01 + p11 - p00 - p10 + 2) >> 2),
Y_HL = 128 + ((p10 + p11 - p00 - p01 + 2) >> 2), Y_HH = 128 + ((p00 + p11 - p10 - p01 + 2) >> 2),
clipped to 0..255; its Cr and Cb, when asked for, are the 2x2 means, (sum + 2) >> 2. Integer
arithmetic; C-contiguous arrays, whose strides the compiler knows.
"""

import numba
import numpy as np

_compiled = numba.njit(cache=True, nogil=True, boundscheck=False)


@_compiled
def _y_bands(layer, y, x, p00, p10, p01, p11):
    layer[y, 0, x] = (p00 + p10 + p01 + p11 + 2) >> 2
    layer[y, 3, x] = min(255, 128 + ((p01 + p11 - p00 - p10 + 2) >> 2))
    layer[y, 4, x] = min(255, 128 + ((p10 + p11 - p00 - p01 + 2) >> 2))
    layer[y, 5, x] = min(255, 128 + ((p00 + p11 - p10 - p01 + 2) >> 2))


@_compiled
def from_pixels(pixels, layer, chroma):
    """Fill ``layer``'s Y bands from channel 0 of the (2h, 2w, channels) uint8 ``pixels`` and,
    when ``chroma``, its Cr and Cb from channels 1 and 2."""
    height, _, width = layer.shape
    for y in range(height):
        for x in range(width):
            top, bottom = pixels[2 * y], pixels[2 * y + 1]
            _y_bands(
                layer,
                y,
                x,
                np.int32(top[2 * x, 0]),
                np.int32(top[2 * x + 1, 0]),
                np.int32(bottom[2 * x, 0]),
                np.int32(bottom[2 * x + 1, 0]),
            )
            if chroma:
                for c in (1, 2):
                    total = (
                        np.int32(top[2 * x, c])
                        + np.int32(top[2 * x + 1, c])
                        + np.int32(bottom[2 * x, c])
                        + np.int32(bottom[2 * x + 1, c])
                    )
                    layer[y, c, x] = (total + 2) >> 2


@_compiled
def next_level(src, dst):
    """Fill the layer ``dst`` from the layer ``src`` of twice its size."""
    height, _, width = dst.shape
    for y in range(height):
        for x in range(width):
            _y_bands(
                dst,
                y,
                x,
                np.int32(src[2 * y, 0, 2 * x]),
                np.int32(src[2 * y, 0, 2 * x + 1]),
                np.int32(src[2 * y + 1, 0, 2 * x]),
                np.int32(src[2 * y + 1, 0, 2 * x + 1]),
            )
            for c in (1, 2):
                total = (
                    np.int32(src[2 * y, c, 2 * x])
                    + np.int32(src[2 * y, c, 2 * x + 1])
                    + np.int32(src[2 * y + 1, c, 2 * x])
                    + np.int32(src[2 * y + 1, c, 2 * x + 1])
                )
                dst[y, c, x] = (total + 2) >> 2
