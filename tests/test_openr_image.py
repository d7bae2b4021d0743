"""OFbkImageVectorData bytes: header and info fields, band offsets, Pixel/Skip, tag, round trips."""

import struct

import numpy as np
import pytest

from openr_bridge import (
    ImageAccessError,
    MessageFormatError,
    OFbkImage,
    OFbkImageInfo,
    OFbkImageVectorData,
    encode_frame,
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
    restore_tag_pixels,
)

RED = (255, 0, 0)  # Y 76, Cr 218, Cb 90 under the forward model (hand-computed in test_openr_encoder)


def u32(data: bytes, offset: int) -> int:
    return struct.unpack_from("<I", data, offset)[0]


@pytest.fixture(scope="module")
def message_bytes() -> bytes:
    frame = np.zeros((160, 208, 3), np.uint8)
    frame[7, 5] = RED
    return bytes(encode_frame(frame, frame_number=0x01020304, field_counter=0x1234, primitive_id=77))


def test_header_fields(message_bytes):
    assert len(message_bytes) == 320 + 199680 + 49920 + 12480 + 8320 == 270720
    assert message_bytes[16:20] == bytes([0x03, 0x04, 0, 0])  # type 1027, little-endian
    fields = [u32(message_bytes, offset) for offset in range(0, 52, 4)]
    # memRegionID physAddr offset totalSize type infoOffset infoSize maxNumData numData syncKey wait optOffset optSize
    assert fields == [0, 0, 0, 270720, 1027, 192, 32, 4, 4, 0, 0, 0, 0]
    assert message_bytes[52:192] == bytes(140)


def test_info_fields_and_band_offsets(message_bytes):
    expected = [  # type primitiveID frameNumber dataOffset dataSize width height padding
        [24, 77, 0x01020304, 320, 199680, 208, 160, 0],
        [24, 77, 0x01020304, 200000, 49920, 104, 80, 0],
        [24, 77, 0x01020304, 249920, 12480, 52, 40, 0],
        [20, 77, 0x01020304, 262400, 8320, 104, 80, 0],
    ]
    for layer, fields in enumerate(expected):
        assert [u32(message_bytes, 192 + 32 * layer + 4 * i) for i in range(8)] == fields
    message = OFbkImageVectorData(message_bytes)
    assert message.numData == message.maxNumData == 4
    assert message.GetInfo(ofbkimageLAYER_M).dataOffset == 200000
    assert message.GetData(ofbkimageLAYER_C).size == 8320


def test_pixel_and_skip_against_raw_offsets(message_bytes):
    message = OFbkImageVectorData(message_bytes)
    info, data = message.GetInfo(ofbkimageLAYER_H), message.GetData(ofbkimageLAYER_H)
    row = 320 + 6 * 208 * 7  # row 7 of layer H
    expected = {
        ofbkimageBAND_Y: (0, 76),
        ofbkimageBAND_Cr: (208, 218),
        ofbkimageBAND_Cb: (416, 90),
        ofbkimageBAND_Y_LH: (624, 128),
        ofbkimageBAND_Y_HL: (832, 128),
        ofbkimageBAND_Y_HH: (1040, 128),
    }
    for band, (run, value) in expected.items():
        image = OFbkImage(info, data, band)
        assert image.IsValid() and image.Skip() == 1040
        assert (image.Width(), image.Height()) == (208, 160)
        assert image.Pixel(5, 7) == message_bytes[row + run + 5] == value
        assert image.Pixel(6, 7) == message_bytes[row + run + 6]
    assert not OFbkImage(info, data, ofbkimageBAND_CDT).IsValid()

    cdt = OFbkImage(message.GetInfo(ofbkimageLAYER_C), message.GetData(ofbkimageLAYER_C), ofbkimageBAND_CDT)
    assert cdt.IsValid() and cdt.Skip() == 0 and (cdt.Width(), cdt.Height()) == (104, 80)
    assert not OFbkImage(
        message.GetInfo(ofbkimageLAYER_C), message.GetData(ofbkimageLAYER_C), ofbkimageBAND_Y
    ).IsValid()
    m_image = OFbkImage(message.GetInfo(ofbkimageLAYER_M), message.GetData(ofbkimageLAYER_M), ofbkimageBAND_Y)
    assert m_image.Skip() == 5 * 104


