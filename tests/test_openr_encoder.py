"""The encoder against hand-computed bytes and against the integer definitions: colour model, Haar
bands, pyramid, CDT, tag, luma."""

import numpy as np
import pytest

from openr_bridge import (
    CdtError,
    FrameError,
    OCdtInfo,
    OCdtVectorData,
    cdt_layer,
    encode_frame,
    frame_number_for_image,
    haar_analysis,
    ocdtCHANNEL0,
    ocdtCHANNEL1,
    ocdtCHANNEL7,
    ofbkimageBAND_Cb,
    ofbkimageBAND_CDT,
    ofbkimageBAND_Cr,
    ofbkimageBAND_Y,
    ofbkimageBAND_Y_HH,
    ofbkimageBAND_Y_HL,
    ofbkimageBAND_Y_LH,
    ofbkimageLAYER_C,
    ofbkimageLAYER_H,
    ofbkimageLAYER_L,
    ofbkimageLAYER_M,
    orange_ball_cdt,
    pink_ball_cdt,
    reconstruct_luma,
    rgb_to_ycrcb,
)
from openr_bridge.pyramid import next_level

H, M, L, C = ofbkimageLAYER_H, ofbkimageLAYER_M, ofbkimageLAYER_L, ofbkimageLAYER_C
Y_BANDS = (ofbkimageBAND_Y, ofbkimageBAND_Y_LH, ofbkimageBAND_Y_HL, ofbkimageBAND_Y_HH)


def bands_at(message, layer, x, y, bands):
    return [int(message.band(layer, band)[y, x]) for band in bands]


def grey(values) -> np.ndarray:
    values = np.asarray(values, np.uint8)
    return np.repeat(values[..., np.newaxis], 3, axis=-1)


def test_forward_colour_model_by_hand():
    # red: Y = 0.299 * 255 = 76.245; Cr = 128 + (128/255) * 178.755 = 217.73; Cb = 128 - (128/255) * 76.245 = 89.73
    # green: Y = 149.685; Cr = Cb = 128 - (128/255) * 149.685 = 52.86
    # blue: Y = 29.07; Cr = 128 - 14.59 = 113.41; Cb = 128 + (128/255) * 225.93 = 241.41
    rgb = np.array([[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 255], [0, 0, 0]], np.uint8)
    y, cr, cb = rgb_to_ycrcb(rgb)
    assert y.tolist() == [76, 150, 29, 255, 0]
    assert cr.tolist() == [218, 53, 113, 128, 128]
    assert cb.tolist() == [90, 53, 241, 128, 128]


def test_full_frame_haar_bands_by_hand():
    luma = np.zeros((320, 416), np.uint8)
    luma[0:2, 0:2] = [[10, 20], [30, 44]]  # p00 p10 / p01 p11
    luma[0:2, 2:4] = [[0, 0], [0, 1]]  # not reachable: p11 comes back as 0
    luma[0:2, 4:6] = [[1, 1], [0, 0]]  # sum 2: Y_LL 0.5 rounds up to 1; Y_LH -0.5 rounds up to 0
    message = encode_frame(grey(luma))
    # Y_LL = 104/4 = 26, Y_LH = 128 + (30 + 44 - 10 - 20)/4 = 139, Y_HL = 128 + (20 + 44 - 10 - 30)/4 = 134,
    # Y_HH = 128 + (10 + 44 - 20 - 30)/4 = 129
    assert bands_at(message, H, 0, 0, Y_BANDS) == [26, 139, 134, 129]
    assert bands_at(message, H, 1, 0, Y_BANDS) == [0, 128, 128, 128]  # 1/4 rounds to 0 everywhere
    assert bands_at(message, H, 2, 0, Y_BANDS) == [1, 128, 128, 128]
    assert bands_at(message, H, 0, 0, (ofbkimageBAND_Cr, ofbkimageBAND_Cb)) == [128, 128]
    full = reconstruct_luma(message)
    assert full[0:2, 0:2].tolist() == [[10, 20], [30, 44]]
    assert full[0:2, 2:4].tolist() == [[0, 0], [0, 0]]
    assert full[0:2, 4:6].tolist() == [[1, 1], [1, 1]]


