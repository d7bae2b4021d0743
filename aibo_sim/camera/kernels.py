"""The ``ers7`` sensor's per-frame passes over the picture, compiled with numba.

A frame goes through four passes (``Sensor.expose`` calls them in this order), each a loop
over contiguous row slices that LLVM vectorises, on planes (channel, row, column):

1. ``smear``: motion blur on the pinhole render, the sum of shifted copies of each row
   (integer taps, weights in 1/256, uint16 sums: twice the SIMD lanes of float32);
2. ``warp_rows`` and ``warp_columns``: the lens remap as two 1-D passes (``lens.Warp``),
   each a linear interpolation convolved with the 3-tap Gaussian of the lens's softness;
3. the response table (OpenCV's ``LUT``, a gather numba's compiler does not vectorise);
4. ``colour``: the YCrCb matrix, vignetting and robot colour, noise, Y's floor, rounding.

Numbers stay in IEEE float32 without fast-math reassociation: the same input gives the same
bytes on a machine, whatever the vector width. Compiled on first use and cached beside the
module (numba's cache); ``Sensor`` imports this module, so that importing ``aibo_sim`` does
not load numba.
"""

from __future__ import annotations

import numba
import numpy as np

_compiled = numba.njit(cache=True, nogil=True, boundscheck=False)


@_compiled
def smear(planes, pad, dx, dy, weights, out):
    """``out[c, y, x]`` = sum over taps t of ``weights[t] * planes[c, y + dy[t], pad + x + dx[t]]``,
    rows clamped at the edges (columns come padded by ``pad``, edges repeated); uint8 planes,
    weights in 1/256 summing to 256, uint16 sums."""
    channels, height, width = out.shape
    for c in range(channels):
        for y in range(height):
            row_out = out[c, y]
            row_out[:] = 0
            for t in range(dx.shape[0]):
                source = planes[c, min(max(y + dy[t], 0), height - 1)]
                shifted = source[pad + dx[t]:pad + dx[t] + width]
                weight = weights[t]
                for x in range(width):
                    row_out[x] += weight * np.uint16(shifted[x])


@_compiled
def warp_rows(planes, base, frac, pointers, runs, outer, centre, out):
    """Pass 1: ``out[c, v, 2 + x]`` = the column x of ``planes`` at row ``base[v, x] + frac[v, x]``,
    interpolated linearly and convolved with the taps (``outer``, ``centre``, ``outer``) along the
    column (rows clamped at the edges); two columns each side repeat the edge."""
    channels, height, width = planes.shape[0], planes.shape[1], out.shape[2] - 4
    for v in range(base.shape[0]):
        for k in range(pointers[v], pointers[v + 1]):
            start, end = runs[k, 0], runs[k, 1]
            first = base[v, start]
            r0, r1 = min(max(first - 1, 0), height - 1), min(max(first, 0), height - 1)
            r2, r3 = min(max(first + 1, 0), height - 1), min(max(first + 2, 0), height - 1)
            f = frac[v, start:end]
            for c in range(channels):
                a0, a1 = planes[c, r0, start:end], planes[c, r1, start:end]
                a2, a3 = planes[c, r2, start:end], planes[c, r3, start:end]
                o = out[c, v, start + 2:end + 2]
                for i in range(end - start):
                    p = f[i]
                    q = np.float32(1.0) - p
                    o[i] = (outer * (q * np.float32(a0[i]) + p * np.float32(a3[i]))
                            + (centre * q + outer * p) * np.float32(a1[i]) + (outer * q + centre * p) * np.float32(a2[i]))
        for c in range(channels):
            out[c, v, 0] = out[c, v, 1] = out[c, v, 2]
            out[c, v, width + 2] = out[c, v, width + 3] = out[c, v, width + 1]


@_compiled
def warp_columns(rows, base, frac, pointers, runs, outer, centre, out):
    """Pass 2: ``out[c, v, u]`` = row v of pass 1's output at column ``base[v, u] + frac[v, u]``,
    interpolated and convolved as in pass 1, rounded to bytes."""
    for v in range(base.shape[0]):
        for k in range(pointers[v], pointers[v + 1]):
            start, end = runs[k, 0], runs[k, 1]
            shift = base[v, start] - start + 1  # tap -1 of column ``start``, in pass 1's padded columns
            f = frac[v, start:end]
            for c in range(out.shape[0]):
                row = rows[c, v]
                a0, a1 = row[start + shift:end + shift], row[start + shift + 1:end + shift + 1]
                a2, a3 = row[start + shift + 2:end + shift + 2], row[start + shift + 3:end + shift + 3]
                o = out[c, v, start:end]
                for i in range(end - start):
                    p = f[i]
                    q = np.float32(1.0) - p
                    o[i] = np.uint8(outer * (q * a0[i] + p * a3[i]) + (centre * q + outer * p) * a1[i]
                                    + (outer * q + centre * p) * a2[i] + np.float32(0.5))


@_compiled
def colour(red, green, blue, matrix, curve, slope, intercept, noise, start, black, out):
    """Y, Cr, Cb planes (uint8, ``out``) of the sensor's R, G, B (float32 planes, flattened):
    ``matrix`` (3, 4) to Y, Cr, Cb, then per pixel and channel ``curve v^2 + slope v +
    intercept`` (vignetting and robot colour, flattened planes), plus ``noise[c, start + i]``;
    Y floored at ``black``, all clipped to 0..255 and rounded half up."""
    n = red.shape[0]
    m = matrix
    noise_y, noise_cr, noise_cb = noise[0, start:start + n], noise[1, start:start + n], noise[2, start:start + n]
    for i in range(n):
        r, g, b = red[i], green[i], blue[i]
        y = m[0, 0] * r + m[0, 1] * g + m[0, 2] * b + m[0, 3]
        cr = m[1, 0] * r + m[1, 1] * g + m[1, 2] * b + m[1, 3]
        cb = m[2, 0] * r + m[2, 1] * g + m[2, 2] * b + m[2, 3]
        y = (curve[0, i] * y + slope[0, i]) * y + intercept[0, i] + noise_y[i]
        cr = (curve[1, i] * cr + slope[1, i]) * cr + intercept[1, i] + noise_cr[i]
        cb = (curve[2, i] * cb + slope[2, i]) * cb + intercept[2, i] + noise_cb[i]
        out[0, i] = np.uint8(min(max(y, black), np.float32(255.0)) + np.float32(0.5))
        out[1, i] = np.uint8(min(max(cr, np.float32(0.0)), np.float32(255.0)) + np.float32(0.5))
        out[2, i] = np.uint8(min(max(cb, np.float32(0.0)), np.float32(255.0)) + np.float32(0.5))