def test_tag_bytes_in_each_layer(message_bytes):
    tag = bytes([0x34, 0x12, 0, 0]) + bytes(8)  # no CDT tables: every frequency 0
    h_last_row = 320 + 6 * 208 * 159
    m_last_row = 200000 + 6 * 104 * 79
    l_last_row = 249920 + 6 * 52 * 39
    c_last_row = 262400 + 104 * 79
    for start in (h_last_row, m_last_row, l_last_row, c_last_row):
        assert message_bytes[start : start + 12] == tag
    assert message_bytes[h_last_row + 208 : h_last_row + 220] == bytes([128]) * 12  # Cr untouched
    message = OFbkImageVectorData(message_bytes)
    for layer, band in [
        (ofbkimageLAYER_H, ofbkimageBAND_Y),
        (ofbkimageLAYER_L, ofbkimageBAND_Y),
        (ofbkimageLAYER_C, ofbkimageBAND_CDT),
    ]:
        image = OFbkImage(message.GetInfo(layer), message.GetData(layer), band)
        assert image.FieldCounter() == 0x1234
        assert all(image.ColorFrequency(1 << k) == 0 for k in range(8))


def test_color_frequency_reads_sonys_tag_positions():
    band = np.zeros((2, 16), np.uint8)
    band[1, :12] = [9, 0, 0, 0, 14, 15, 16, 17, 10, 11, 12, 13]
    data = band.reshape(-1)
    image = OFbkImage(OFbkImageInfo(20, 0, 0, 0, 32, 16, 2), data, ofbkimageBAND_CDT)
    assert [image.ColorFrequency(1 << k) for k in range(8)] == [10, 11, 12, 13, 14, 15, 16, 17]
    assert image.FieldCounter() == 9
    with pytest.raises(ImageAccessError):
        image.ColorFrequency(0x03)


def test_restore_tag_pixels_copies_the_row_above_over_12_pixels():
    band = np.arange(3 * 20, dtype=np.uint8).reshape(3, 20)
    restored = restore_tag_pixels(band)
    assert restored[2, :12].tolist() == band[1, :12].tolist()
    assert restored[2, 12:].tolist() == band[2, 12:].tolist()
    assert band[2, 0] == 40  # the input is not modified


def test_numpy_views_are_zero_copy():
    frame = np.zeros((160, 208, 3), np.uint8)
    buffer = bytearray(bytes(encode_frame(frame)))
    message = OFbkImageVectorData(buffer)
    cb = message.band(ofbkimageLAYER_H, ofbkimageBAND_Cb)
    assert cb.shape == (160, 208) and cb.strides == (1248, 1)
    buffer[320 + 1248 * 3 + 416 + 9] = 201
    assert cb[3, 9] == 201
    assert message.band(ofbkimageLAYER_C, ofbkimageBAND_CDT).shape == (80, 104)


def test_round_trip_through_bytes(message_bytes):
    assert bytes(OFbkImageVectorData(message_bytes)) == message_bytes
    copy = OFbkImageVectorData.from_bytes(message_bytes)
    copy.band(ofbkimageLAYER_H, ofbkimageBAND_Y)[0, 0] = 99  # from_bytes owns a writable copy
    assert message_bytes[320] == 0 and bytes(copy)[320] == 99


def hand_built_message() -> bytes:
    """A layout unlike the encoder's: layers in reverse order with gaps, odd header fields."""
    infos, chunks, offset = [], [], 192 + 4 * 32
    layers = [(24, 8, 4), (24, 4, 2), (19, 2, 2), (20, 4, 2)]  # H, M, L (plain YCrCb), C
    blobs = {}
    for layer in reversed(range(4)):
        kind, width, height = layers[layer]
        runs = {24: 6, 19: 3, 20: 1}[kind]
        blob = bytes((layer * 50 + i) % 256 for i in range(runs * width * height)) + b"\xee" * 5
        blobs[layer] = (offset, blob)
        chunks.append(blob)
        offset += len(blob)
    for layer, (kind, width, height) in enumerate(layers):
        start, blob = blobs[layer]
        infos.append(struct.pack("<8I", kind, 0xAB, 1000 + layer, start, len(blob), width, height, 0))
    header = struct.pack("<13I", 7, 0x80001000, 0, offset, 1027, 192, 128, 6, 4, 3, 1, 0, 0)
    return header + bytes(12) + bytes(range(128)) + b"".join(infos) + b"".join(chunks)


