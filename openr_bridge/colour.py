"""Colour conversions between RGB and the camera's YCrCb.

``ycrcb_to_rgb`` is the report's ``YCrCb2RGB`` (Sony's BMP sample): with Cr' = Cr - 128 and
Cb' = Cb - 128, in double precision,

    R = 255 (Y/255 + Cr'/128),  G = 255 (Y/255 - 0.51 Cr'/128 - 0.19 Cb'/128),
    B = 255 (Y/255 + Cb'/128),

each clamped to 0..255 and truncated to a byte. The C expression is compiled with numba,
operation by operation in float64 as the C source has it (no fused multiply-adds: numba
compiles without fast-math), into a loop that LLVM vectorises: ~20 us a 208x160 frame,
against ~25-55 us (hot or cold) for a gather from a 64 MiB table of all 2^24 answers. The
test suite checks every input against the compiled C.

``ycrcb_to_rgb_bt601`` is the JFIF / BT.601 full-range decoder that Tekkotsu and most
image libraries assume: R = Y + 1.402 Cr', G = Y - 0.344136 Cb' - 0.714136 Cr',
B = Y + 1.772 Cb', rounded to nearest. Sony's conversion has a chroma gain of 255/128 = 1.99
on R and B (against 1.402 and 1.772), green weights 1.016 and 0.379 (against 0.714 and
0.344), and truncates: on the same bytes its colours are stronger; over all 2^24 inputs
the two differ by up to 76 levels in R, 44 in G and 29 in B.

``rgb_to_ycrcb`` is the forward model consistent with Sony's conversion (spec section 7):
Y = 0.299 R + 0.587 G + 0.114 B, Cr = 128 + (128/255)(R - Y), Cb = 128 + (128/255)(B - Y),
with the unrounded Y, each rounded half up (floor(v + 1/2)). It is defined exactly, in
integers: Y = floor((299 R + 587 G + 114 B + 500) / 1000), Cr = 128 + floor((128 (701 R -
587 G - 114 B) + 127500) / 255000), Cb = 128 + floor((128 (886 B - 299 R - 587 G) + 127500) /
255000). No clip is needed: Cr stays in 38..218 and Cb in 15..241. Every RGB colour comes
back through ``ycrcb_to_rgb`` within -2..+1 per channel. For uint8 pixels the formula is
evaluated for all 2^24 colours once, on first use (about 0.4 s), into a 64 MiB table of
packed Y, Cr, Cb (``rgb_to_ycrcb_packed``; the test suite checks every entry against the
formula): a 208x160 rendered frame then costs about 40 us (a random-noise frame, whose
lookups miss the caches, about 250 us) against 200 us for the integer arithmetic with its
divisions. Sums of ``pixels`` RGB values (the model of their mean) keep the arithmetic.
"""

from functools import cache

import cv2
import numpy as np

from .errors import FrameError


def rgb_to_ycrcb(rgb, *, pixels: int = 1) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(Y, Cr, Cb) uint8 planes of an (..., 3) integer RGB array.

    With ``pixels`` > 1, each entry is the sum of that many RGB pixels and the model is
    applied to their mean.
    """
    rgb = np.asarray(rgb)
    if rgb.ndim == 0 or rgb.shape[-1] != 3 or not np.issubdtype(rgb.dtype, np.integer):
        raise FrameError(f"RGB array of shape {rgb.shape} and dtype {rgb.dtype}, expected integers (..., 3)")
    if pixels == 1 and rgb.dtype == np.uint8 and rgb.size:
        ycrcb = rgb_to_ycrcb_packed(rgb)
        return ycrcb[..., 0], ycrcb[..., 1], ycrcb[..., 2]
    planes = _forward_model(*(rgb[..., channel].astype(np.int32) for channel in range(3)), pixels)
    return tuple(plane.astype(np.uint8) for plane in planes)


def rgb_to_ycrcb_packed(rgb: np.ndarray) -> np.ndarray:
    """Y, Cr, Cb and a zero byte per pixel, (..., 4) uint8, of a non-empty (..., 3) uint8 RGB array."""
    rgba = cv2.cvtColor(rgb.reshape(1, -1, 3), cv2.COLOR_RGB2RGBA)
    # As int32, R | G << 8 | B << 16 | 255 << 24 is the table index minus 2^24, which np.take
    # counts from the table's end: the index itself.
    packed = np.take(_forward_table(), rgba.view(np.int32))
    return packed.view(np.uint8).reshape(rgb.shape[:-1] + (4,))


def _forward_model(r, g, b, pixels: int) -> tuple:
    """The integer forward model of int32 R, G, B sums of ``pixels`` pixels."""
    y = (299 * r + 587 * g + 114 * b + 500 * pixels) // (1000 * pixels)
    cr = 128 + (128 * (701 * r - 587 * g - 114 * b) + 127500 * pixels) // (255000 * pixels)
    cb = 128 + (128 * (886 * b - 299 * r - 587 * g) + 127500 * pixels) // (255000 * pixels)
    return y, cr, cb


@cache
def _forward_table() -> np.ndarray:
    """Packed little-endian Y | Cr << 8 | Cb << 16 for index R | G << 8 | B << 16."""
    rg = np.arange(256 * 256, dtype=np.int32)
    table = np.empty((256, 256 * 256), "<u4")
    for b in range(256):
        y, cr, cb = _forward_model(rg & 0xFF, rg >> 8, b, 1)
        table[b] = y | cr << 8 | cb << 16
    return table.reshape(-1)


def ycrcb_to_rgb(y, cr, cb) -> np.ndarray:
    """Sony's YCrCb2RGB, bit-exact, over uint8 arrays of one shape; returns (..., 3) uint8 RGB."""
    return ycrcb_image_to_rgb(np.stack(_planes(y, cr, cb), axis=-1))


def ycrcb_image_to_rgb(ycrcb: np.ndarray) -> np.ndarray:
    """``ycrcb_to_rgb`` of one (..., 3) uint8 array of Y, Cr, Cb."""
    from .ycrcb2rgb import ycrcb2rgb  # numba, loaded by the first decode rather than by every import

    rgb = np.empty(ycrcb.shape, np.uint8)
    ycrcb2rgb(np.ascontiguousarray(ycrcb).reshape(-1), rgb.reshape(-1))
    return rgb


def ycrcb_to_rgb_bt601(y, cr, cb) -> np.ndarray:
    """The BT.601 full-range (JFIF) decoder, rounded to nearest; returns (..., 3) uint8 RGB."""
    y, cr, cb = (p.astype(np.float64) for p in _planes(y, cr, cb))
    cr -= 128
    cb -= 128
    rgb = np.stack([y + 1.402 * cr, y - 0.344136 * cb - 0.714136 * cr, y + 1.772 * cb], axis=-1)
    return np.clip(np.floor(rgb + 0.5), 0, 255).astype(np.uint8)


def _planes(*planes) -> list[np.ndarray]:
    arrays = [np.asarray(p) for p in planes]
    if any(a.dtype != np.uint8 for a in arrays):
        raise FrameError(f"Y, Cr, Cb must be uint8 arrays, got {[str(a.dtype) for a in arrays]}")
    if len({a.shape for a in arrays}) != 1:
        raise FrameError(f"Y, Cr, Cb of different shapes {[a.shape for a in arrays]}")
    return arrays