def test_full_frame_chroma_is_the_model_of_the_block_mean():
    frame = np.zeros((320, 416, 3), np.uint8)
    frame[0, 0] = frame[1, 1] = (255, 0, 0)
    frame[0, 1] = frame[1, 0] = (0, 0, 255)
    message = encode_frame(frame)
    # mean RGB (127.5, 0, 127.5): Y = 52.6575, Cr = Cb = 128 + (128/255) * 74.8425 = 165.57 -> 166
    # (rounding per pixel first would give (218 + 113) / 2 = 165.5)
    assert bands_at(message, H, 0, 0, (ofbkimageBAND_Cr, ofbkimageBAND_Cb)) == [166, 166]
    # per-pixel luma 76 (red) and 29 (blue): Y_LL = 210/4 = 52.5 -> 53, Y_HH = 128 + (76 + 76 - 29 - 29)/4 = 152
    assert bands_at(message, H, 0, 0, Y_BANDS) == [53, 128, 128, 152]


def test_half_resolution_frame_has_flat_details_and_pyramid_by_hand():
    luma = np.zeros((160, 208), np.uint8)
    luma[0:2, 0:2] = [[10, 20], [30, 44]]
    message = encode_frame(grey(luma))
    assert bands_at(message, H, 1, 0, Y_BANDS) == [20, 128, 128, 128]
    assert (message.band(H, ofbkimageBAND_Y_LH) == 128).all()
    assert bands_at(message, M, 0, 0, Y_BANDS) == [26, 139, 134, 129]
    # L from M's Y block 26, 0 / 0, 0: Y_LL 6.5 -> 7, Y_LH = Y_HL = 128 + (-26/4 = -6.5 -> -6), Y_HH = 128 + 6.5 -> 135
    assert bands_at(message, L, 0, 0, Y_BANDS) == [7, 122, 122, 135]
    assert bands_at(message, L, 0, 0, (ofbkimageBAND_Cr, ofbkimageBAND_Cb)) == [128, 128]


def test_chroma_pyramid_means_by_hand():
    frame = np.zeros((160, 208, 3), np.uint8)
    frame[0, 0] = (255, 0, 0)  # Cr 218, Cb 90; the other three pixels black (128, 128)
    message = encode_frame(frame)
    # M: (218 + 3 * 128) / 4 = 150.5 -> 151 and (90 + 384) / 4 = 118.5 -> 119
    # L: (151 + 384) / 4 = 133.75 -> 134 and (119 + 384) / 4 = 125.75 -> 126
    assert bands_at(message, M, 0, 0, (ofbkimageBAND_Cr, ofbkimageBAND_Cb)) == [151, 119]
    assert bands_at(message, L, 0, 0, (ofbkimageBAND_Cr, ofbkimageBAND_Cb)) == [134, 126]


def ball_frame() -> np.ndarray:
    frame = np.full((160, 208, 3), 128, np.uint8)
    frame[0:32, 0:64] = (255, 105, 180)  # pink: Y 158, Cr 176, Cb 139 -> M 32 x 16 = 512 pixels
    frame[64:80, 100:132] = (255, 128, 0)  # orange: Y 151, Cr 180, Cb 52 -> M 16 x 8 = 128 pixels
    return frame


