"""OPEN-R's image message, ``OFbkImageVectorData``, with Sony's names and a numpy face.

Byte layout (little-endian, offsets from the start of the message, as Sony's ``GetData``):

- 0: ``ODataVectorInfo``, 192 bytes (``VECTOR_INFO_FORMAT``);
- 192: ``OFbkImageInfo[numData]``, 32 bytes each, indexed by layer (``IMAGE_INFO_FORMAT``);
- ``info.dataOffset``: the layer. A ``YCrCb_HPF`` row is six W-byte runs Y, Cr, Cb, Y_LH,
  Y_HL, Y_HH (stride 6W), a ``YCrCb`` row three (Y, Cr, Cb), a ``CDT`` row one.

Parsing follows Sony's accessors: ``GetInfo(i)`` reads the i-th 32-byte block after the
header (``infoOffset`` must be 192; ``infoSize`` is not checked, its real value being
unconfirmed), and each layer's ``dataOffset``/``dataSize`` must lie inside the buffer and hold
``height`` rows of its stride. A message keeps its buffer as given, so ``bytes(message)``
returns it unchanged, and every numpy array it hands out is a view of that buffer.

The tag: OPEN-R overwrites the first ``TAG_LENGTH`` bytes of a layer's last row with the
field counter (bytes 0-1, u16) and the colour frequencies (bytes 4-7: channels 4-7, bytes
8-11: channels 0-3). ``OFbkImage.FieldCounter`` and ``ColorFrequency`` read it as Sony's
inline functions do; ``restore_tag_pixels`` hides it.
"""

import struct
from typing import NamedTuple

import numpy as np

from .errors import ImageAccessError, MessageFormatError

odataFBK_YCrCb = 19
odataFBK_CDT = 20
odataCDT = 21
odataFBK_YCrCb_HPF = 24
odataFBKIMAGE_VECTOR = 1027
odataCDT_VECTOR = 1028

ofbkimageLAYER_H = 0
ofbkimageLAYER_M = 1
ofbkimageLAYER_L = 2
ofbkimageLAYER_C = 3

ofbkimageBAND_Y = 0
ofbkimageBAND_Cr = 1
ofbkimageBAND_Cb = 2
ofbkimageBAND_CDT = 3
ofbkimageBAND_Y_LH = 4
ofbkimageBAND_Y_HL = 5
ofbkimageBAND_Y_HH = 6

VECTOR_INFO_FORMAT = "<13I12x128s"
VECTOR_INFO_SIZE = struct.calcsize(VECTOR_INFO_FORMAT)  # 192
IMAGE_INFO_FORMAT = "<8I"
IMAGE_INFO_SIZE = struct.calcsize(IMAGE_INFO_FORMAT)  # 32
TAG_LENGTH = 12

# For each layer type: the run (in units of W) at which each valid band starts, and the
# number of runs in a row. A band missing here makes an invalid OFbkImage, as in OPEN-R.
BAND_RUNS = {
    odataFBK_YCrCb_HPF: (
        {
            ofbkimageBAND_Y: 0,
            ofbkimageBAND_Cr: 1,
            ofbkimageBAND_Cb: 2,
            ofbkimageBAND_Y_LH: 3,
            ofbkimageBAND_Y_HL: 4,
            ofbkimageBAND_Y_HH: 5,
        },
        6,
    ),
    odataFBK_YCrCb: ({ofbkimageBAND_Y: 0, ofbkimageBAND_Cr: 1, ofbkimageBAND_Cb: 2}, 3),
    odataFBK_CDT: ({ofbkimageBAND_CDT: 0}, 1),
}


class ODataVectorInfo(NamedTuple):
    """The 192-byte header of every OPEN-R vector message."""

    memRegionID: int = 0
    physAddr: int = 0
    offset: int = 0
    totalSize: int = 0
    type: int = odataFBKIMAGE_VECTOR
    infoOffset: int = VECTOR_INFO_SIZE
    infoSize: int = IMAGE_INFO_SIZE
    maxNumData: int = 0
    numData: int = 0
    syncKey: int = 0
    wait: int = 0
    optOffset: int = 0
    optSize: int = 0
    optional: bytes = bytes(128)

    def pack(self) -> bytes:
        """The header's 192 bytes."""
        return struct.pack(VECTOR_INFO_FORMAT, *self)


