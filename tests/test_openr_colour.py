"""ycrcb_to_rgb against the report's YCrCb2RGB on all 2^24 inputs; the BT.601 decoder; the forward model."""

import numpy as np
import pytest

from openr_bridge import FrameError, rgb_to_ycrcb, ycrcb_to_rgb, ycrcb_to_rgb_bt601
from openr_bridge.report_c import compile_report_c

Y_PER_CHUNK = 16  # 2^20 inputs a chunk


@pytest.fixture(scope="module")
def report_c(tmp_path_factory):
    reference = compile_report_c(tmp_path_factory.mktemp("report_c"))
    if reference is None:
        pytest.skip("no C compiler")
    return reference


def transcribed_ycrcb2rgb(y, cr, cb):
    """The report's C function line by line in float64 (sbyte via XOR 0x80, truncating casts)."""
    scr = (cr ^ 0x80).view(np.int8).astype(np.float64)
    scb = (cb ^ 0x80).view(np.int8).astype(np.float64)
    y_ = y.astype(np.float64) / 255.0
    cr_ = scr / 128.0
    cb_ = scb / 128.0
    channels = [255.0 * (y_ + cr_), 255.0 * (y_ - 0.51 * cr_ - 0.19 * cb_), 255.0 * (y_ + cb_)]
    out = []
    for value in channels:
        byte = np.trunc(np.where(value > 255.0, 255.0, np.where(value < 0.0, 0.0, value)))
        out.append(byte.astype(np.uint8))
    return np.stack(out, axis=-1)


def chunk_inputs(y_first):
    y, cr, cb = np.meshgrid(
        np.arange(y_first, y_first + Y_PER_CHUNK, dtype=np.uint8),
        np.arange(256, dtype=np.uint8),
        np.arange(256, dtype=np.uint8),
        indexing="ij",
    )
    return y, cr, cb


def test_all_2_24_inputs_match_the_compiled_report_function(report_c):
    for y_first in range(0, 256, Y_PER_CHUNK):
        expected = report_c.all_inputs(y_first, Y_PER_CHUNK)
        assert np.array_equal(ycrcb_to_rgb(*chunk_inputs(y_first)), expected), f"Y from {y_first}"


@pytest.mark.slow
def test_all_2_24_inputs_match_a_float64_transcription():
    for y_first in range(0, 256, Y_PER_CHUNK):
        inputs = chunk_inputs(y_first)
        assert np.array_equal(ycrcb_to_rgb(*inputs), transcribed_ycrcb2rgb(*inputs)), f"Y from {y_first}"


def test_hand_computed_values():
    # (Y, Cr, Cb) -> RGB: Cr' = 127 gives R = 255 * 127/128 = 253.0 -> 253, G < 0 -> 0
    # Y 255 with Cr' = Cb' = -128: R = B = 0, G = 255 * 1.70 -> 255; neutral chroma returns grey
    y = np.array([0, 255, 100, 100], np.uint8)
    cr = np.array([255, 0, 128, 192], np.uint8)
    cb = np.array([128, 0, 128, 128], np.uint8)
    # last: Cr' = 64: R = 100 + 127.5 = 227.5 -> 227, G = 100 - 0.51 * 127.5 = 34.975 -> 34
    assert ycrcb_to_rgb(y, cr, cb).tolist() == [[253, 0, 0], [0, 255, 0], [100, 100, 100], [227, 34, 100]]


def test_shapes_and_strided_inputs():
    layer = np.random.default_rng(0).integers(0, 256, (5, 6, 7), dtype=np.uint8)
    y, cr, cb = layer[:, 0], layer[:, 1], layer[:, 2]
    rgb = ycrcb_to_rgb(y, cr, cb)
    assert rgb.shape == (5, 7, 3) and rgb.dtype == np.uint8
    assert np.array_equal(rgb, transcribed_ycrcb2rgb(y, cr, cb))
    assert ycrcb_to_rgb(np.uint8(100), np.uint8(128), np.uint8(128)).tolist() == [100, 100, 100]
    assert ycrcb_to_rgb(*(np.zeros((0, 4), np.uint8),) * 3).shape == (0, 4, 3)


def test_bad_planes_raise_frame_error():
    good = np.zeros((2, 2), np.uint8)
    with pytest.raises(FrameError):
        ycrcb_to_rgb(good, good, np.zeros((2, 3), np.uint8))
    with pytest.raises(FrameError):
        ycrcb_to_rgb(good, good, good.astype(np.int16))
    with pytest.raises(FrameError):
        ycrcb_to_rgb_bt601(good, good, [[0, 0], [0, 0]])


def test_bt601_decoder_by_hand():
    y = np.array([100, 128, 50], np.uint8)
    cr = np.array([228, 128, 128], np.uint8)
    cb = np.array([128, 128, 28], np.uint8)
    # Cr' = 100: R = 100 + 140.2 -> 240, G = 100 - 71.4136 -> 29; Cb' = -100: G = 50 + 34.41 -> 84, B < 0 -> 0
    assert ycrcb_to_rgb_bt601(y, cr, cb).tolist() == [[240, 29, 100], [128, 128, 128], [50, 84, 0]]


def test_forward_model_round_trips_within_two_levels():
    levels = np.arange(0, 256, 3)
    rgb = np.stack(np.meshgrid(levels, levels, levels, indexing="ij"), axis=-1).astype(np.uint8)
    error = ycrcb_to_rgb(*rgb_to_ycrcb(rgb)).astype(int) - rgb
    assert error.min() >= -2 and error.max() <= 1


def integer_forward_model(r, g, b):
    """The docstring's exact integer forward model, in int64."""
    y = (299 * r + 587 * g + 114 * b + 500) // 1000
    cr = 128 + (128 * (701 * r - 587 * g - 114 * b) + 127500) // 255000
    cb = 128 + (128 * (886 * b - 299 * r - 587 * g) + 127500) // 255000
    return y, cr, cb


@pytest.mark.slow
def test_forward_table_is_the_integer_model_on_all_2_24_colours():
    r, g = np.meshgrid(np.arange(256), np.arange(256), indexing="ij")
    for b_first in range(0, 256, 16):
        b = np.arange(b_first, b_first + 16).reshape(-1, 1, 1)
        rgb = np.stack(np.broadcast_arrays(r, g, b), axis=-1).astype(np.uint8)
        expected = integer_forward_model(r, g, b)
        for name, planes in [("table", rgb_to_ycrcb(rgb)), ("arithmetic", rgb_to_ycrcb(rgb.astype(np.int64)))]:
            for plane, want in zip(planes, expected, strict=True):
                assert plane.dtype == np.uint8 and np.array_equal(plane, want), f"{name}, B from {b_first}"


def test_forward_model_rejects_non_rgb():
    with pytest.raises(FrameError):
        rgb_to_ycrcb(np.zeros((4, 4)))
