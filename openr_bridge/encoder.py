"""From an RGB frame to the ``OFbkImageVectorData`` an ERS-7 would deliver, and back to luma.

Choices made where the spec leaves the hardware unconfirmed:

- Layout: the 192-byte header, four 32-byte infos (``infoSize`` 32), then the data of H, M,
  L and C back to back from offset 320; ``dataSize`` = 6 w h for the HPF layers (199680,
  49920, 12480) and w h for C (8320); ``numData`` = ``maxNumData`` = 4; ``totalSize`` is the
  message length; region, address, sync and option fields are 0.
- ``frameNumber`` (8 ms ticks, see ``ers7_camera.frame_number_for_image``) is the same in all
  four infos; it wraps at 2^32 and the field counter at 2^16.
- Y subbands, from the layer's double-resolution luma p (pXY = p(2x + X, 2y + Y)):
  Y_LL = (p00 + p10 + p01 + p11 + 2) >> 2, Y_LH = 128 + ((p01 + p11 - p00 - p10 + 2) >> 2),
  Y_HL = 128 + ((p10 + p11 - p00 - p01 + 2) >> 2), Y_HH = 128 + ((p00 + p11 - p10 - p01 + 2) >> 2):
  the Haar analysis with scale 1/4, rounded half up, clipped to 0..255.
- From a 416x320 frame that luma is the frame's per-pixel Y (``colour.rgb_to_ycrcb``), and
  H's chroma is the forward model of each 2x2 block's mean RGB, rounded once (by linearity,
  the mean of the unrounded per-pixel chroma; rounding each pixel first would differ). From
  a 208x160 frame H is the per-pixel forward model and its detail bands are flat (128).
- M is the next level from H's stored bytes: its Y bands are the Haar analysis of H's Y,
  its Cr and Cb the 2x2 means of H's, rounded half up ((sum + 2) >> 2); L follows from M.
- C is ``cdt.cdt_layer`` of M's Y, Cr, Cb (zero without tables).
- The tag, written last: bytes 0-1 the field counter (u16 LE), bytes 2-3 zero, bytes 4-7
  the colour frequencies of channels 4-7 and 8-11 those of channels 0-3, each
  min(255, pixels / 16) over the whole C layer (104 x 80 / 16 = 520 would not fit a byte).
  It goes into the first 12 bytes of the last row of the Y band of H, M and L and of layer
  C: Sony reads the CDT layer's ``ColorFrequency`` and skips C's last row "because of
  TagInfo" in its BallTrackingHead sample, so C carries it as well; the Cr, Cb and detail
  bands are left alone. M, L and C are computed from the untagged values.

``reconstruct_luma`` is Sony's double-resolution reconstruction. It returns exactly the luma
whose 2x2 blocks the bands can hold: four values of one parity whose sum is a multiple of 4.
No byte bands can hold every luma (the analysis maps 4 bytes to 4 bytes with determinant
1/16); as the analysis is orthogonal up to a factor 2, rounding each band is the nearest
holdable block, so any other luma comes back within 2 levels per pixel (and within 2 in the
root-sum-square over a block).
"""

import numpy as np

from .cdt import OCdtVectorData, cdt_layer, ocdtNUM_CHANNELS
from .colour import rgb_to_ycrcb
from .errors import FrameError
from .ers7_camera import FULL_HEIGHT, FULL_WIDTH, LAYER_SIZE, LAYER_TYPE
from .image import (
    IMAGE_INFO_SIZE,
    TAG_LENGTH,
    VECTOR_INFO_SIZE,
    ODataVectorInfo,
    OFbkImageInfo,
    OFbkImageVectorData,
    ofbkimageBAND_Y,
    ofbkimageBAND_Y_HH,
    ofbkimageBAND_Y_HL,
    ofbkimageBAND_Y_LH,
    ofbkimageLAYER_H,
)


def encode_frame(
    rgb: np.ndarray,
    *,
    frame_number: int = 0,
    field_counter: int = 0,
    cdt: OCdtVectorData | None = None,
    primitive_id: int = 0,
) -> OFbkImageVectorData:
    """The message for a (320, 416, 3) or (160, 208, 3) uint8 RGB frame."""
    h_layer = _layer_h(rgb)
    m_layer = _next_level(h_layer)
    l_layer = _next_level(m_layer)
    c_layer = cdt_layer(m_layer[0], m_layer[1], m_layer[2], cdt)
    layers = [np.stack(h_layer, axis=1), np.stack(m_layer, axis=1), np.stack(l_layer, axis=1), c_layer]

    tag = _tag(field_counter, c_layer)
    for hpf_layer in layers[:3]:
        hpf_layer[-1, 0, :TAG_LENGTH] = tag  # run 0 of a row is the Y band
    c_layer[-1, :TAG_LENGTH] = tag

    offset = VECTOR_INFO_SIZE + IMAGE_INFO_SIZE * len(layers)
    infos = []
    for (width, height), layer_type, layer in zip(LAYER_SIZE, LAYER_TYPE, layers, strict=True):
        info = OFbkImageInfo(layer_type, primitive_id, frame_number % 2**32, offset, layer.size, width, height)
        infos.append(info.pack())
        offset += layer.size
    header = ODataVectorInfo(totalSize=offset, maxNumData=len(layers), numData=len(layers)).pack()
    return OFbkImageVectorData(bytearray(b"".join([header, *infos, *(layer.tobytes() for layer in layers)])))