class OFbkImageInfo(NamedTuple):
    """One layer's 32-byte description."""

    type: int
    primitiveID: int
    frameNumber: int
    dataOffset: int
    dataSize: int
    width: int
    height: int
    padding: int = 0

    def pack(self) -> bytes:
        """The description's 32 bytes."""
        return struct.pack(IMAGE_INFO_FORMAT, *self)


class OFbkImageVectorData:
    """An image message over a bytes-like buffer (zero copy), validated on construction."""

    def __init__(self, buffer):
        try:
            self._bytes = np.frombuffer(buffer, np.uint8)
        except (TypeError, ValueError) as error:
            raise MessageFormatError(f"not a bytes-like buffer: {error}") from None
        size = self._bytes.size
        if size < VECTOR_INFO_SIZE:
            raise MessageFormatError(f"truncated: {size} bytes, the header alone is {VECTOR_INFO_SIZE}")
        self.vectorInfo = ODataVectorInfo(*struct.unpack_from(VECTOR_INFO_FORMAT, self._bytes))
        header = self.vectorInfo
        if header.type != odataFBKIMAGE_VECTOR:
            raise MessageFormatError(f"type code {header.type}, expected {odataFBKIMAGE_VECTOR} (odataFBKIMAGE_VECTOR)")
        if header.infoOffset != VECTOR_INFO_SIZE:
            raise MessageFormatError(f"infoOffset {header.infoOffset}, expected {VECTOR_INFO_SIZE}")
        if not 1 <= header.numData <= header.maxNumData:
            raise MessageFormatError(f"numData {header.numData} not in 1..maxNumData ({header.maxNumData})")
        infos_end = VECTOR_INFO_SIZE + IMAGE_INFO_SIZE * header.numData
        if size < infos_end:
            raise MessageFormatError(f"truncated: {size} bytes, {header.numData} infos end at {infos_end}")
        self._infos = [
            OFbkImageInfo(*struct.unpack_from(IMAGE_INFO_FORMAT, self._bytes, VECTOR_INFO_SIZE + IMAGE_INFO_SIZE * i))
            for i in range(header.numData)
        ]
        for layer, info in enumerate(self._infos):
            _check_layer(layer, info, infos_end, size)

    @classmethod
    def from_bytes(cls, data) -> "OFbkImageVectorData":
        """A message over a private, writable copy of ``data``."""
        return cls(bytearray(data))

    def __bytes__(self) -> bytes:
        return self._bytes.tobytes()

    @property
    def numData(self) -> int:
        """Number of layers in the message."""
        return self.vectorInfo.numData

    @property
    def maxNumData(self) -> int:
        """The header's ``maxNumData``."""
        return self.vectorInfo.maxNumData

    def GetInfo(self, layer: int) -> OFbkImageInfo:
        """The description of ``layer``; ImageAccessError for a layer not in the message."""
        return self._infos[self._layer_index(layer)]

    def GetData(self, layer: int) -> np.ndarray:
        """The layer's ``dataSize`` bytes, as a flat uint8 view."""
        info = self.GetInfo(layer)
        return self._bytes[info.dataOffset : info.dataOffset + info.dataSize]

    def band(self, layer: int, band: int) -> np.ndarray:
        """One band of one layer as a (height, width) uint8 view of the message."""
        image = OFbkImage(self.GetInfo(layer), self.GetData(layer), band)
        if not image.IsValid():
            raise ImageAccessError(f"layer {layer} of type {self.GetInfo(layer).type} has no band {band}")
        return image.array

    def _layer_index(self, layer) -> int:
        if not _is_index(layer, self.numData):
            raise ImageAccessError(f"layer {layer!r} not in 0..{self.numData - 1}")
        return int(layer)


