"""The encoder against hand-computed bytes: colour model, Haar bands, pyramid, CDT, tag, luma."""

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


def test_frame_numbers_count_8ms_ticks():
    assert [frame_number_for_image(n) for n in range(8)] == [0, 4, 8, 12, 16, 20, 25, 29]
    message = encode_frame(np.zeros((160, 208, 3), np.uint8), frame_number=2**32 + 5, field_counter=2**16 + 3)
    assert {message.GetInfo(layer).frameNumber for layer in range(4)} == {5}
    assert message.band(H, ofbkimageBAND_Y)[-1, :2].tolist() == [3, 0]


@pytest.mark.parametrize(
    "frame", [np.zeros((160, 208), np.uint8), np.zeros((161, 208, 3), np.uint8), np.zeros((160, 208, 3), np.float32)]
)
def test_bad_frames_raise_frame_error(frame):
    with pytest.raises(FrameError):
        encode_frame(frame)