def haar_analysis(luma: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(Y_LL, Y_LH, Y_HL, Y_HH) uint8 bands of a (2h, 2w) uint8 luma."""
    p = luma.astype(np.int32)
    p00, p10, p01, p11 = p[0::2, 0::2], p[0::2, 1::2], p[1::2, 0::2], p[1::2, 1::2]
    ll = (p00 + p10 + p01 + p11 + 2) >> 2
    lh = 128 + ((p01 + p11 - p00 - p10 + 2) >> 2)
    hl = 128 + ((p10 + p11 - p00 - p01 + 2) >> 2)
    hh = 128 + ((p00 + p11 - p10 - p01 + 2) >> 2)
    return tuple(np.clip(band, 0, 255).astype(np.uint8) for band in (ll, lh, hl, hh))


def reconstruct_luma(message: OFbkImageVectorData, layer: int = ofbkimageLAYER_H) -> np.ndarray:
    """The (2h, 2w) uint8 luma rebuilt from a layer's Y, Y_LH, Y_HL, Y_HH (Sony's formulas)."""
    ll, a, b, c = (
        message.band(layer, band).astype(np.int16)
        for band in (ofbkimageBAND_Y, ofbkimageBAND_Y_LH, ofbkimageBAND_Y_HL, ofbkimageBAND_Y_HH)
    )
    a, b, c = a - 128, b - 128, c - 128
    height, width = ll.shape
    luma = np.empty((2 * height, 2 * width), np.int16)
    luma[1::2, 1::2] = ll + a + b + c
    luma[1::2, 0::2] = ll + a - b - c
    luma[0::2, 1::2] = ll - a + b - c
    luma[0::2, 0::2] = ll - a - b + c
    return np.clip(luma, 0, 255).astype(np.uint8)


def _layer_h(rgb) -> list[np.ndarray]:
    """H's bands in row order Y, Cr, Cb, Y_LH, Y_HL, Y_HH."""
    rgb = np.asarray(rgb)
    width, height = LAYER_SIZE[ofbkimageLAYER_H]
    if rgb.dtype != np.uint8 or rgb.shape not in [(FULL_HEIGHT, FULL_WIDTH, 3), (height, width, 3)]:
        raise FrameError(
            f"frame of shape {rgb.shape} and dtype {rgb.dtype}, expected uint8 RGB "
            f"({FULL_HEIGHT}, {FULL_WIDTH}, 3) or ({height}, {width}, 3)"
        )
    if rgb.shape[0] == height:
        flat = np.full((height, width), 128, np.uint8)
        return [*rgb_to_ycrcb(rgb), flat, flat, flat]
    ll, lh, hl, hh = haar_analysis(rgb_to_ycrcb(rgb)[0])
    _, cr, cb = rgb_to_ycrcb(_sum2x2(rgb), pixels=4)
    return [ll, cr, cb, lh, hl, hh]


def _next_level(bands: list[np.ndarray]) -> list[np.ndarray]:
    y, cr, cb = bands[:3]
    ll, lh, hl, hh = haar_analysis(y)
    return [ll, _mean2x2(cr), _mean2x2(cb), lh, hl, hh]


def _mean2x2(band: np.ndarray) -> np.ndarray:
    return ((_sum2x2(band) + 2) >> 2).astype(np.uint8)


def _sum2x2(image: np.ndarray) -> np.ndarray:
    p = image.astype(np.int32)
    return p[0::2, 0::2] + p[0::2, 1::2] + p[1::2, 0::2] + p[1::2, 1::2]


def _tag(field_counter: int, c_layer: np.ndarray) -> np.ndarray:
    frequency = [min(255, np.count_nonzero(c_layer & (1 << k)) // 16) for k in range(ocdtNUM_CHANNELS)]
    counter = field_counter % 2**16
    return np.array([counter & 0xFF, counter >> 8, 0, 0, *frequency[4:], *frequency[:4]], np.uint8)