def test_cdt_layer_bits_and_tag_by_hand():
    cdt = OCdtVectorData.of(pink_ball_cdt(chan=ocdtCHANNEL0), orange_ball_cdt(chan=ocdtCHANNEL1))
    message = encode_frame(ball_frame(), field_counter=0x0201, cdt=cdt)
    layer_c = message.band(C, ofbkimageBAND_CDT)
    assert layer_c[0, 0] == 1 and layer_c[15, 31] == 1 and layer_c[16, 31] == 0
    assert layer_c[32, 50] == 2 and layer_c[39, 65] == 2 and layer_c[40, 65] == 0
    assert layer_c[60, 100] == 0
    assert not (layer_c & 0x80).any()
    tag = [0x01, 0x02, 0, 0, 0, 0, 0, 0, 512 // 16, 128 // 16, 0, 0]
    for layer, band in [(H, ofbkimageBAND_Y), (M, ofbkimageBAND_Y), (L, ofbkimageBAND_Y), (C, ofbkimageBAND_CDT)]:
        assert message.band(layer, band)[-1, :12].tolist() == tag


def test_colour_frequency_saturates_at_255():
    frame = np.full((160, 208, 3), (255, 105, 180), np.uint8)
    message = encode_frame(frame, cdt=OCdtVectorData.of(pink_ball_cdt()))
    assert message.band(C, ofbkimageBAND_CDT)[-1, 8] == 255  # 104 * 80 / 16 = 520


def test_cdt_box_bounds_are_inclusive_and_init_matches_nothing():
    info = OCdtInfo()
    info.Init(0, ocdtCHANNEL0)
    info.Set(16, 140, 130, 110, 100)  # Y 128..135: Cr 130..140, Cb 100..110
    frame = np.zeros((160, 208, 3), np.uint8)
    message = encode_frame(frame, cdt=OCdtVectorData.of(info))
    assert not message.band(C, ofbkimageBAND_CDT).any()  # black: Y 0, Cr = Cb = 128 at an INIT segment
    y = np.array([128, 135, 136, 128, 128, 128, 127], np.uint8)
    cr = np.array([130, 140, 135, 129, 141, 135, 135], np.uint8)
    cb = np.array([100, 110, 105, 105, 105, 99, 105], np.uint8)
    assert cdt_layer(y, cr, cb, OCdtVectorData.of(info)).tolist() == [1, 1, 0, 0, 0, 0, 0]


def test_channel_7_and_bad_tables_are_refused():
    for chan in (ocdtCHANNEL7, 0x03, 0):
        info = OCdtInfo()
        info.Init(0, chan)
        with pytest.raises(CdtError):
            encode_frame(np.zeros((160, 208, 3), np.uint8), cdt=OCdtVectorData.of(info))
    with pytest.raises(CdtError, match="two tables"):
        encode_frame(np.zeros((160, 208, 3), np.uint8), cdt=OCdtVectorData.of(pink_ball_cdt(), pink_ball_cdt()))
    info = OCdtInfo()
    info.Init(0, ocdtCHANNEL0)
    for args in [(32, 1, 0, 1, 0), (0, 256, 0, 1, 0)]:
        with pytest.raises(CdtError):
            info.Set(*args)


def test_cdt_packing_is_sonys():
    info = pink_ball_cdt(prmID=5, chan=ocdtCHANNEL0)
    assert (info.type, info.primitiveID, info.channel) == (21, 5, 1)
    # Cr_min | Cr_max << 8 | Cb_min << 16 | Cb_max << 24
    assert info.table[0] == 150 | 230 << 8 | 120 << 16 | 190 << 24 == 0xBE78E696
    assert info.table[20] == 160 | 230 << 8 | 120 << 16 | 190 << 24
    fresh = OCdtInfo()
    fresh.Init(0, ocdtCHANNEL1)
    assert fresh.table == [0x80808080] * 32


def test_orange_table_picks_orange_only():
    oranges = [(255, 128, 0), (255, 100, 0), (255, 160, 40), (140, 60, 0), (255, 190, 90)]
    others = [
        (255, 0, 0),
        (255, 255, 0),
        (255, 105, 180),
        (230, 180, 150),
        (120, 80, 40),
        (40, 140, 40),
        (255, 255, 255),
    ]
    y, cr, cb = rgb_to_ycrcb(np.array(oranges + others, np.uint8))
    bits = cdt_layer(y, cr, cb, OCdtVectorData.of(orange_ball_cdt(chan=ocdtCHANNEL0)))
    assert bits.tolist() == [1] * len(oranges) + [0] * len(others)


def test_luma_reconstructs_exactly_when_reachable():
    rng = np.random.default_rng(3)
    # blocks built from integer bands (L, a, b, c) with every pixel in 0..255
    ll = rng.integers(40, 216, (160, 208))
    a, b, c = (rng.integers(-13, 14, (160, 208)) for _ in range(3))
    luma = np.empty((320, 416), np.int64)
    luma[1::2, 1::2] = ll + a + b + c
    luma[1::2, 0::2] = ll + a - b - c
    luma[0::2, 1::2] = ll - a + b - c
    luma[0::2, 0::2] = ll - a - b + c
    full = reconstruct_luma(encode_frame(grey(luma)))
    tagged = np.zeros(full.shape, bool)
    tagged[318:, :24] = True  # under H's 12 tag pixels
    assert (full == luma)[~tagged].all()


def test_luma_error_is_at_most_2_otherwise():
    rng = np.random.default_rng(4)
    frame = rng.integers(0, 256, (320, 416, 3), dtype=np.uint8)
    error = reconstruct_luma(encode_frame(frame)).astype(int) - rgb_to_ycrcb(frame)[0]
    error[318:, :24] = 0
    assert np.abs(error).max() <= 2
    block_rss = np.sqrt((error.reshape(160, 2, 208, 2) ** 2).sum(axis=(1, 3)))
    assert block_rss.max() <= 2
    assert (error == 0).mean() > 0.5


def integer_haar(luma) -> list[np.ndarray]:
    """The module docstring's Y subbands, in int64."""
    p = np.asarray(luma, np.int64)
    p00, p10, p01, p11 = p[0::2, 0::2], p[0::2, 1::2], p[1::2, 0::2], p[1::2, 1::2]
    ll = (p00 + p10 + p01 + p11 + 2) >> 2
    details = [p01 + p11 - p00 - p10, p10 + p11 - p00 - p01, p00 + p11 - p10 - p01]
    return [ll] + [np.clip(128 + ((x + 2) >> 2), 0, 255) for x in details]


def integer_mean2x2(plane) -> np.ndarray:
    p = np.asarray(plane, np.int64)
    return (p[0::2, 0::2] + p[0::2, 1::2] + p[1::2, 0::2] + p[1::2, 1::2] + 2) >> 2


def integer_next_level(y, cr, cb) -> list[np.ndarray]:
    """A layer's runs Y, Cr, Cb, Y_LH, Y_HL, Y_HH from the next larger layer's Y, Cr, Cb."""
    ll, lh, hl, hh = integer_haar(y)
    return [ll, integer_mean2x2(cr), integer_mean2x2(cb), lh, hl, hh]


def reference_layers(rgb, field_counter, cdt) -> list[np.ndarray]:
    """Layers H, M, L, C as (height, runs, width), from the docstrings' definitions."""
    r, g, b = (rgb[..., k].astype(np.int64) for k in range(3))
    y = (299 * r + 587 * g + 114 * b + 500) // 1000
    if rgb.shape[0] == 160:
        cr = 128 + (128 * (701 * r - 587 * g - 114 * b) + 127500) // 255000
        cb = 128 + (128 * (886 * b - 299 * r - 587 * g) + 127500) // 255000
        h = [y, cr, cb] + [np.full(y.shape, 128)] * 3
    else:
        r4, g4, b4 = (p[0::2, 0::2] + p[0::2, 1::2] + p[1::2, 0::2] + p[1::2, 1::2] for p in (r, g, b))
        ll, lh, hl, hh = integer_haar(y)
        cr = 128 + (128 * (701 * r4 - 587 * g4 - 114 * b4) + 4 * 127500) // (4 * 255000)
        cb = 128 + (128 * (886 * b4 - 299 * r4 - 587 * g4) + 4 * 127500) // (4 * 255000)
        h = [ll, cr, cb, lh, hl, hh]
    m = integer_next_level(*h[:3])
    l_ = integer_next_level(*m[:3])
    c = cdt_layer(*(np.asarray(band, np.uint8) for band in m[:3]), cdt)
    layers = [np.stack(h, axis=1), np.stack(m, axis=1), np.stack(l_, axis=1), c[:, np.newaxis]]
    frequency = [min(255, np.count_nonzero(c & (1 << k)) // 16) for k in range(8)]
    counter = field_counter % 2**16
    for layer in layers:
        layer[-1, 0, :12] = [counter & 0xFF, counter >> 8, 0, 0, *frequency[4:], *frequency[:4]]
    return layers


@pytest.mark.parametrize("shape", [(160, 208, 3), (320, 416, 3)])
def test_messages_match_the_integer_definitions(shape):
    rng = np.random.default_rng(6)
    cdt = OCdtVectorData.of(pink_ball_cdt(chan=ocdtCHANNEL0), orange_ball_cdt(chan=ocdtCHANNEL1))
    frames = [
        rng.integers(0, 256, shape, dtype=np.uint8),
        rng.integers(0, 2, shape, dtype=np.uint8) * 255,  # extremes: saturated detail bands
        np.repeat(rng.integers(0, 256, (shape[0], shape[1] // 8, 3), dtype=np.uint8), 8, axis=1),
        np.full(shape, (255, 105, 180), np.uint8),
    ]
    for index, frame in enumerate(frames):
        for field_counter, tables in [(index, None), (70000 + index, cdt)]:
            message = encode_frame(frame, field_counter=field_counter, cdt=tables)
            for layer, expected in enumerate(reference_layers(frame, field_counter, tables)):
                actual = message.GetData(layer).reshape(expected.shape)
                assert np.array_equal(actual, expected), f"frame {index}, layer {layer}, CDT {tables is not None}"


def test_pyramid_step_matches_the_integer_definitions_on_all_low_bit_blocks():
    # every 2x2 block of 32 levels (all residues mod 4, both ends of the range) in each of
    # Y, Cr and Cb of an H-width layer: Haar bands with their clip, and (sum + 2) >> 2
    levels = np.r_[0:8, 60:68, 124:132, 248:256].astype(np.uint8)
    blocks = np.stack(np.meshgrid(levels, levels, levels, levels, indexing="ij"), axis=-1).reshape(-1, 2, 2)
    width = 104  # blocks per row of M, as made from H
    blocks = np.concatenate([blocks, blocks[: -len(blocks) % width]])
    plane = blocks.reshape(-1, width, 2, 2).transpose(0, 2, 1, 3).reshape(-1, 2 * width)
    src = np.full((plane.shape[0], 6, 2 * width), 128, np.uint8)
    src[:, 0], src[:, 1], src[:, 2] = plane, np.roll(plane, 2), plane[::-1]
    dst = np.zeros((plane.shape[0] // 2, 6, width), np.uint8)
    next_level(src, dst)
    expected = integer_next_level(src[:, 0], src[:, 1], src[:, 2])
    for run, want in enumerate(expected):
        assert np.array_equal(dst[:, run], want), f"run {run}"
    assert (expected[3] == 255).any() and (expected[5] == 1).any()  # the clip and the low end are reached


def test_haar_analysis_of_any_luma():
    luma = np.random.default_rng(7).integers(0, 256, (6, 10), dtype=np.uint8)
    for band, want in zip(haar_analysis(luma[:, ::-1]), integer_haar(luma[:, ::-1]), strict=True):
        assert band.dtype == np.uint8 and np.array_equal(band, want)


def test_frame_numbers_count_8ms_ticks():
    # the first 8 ms frame at or after n/30 s, as the runtime delivers images: 0, 5, 9, 13, ...
    assert [frame_number_for_image(n) for n in range(8)] == [0, 5, 9, 13, 17, 21, 25, 30]
    for n in range(100):
        tick = frame_number_for_image(n)
        assert tick * 8 * 30 >= n * 1000 > (tick - 1) * 8 * 30
    message = encode_frame(np.zeros((160, 208, 3), np.uint8), frame_number=2**32 + 5, field_counter=2**16 + 3)
    assert message.band(H, ofbkimageBAND_Y)[-1, :2].tolist() == [3, 0]
    # OPEN-R's frame numbers wrap to 1 after oframeMAX_NUMBER (0x0ffffff0), never to 0.
    for tick, number in (
        (0, 0),
        (0x0FFFFFF0, 0x0FFFFFF0),
        (0x0FFFFFF1, 1),
        (2 * 0x0FFFFFF0 + 1, 1),
        (2**32 + 5, (2**32 + 4) % 0x0FFFFFF0 + 1),
    ):
        message = encode_frame(np.zeros((160, 208, 3), np.uint8), frame_number=tick)
        assert {message.GetInfo(layer).frameNumber for layer in range(4)} == {number}


@pytest.mark.parametrize(
    "frame", [np.zeros((160, 208), np.uint8), np.zeros((161, 208, 3), np.uint8), np.zeros((160, 208, 3), np.float32)]
)
def test_bad_frames_raise_frame_error(frame):
    with pytest.raises(FrameError):
        encode_frame(frame)
