"""The ``ers7`` sensor's per-frame passes over the picture, compiled with numba.

A frame goes through these passes (``Sensor.expose`` calls them in this order), each a loop
over contiguous row slices that LLVM vectorises (interleaved channels are indexed 3 x + c,
which LLVM reads and writes with shuffles):

1. ``split``: the render's RGBA pixels into R, G, B planes, padded for the smear;
2. ``smear``: motion blur on the pinhole render, the sum of shifted copies of each row
   (``motion_taps``: integer taps, weights in 1/256, uint16 sums: twice the SIMD lanes of
   float32);
3. ``develop``, row by row: the lens remap as two 1-D passes (``lens.Warp``), each a linear
   interpolation convolved with the 3-tap Gaussian of the lens's softness, into a row
   buffer; then the response (a gain per channel, clipped), the YCrCb matrix,
   vignetting and robot colour, noise, Y's floor and rounding, into the interleaved Y, Cr,
   Cb picture. One pass over the frame: the passes' intermediate rows stay in the cache.

Runs of columns are computed in whole vectors (``VECTOR`` columns: AVX-512's float32 lanes)
rather than finishing each with a scalar remainder loop: a run spills its last vector into the
next run's columns, which that run then writes again, and the last run into ``SLACK`` spare
columns that the planes, row buffers and fractions carry past each row's end (a lens row has
3-5 runs in each pass: their remainders cost develop ~12 % of its time; the smear's rows, ~20 %).

Numbers stay in IEEE float32 without fast-math reassociation: the same input gives the same
bytes on a machine, whatever the vector width. Compiled on first use and cached beside the
module (numba's cache); ``Sensor`` imports this module, so that importing ``aibo_sim`` does
not load numba.
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import compiled

_compiled = compiled(nogil=True, boundscheck=False)
VECTOR = 16  # columns a pass computes at a time
SLACK = VECTOR  # spare columns past each row's end


@_compiled
def _in_vectors(count):
    """``count`` rounded up to whole vectors."""
    return (count + VECTOR - 1) // VECTOR * VECTOR


@_compiled
def motion_taps(du, dv):
    """(dx, dy, weights) of the integer shifts whose weighted sum averages a picture along the
    image motion (du, dv) px over the exposure: what each pixel saw during the exposure lies at
    +t (du, dv), t in 0..1. One tap per pixel along the longer axis (each unit segment's length
    shared by the pixels at its ends, so that its centroid stays put), the other axis rounded
    to the nearest pixel; weights sum to 1, taps of weight 0 left out."""
    horizontal = abs(du) >= abs(dv)
    along, across = (du, dv) if horizontal else (dv, du)
    length = abs(along)
    slope = across / along if along != 0 else 0.0
    count = int(math.ceil(length)) + 1
    weights = np.zeros(count)
    weights[0] = 1.0 if length == 0 else 0.0
    for k in range(count - 1):
        covered = min(k + 1.0, length) - k  # the line's length in the unit segment [k, k + 1]
        weights[k] += covered * (1 - covered / 2)
        weights[k + 1] += covered * covered / 2
    kept = np.flatnonzero(weights > 0)
    major = np.copysign(kept.astype(np.float64), along).astype(np.int64)
    minor = np.round(major * slope).astype(np.int64)
    if horizontal:
        return major, minor, weights[kept] / weights.sum()
    return minor, major, weights[kept] / weights.sum()


@_compiled
def smear_taps(du, dv):
    """``motion_taps`` with the weights in 1/256 (uint16, summing to exactly 256: the largest
    takes the rounding's remainder) and the taps' reach, the largest |dx|."""
    dx, dy, weights = motion_taps(du, dv)
    fixed = np.round(256 * weights).astype(np.int64)
    fixed[np.argmax(fixed)] += 256 - fixed.sum()
    return dx, dy, fixed.astype(np.uint16), np.abs(dx).max()


@_compiled
def split(image, pad, out):
    """``out[c, y, pad + x]`` = ``image[y, x, c]`` for R, G, B of the render's (h, w, 4) RGBA
    pixels (alpha unread): the picture's channels as planes, the ``pad`` columns each side (and
    the ``SLACK`` past them) repeating the edge."""
    height, width, _ = image.shape
    flat = image.reshape(height, 4 * width)
    for y in range(height):
        row = flat[y]
        red, green, blue = out[0, y, pad : pad + width], out[1, y, pad : pad + width], out[2, y, pad : pad + width]
        for x in range(width):
            red[x], green[x], blue[x] = row[4 * x], row[4 * x + 1], row[4 * x + 2]
        for c in range(3):
            out[c, y, :pad] = row[c]
            out[c, y, pad + width :] = row[4 * width - 4 + c]


@_compiled
def smear(planes, pad, dx, dy, weights, out):
    """``out[c, y, x]`` = sum over taps t of ``weights[t] * planes[c, y + dy[t], pad + x + dx[t]]``,
    rows clamped at the edges (columns come padded by ``pad``, edges repeated); uint8 planes,
    weights in 1/256 summing to 256, uint16 sums, taken four taps at a time. Both carry
    ``SLACK`` columns past the padding (``out``'s are left with any values)."""
    channels, height, width = out.shape
    span = _in_vectors(width - SLACK)
    taps = dx.shape[0]
    for c in range(channels):
        for y in range(height):
            row_out = out[c, y]
            row_out[:span] = 0
            for first in range(0, taps, 4):
                t0, t1, t2, t3 = first, min(first + 1, taps - 1), min(first + 2, taps - 1), min(first + 3, taps - 1)
                s0 = planes[c, min(max(y + dy[t0], 0), height - 1), pad + dx[t0] : pad + dx[t0] + span]
                s1 = planes[c, min(max(y + dy[t1], 0), height - 1), pad + dx[t1] : pad + dx[t1] + span]
                s2 = planes[c, min(max(y + dy[t2], 0), height - 1), pad + dx[t2] : pad + dx[t2] + span]
                s3 = planes[c, min(max(y + dy[t3], 0), height - 1), pad + dx[t3] : pad + dx[t3] + span]
                # past the last tap, the last again with weight 0
                w0, w1 = weights[t0], weights[t1] if first + 1 < taps else np.uint16(0)
                w2, w3 = (
                    weights[t2] if first + 2 < taps else np.uint16(0),
                    weights[t3] if first + 3 < taps else np.uint16(0),
                )
                for x in range(span):
                    row_out[x] += (
                        w0 * np.uint16(s0[x]) + w1 * np.uint16(s1[x]) + w2 * np.uint16(s2[x]) + w3 * np.uint16(s3[x])
                    )


@_compiled
def develop(
    planes,
    rows_frac,
    rows_pointers,
    rows_runs,
    columns_frac,
    columns_pointers,
    columns_runs,
    level,
    outer,
    centre,
    response,
    matrix,
    curve,
    slope,
    intercept,
    coefficient_row,
    noise,
    noise_scale,
    noise_rows,
    y_floor,
    across,
    line,
    out,
):
    """The lens's two passes and the colour, row by row of the picture ``out`` (h, w, 3):

    1. ``across[c, 2 + x]`` = the column x of ``planes`` (3, h', w') at row ``k + rows_frac[v,
       x]``, k the source row of x's run in ``rows_runs``, interpolated linearly and convolved
       with the taps (``outer``, ``centre``, ``outer``) along the column (rows clamped at the
       edges), times ``level`` (what a unit of ``planes`` is worth: 1 for bytes, 1/256 for
       ``smear``'s sums), two columns each side repeating the edge;
    2. ``line[c, u]`` = ``across`` at column ``u + k + columns_frac[v, u]``, k the offset of u's
       run in ``columns_runs``, interpolated and convolved the same way;
    3. per pixel ``min(max(response[c] line, 0), 255)`` (R, G, B),
       ``matrix`` (3, 4) to Y, Cr, Cb, ``curve v^2 + slope v + intercept`` (vignetting and
       robot colour, planes (3, rows, w), image row v at ``coefficient_row[v]``; Cr's curve is
       not read: its table has two columns, so Cr's fit is a line), plus
       ``noise[c, noise_rows[v] + u] * noise_scale[c]``; Y floored at ``y_floor``, all clipped to
       0..255 and rounded half up.

    ``*_pointers`` and ``*_runs`` split each row into runs of one source offset (``lens.Warp``:
    (start, end, offset) triples).
    ``planes``, the fractions, ``across`` and ``line`` carry ``SLACK`` columns past each row."""
    height, width = out.shape[:2]
    source_width, last = across.shape[1] - 4 - SLACK, planes.shape[1] - 1
    flat = out.reshape(height, 3 * width)  # indexed 3 u + c: LLVM vectorises the interleaved stores
    m = matrix
    outer_level, centre_level = outer * level, centre * level
    for v in range(height):
        for k in range(rows_pointers[v], rows_pointers[v + 1]):
            first = rows_runs[k, 0]
            end = first + _in_vectors(rows_runs[k, 1] - first)
            top = rows_runs[k, 2]
            r0, r1 = min(max(top - 1, 0), last), min(max(top, 0), last)
            r2, r3 = min(max(top + 1, 0), last), min(max(top + 2, 0), last)
            f = rows_frac[v, first:end]
            for c in range(3):
                a0, a1 = planes[c, r0, first:end], planes[c, r1, first:end]
                a2, a3 = planes[c, r2, first:end], planes[c, r3, first:end]
                o = across[c, first + 2 : end + 2]
                for i in range(end - first):
                    p = f[i]
                    q = np.float32(1.0) - p
                    o[i] = (
                        outer_level * (q * np.float32(a0[i]) + p * np.float32(a3[i]))
                        + (centre_level * q + outer_level * p) * np.float32(a1[i])
                        + (outer_level * q + centre_level * p) * np.float32(a2[i])
                    )
        for c in range(3):
            across[c, 0] = across[c, 1] = across[c, 2]
            across[c, source_width + 2] = across[c, source_width + 3] = across[c, source_width + 1]
        for k in range(columns_pointers[v], columns_pointers[v + 1]):
            first = columns_runs[k, 0]
            end = first + _in_vectors(columns_runs[k, 1] - first)
            shift = columns_runs[k, 2] + 1  # tap -1 of column ``first``, in ``across``'s columns
            f = columns_frac[v, first:end]
            for c in range(3):
                row = across[c]
                a0, a1 = row[first + shift : end + shift], row[first + shift + 1 : end + shift + 1]
                a2, a3 = row[first + shift + 2 : end + shift + 2], row[first + shift + 3 : end + shift + 3]
                o = line[c, first:end]
                for i in range(end - first):
                    p = f[i]
                    q = np.float32(1.0) - p
                    o[i] = (
                        outer * (q * a0[i] + p * a3[i])
                        + (centre * q + outer * p) * a1[i]
                        + (outer * q + centre * p) * a2[i]
                    )
        at = noise_rows[v]
        noise_y, noise_cr, noise_cb = noise[0, at : at + width], noise[1, at : at + width], noise[2, at : at + width]
        row = coefficient_row[v]
        curve_y, curve_cb = curve[0, row], curve[2, row]
        slope_y, slope_cr, slope_cb = slope[0, row], slope[1, row], slope[2, row]
        intercept_y, intercept_cr, intercept_cb = intercept[0, row], intercept[1, row], intercept[2, row]
        red, green, blue, picture = line[0], line[1], line[2], flat[v]
        for u in range(width):
            r = min(max(response[0] * red[u], np.float32(0.0)), np.float32(255.0))
            g = min(max(response[1] * green[u], np.float32(0.0)), np.float32(255.0))
            b = min(max(response[2] * blue[u], np.float32(0.0)), np.float32(255.0))
            y = m[0, 0] * r + m[0, 1] * g + m[0, 2] * b + m[0, 3]
            cr = m[1, 0] * r + m[1, 1] * g + m[1, 2] * b + m[1, 3]
            cb = m[2, 0] * r + m[2, 1] * g + m[2, 2] * b + m[2, 3]
            y = (curve_y[u] * y + slope_y[u]) * y + intercept_y[u] + noise_scale[0] * np.float32(noise_y[u])
            cr = slope_cr[u] * cr + intercept_cr[u] + noise_scale[1] * np.float32(noise_cr[u])
            cb = (curve_cb[u] * cb + slope_cb[u]) * cb + intercept_cb[u] + noise_scale[2] * np.float32(noise_cb[u])
            picture[3 * u] = np.uint8(min(max(y, y_floor), np.float32(255.0)) + np.float32(0.5))
            picture[3 * u + 1] = np.uint8(min(max(cr, np.float32(0.0)), np.float32(255.0)) + np.float32(0.5))
            picture[3 * u + 2] = np.uint8(min(max(cb, np.float32(0.0)), np.float32(255.0)) + np.float32(0.5))