def test_a_hand_built_message_parses_and_round_trips():
    data = hand_built_message()
    message = OFbkImageVectorData(data)
    assert bytes(message) == data
    assert message.vectorInfo.physAddr == 0x80001000 and message.vectorInfo.optional == bytes(range(128))
    info = message.GetInfo(ofbkimageLAYER_H)
    assert (info.width, info.height, info.frameNumber) == (8, 4, 1000)
    h_y = OFbkImage(info, message.GetData(ofbkimageLAYER_H), ofbkimageBAND_Y_HH)
    assert h_y.Pixel(3, 2) == data[info.dataOffset + 48 * 2 + 5 * 8 + 3] == (5 * 8 + 48 * 2 + 3) % 256
    l_info = message.GetInfo(ofbkimageLAYER_L)
    l_cb = OFbkImage(l_info, message.GetData(ofbkimageLAYER_L), ofbkimageBAND_Cb)
    assert l_cb.Skip() == 4 and l_cb.Pixel(1, 1) == (100 + 6 + 4 + 1) % 256
    assert not OFbkImage(l_info, message.GetData(ofbkimageLAYER_L), ofbkimageBAND_Y_LH).IsValid()


def corrupt(data: bytes, offset: int, value: int) -> bytes:
    return data[:offset] + struct.pack("<I", value) + data[offset + 4 :]


@pytest.mark.parametrize(
    "mutate, words",
    [
        (lambda d: d[:100], "truncated"),
        (lambda d: d[:250], "truncated"),
        (lambda d: d[:-1], "outside"),
        (lambda d: corrupt(d, 16, 1028), "type code 1028"),
        (lambda d: corrupt(d, 20, 200), "infoOffset"),
        (lambda d: corrupt(d, 32, 0), "numData 0"),
        (lambda d: corrupt(d, 32, 5), "numData 5"),
        (lambda d: corrupt(d, 192 + 32, 25), "layer 1: type code 25"),
        (lambda d: corrupt(d, 192 + 64 + 12, 10), "layer 2: data"),
        (lambda d: corrupt(d, 192 + 96 + 16, 100), "layer 3: dataSize 100"),
        (lambda d: corrupt(d, 192 + 20, 0), "layer 0: empty"),
        (lambda d: corrupt(d, 192 + 24, 2**31), "layer 0: dataSize"),
    ],
)
def test_bad_buffers_raise_message_format_error(message_bytes, mutate, words):
    with pytest.raises(MessageFormatError, match=words):
        OFbkImageVectorData(mutate(message_bytes))


def test_not_a_buffer():
    with pytest.raises(MessageFormatError):
        OFbkImageVectorData("text")


def test_out_of_range_access(message_bytes):
    message = OFbkImageVectorData(message_bytes)
    image = OFbkImage(message.GetInfo(ofbkimageLAYER_H), message.GetData(ofbkimageLAYER_H), ofbkimageBAND_Y)
    for x, y in [(208, 0), (-1, 0), (0, 160), (0, -1), (1.5, 0)]:
        with pytest.raises(ImageAccessError):
            image.Pixel(x, y)
    with pytest.raises(ImageAccessError):
        message.GetInfo(4)
    with pytest.raises(ImageAccessError):
        message.band(ofbkimageLAYER_C, ofbkimageBAND_Y)
    invalid = OFbkImage(message.GetInfo(ofbkimageLAYER_C), message.GetData(ofbkimageLAYER_C), ofbkimageBAND_Cr)
    with pytest.raises(ImageAccessError):
        invalid.Pixel(0, 0)