def _check_layer(layer: int, info: OFbkImageInfo, data_start: int, size: int) -> None:
    if info.type not in BAND_RUNS:
        raise MessageFormatError(f"layer {layer}: type code {info.type}, expected 19, 20 or 24")
    if info.width == 0 or info.height == 0:
        raise MessageFormatError(f"layer {layer}: empty image {info.width}x{info.height}")
    needed = BAND_RUNS[info.type][1] * info.width * info.height
    if info.dataSize < needed:
        raise MessageFormatError(f"layer {layer}: dataSize {info.dataSize} < {needed} for {info.width}x{info.height}")
    if info.dataOffset < data_start or info.dataOffset + info.dataSize > size:
        raise MessageFormatError(
            f"layer {layer}: data [{info.dataOffset}, {info.dataOffset + info.dataSize}) outside [{data_start}, {size})"
        )


class OFbkImage:
    """One band of one layer, as Sony's ``OFbkImage(info, data, band)``.

    ``data`` is the layer as ``GetData`` returns it. For a band the layer type does not
    have, the image is invalid (``IsValid()`` is False), as in OPEN-R.
    """

    def __init__(self, info: OFbkImageInfo, data: np.ndarray, band: int):
        self._width = info.width
        self._height = info.height
        runs, runs_per_row = BAND_RUNS.get(info.type, ({}, 1))
        self._skip = (runs_per_row - 1) * info.width
        self._array = None
        if band in runs:
            rows = np.asarray(data, np.uint8)[: runs_per_row * info.width * info.height]
            if rows.size != runs_per_row * info.width * info.height:
                raise ImageAccessError(f"{rows.size} bytes of data, too few for the layer {info}")
            self._array = rows.reshape(info.height, runs_per_row, info.width)[:, runs[band], :]

    def IsValid(self) -> bool:
        """Whether the layer has this band."""
        return self._array is not None

    def Width(self) -> int:
        """Band width in pixels."""
        return self._width

    def Height(self) -> int:
        """Band height in pixels."""
        return self._height

    def Skip(self) -> int:
        """Bytes from the end of a row of the band to the start of its next row."""
        return self._skip

    def Pixel(self, x: int, y: int) -> int:
        """``image_[(W + skip) * y + x]``, with (0, 0) the top-left pixel."""
        if not (_is_index(x, self._width) and _is_index(y, self._height)):
            raise ImageAccessError(f"pixel ({x}, {y}) outside {self._width}x{self._height}")
        return int(self.array[y, x])

    def FieldCounter(self) -> int:
        """The frame counter the last row's tag carries (its first two bytes, little-endian)."""
        tag = self._tag()
        return int(tag[0]) | int(tag[1]) << 8

    def ColorFrequency(self, chan: int) -> int:
        """The tag's pixel count / 16 for a channel mask ``ocdtCHANNELk``."""
        if chan not in [1 << k for k in range(8)]:
            raise ImageAccessError(f"channel mask {chan!r} is not one of ocdtCHANNEL0..7")
        k = int(chan).bit_length() - 1
        return int(self._tag()[8 + k if k < 4 else k])

    def _tag(self) -> np.ndarray:
        last_row = self.array[-1]
        if last_row.size < TAG_LENGTH:
            raise ImageAccessError(f"a band {last_row.size} pixels wide has no room for the {TAG_LENGTH}-byte tag")
        return last_row

    @property
    def array(self) -> np.ndarray:
        """The band as a (height, width) uint8 view of the message."""
        if self._array is None:
            raise ImageAccessError("invalid OFbkImage: the layer type has no such band")
        return self._array


def _is_index(value, length: int) -> bool:
    return isinstance(value, (int, np.integer)) and 0 <= value < length


def restore_tag_pixels(band: np.ndarray) -> np.ndarray:
    """A copy of a (height, width) band whose tag pixels repeat the row above.

    Tekkotsu's ``restore_image`` copies 16 pixels; this copies the ``TAG_LENGTH`` = 12 that
    the tag occupies, so pixels 12-15 keep their own values.
    """
    if band.ndim != 2 or band.shape[0] < 2:
        raise ImageAccessError(f"a band of shape {band.shape} has no row above its last")
    restored = np.array(band, copy=True)
    restored[-1, :TAG_LENGTH] = restored[-2, :TAG_LENGTH]
    return restored
