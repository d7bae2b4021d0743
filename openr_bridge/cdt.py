"""Colour detection tables (CDT) and the C layer they produce.

``OCdtInfo`` keeps Sony's packing: ``table[s]`` covers Y in [8s, 8s + 7] and is one longword
Cr_min | Cr_max << 8 | Cb_min << 16 | Cb_max << 24, set with Sony's argument order
``Set(y_segment, cr_max, cr_min, cb_max, cb_min)``. ``OCdtVectorData`` holds up to eight
of them (``SetNumData``, ``GetInfo``).

The C layer (``cdt_layer``): bit k of a pixel is set when channel k's box for that pixel's
Y segment contains its (Cr, Cb), bounds inclusive. Choices where no source settles it:

- the hardware's tested values are taken to be the M layer's Y, Cr, Cb (the C layer has M's
  size, one CDT pixel per 2x2 H pixels);
- a segment still at ``ocdtINIT`` (0x80808080) matches nothing, as Sony's CDT viewer reads
  it as "no CDT", although as a box it would hold Cr = Cb = 128;
- the ERS-7 has channels 0-6 only: a table for channel 7 raises ``CdtError``, so bit 7 is
  never set; so do a channel mask that is not one bit and two tables for one channel.
"""

import struct

import numpy as np

from .errors import CdtError
from .image import VECTOR_INFO_SIZE, odataCDT

ocdtNUM_CHANNELS = 8
ocdtCHANNEL_UNDEF = 0x00
ocdtCHANNEL0 = 0x01
ocdtCHANNEL1 = 0x02
ocdtCHANNEL2 = 0x04
ocdtCHANNEL3 = 0x08
ocdtCHANNEL4 = 0x10
ocdtCHANNEL5 = 0x20
ocdtCHANNEL6 = 0x40
ocdtCHANNEL7 = 0x80
ocdtMAX_Y_SEGMENT = 32
ocdtINIT = 0x80808080
ERS7_CDT_CHANNELS = 7
_CDT_INFO = struct.Struct(f"<3I{ocdtMAX_Y_SEGMENT}I4x")  # OCdtInfo, 144 bytes


class OCdtInfo:
    """One channel's table: 32 Y segments, each a Cr/Cb box."""

    def __init__(self):
        self.type = 0
        self.primitiveID = 0
        self.channel = ocdtCHANNEL_UNDEF
        self.table = [0] * ocdtMAX_Y_SEGMENT

    def Init(self, prmID: int, chan: int) -> None:
        """Set up the table for primitive ``prmID`` and channel mask ``chan``, every box empty."""
        self.type = odataCDT
        self.primitiveID = prmID
        self.channel = chan
        self.table = [ocdtINIT] * ocdtMAX_Y_SEGMENT

    def Set(self, y_segment: int, cr_max: int, cr_min: int, cb_max: int, cb_min: int) -> None:
        """The Cr/Cb box of Y segment ``y_segment`` (bounds inclusive).

        :raises CdtError: the segment is not 0..31 or a bound is not 0..255.
        """
        if not 0 <= y_segment < ocdtMAX_Y_SEGMENT:
            raise CdtError(f"Y segment {y_segment} not in 0..{ocdtMAX_Y_SEGMENT - 1}")
        bounds = (cr_min, cr_max, cb_min, cb_max)
        if not all(0 <= v <= 255 for v in bounds):
            raise CdtError(f"box bounds {bounds} not bytes")
        self.table[y_segment] = cr_min | cr_max << 8 | cb_min << 16 | cb_max << 24

    def channel_index(self) -> int:
        """k for ``ocdtCHANNELk``; raises CdtError for masks the ERS-7 cannot use."""
        if self.channel not in [1 << k for k in range(ocdtNUM_CHANNELS)]:
            raise CdtError(f"channel mask {self.channel:#x} is not one of ocdtCHANNEL0..7")
        k = int(self.channel).bit_length() - 1
        if k >= ERS7_CDT_CHANNELS:
            raise CdtError(f"channel {k} is not available on the ERS-7 (channels 0-6 only)")
        return k


class OCdtVectorData:
    """Up to eight ``OCdtInfo``, of which the first ``numData`` are in use."""

    def __init__(self):
        self.numData = 0
        self.info = [OCdtInfo() for _ in range(ocdtNUM_CHANNELS)]

    def SetNumData(self, ndata: int) -> None:
        """Use the first ``ndata`` tables; CdtError unless 0..8."""
        if not 0 <= ndata <= ocdtNUM_CHANNELS:
            raise CdtError(f"numData {ndata} not in 0..{ocdtNUM_CHANNELS}")
        self.numData = ndata

    def GetInfo(self, index: int) -> OCdtInfo:
        """The table ``index`` (0..7)."""
        return self.info[index]

    @classmethod
    def from_bytes(cls, data: bytes) -> "OCdtVectorData":
        """The vector from the robot's bytes: the 192-byte header (``numData`` at 32), then eight
        144-byte ``OCdtInfo`` (type, primitiveID, channel, table[32], padding), little-endian."""
        if len(data) != VECTOR_INFO_SIZE + ocdtNUM_CHANNELS * _CDT_INFO.size:
            raise CdtError(
                f"an OCdtVectorData has {VECTOR_INFO_SIZE + ocdtNUM_CHANNELS * _CDT_INFO.size} bytes, not {len(data)}"
            )
        vector = cls()
        vector.SetNumData(struct.unpack_from("<I", data, 32)[0])
        for index, info in enumerate(vector.info):
            info.type, info.primitiveID, info.channel, *table = _CDT_INFO.unpack_from(
                data, VECTOR_INFO_SIZE + index * _CDT_INFO.size
            )
            info.table = table
        return vector

    @classmethod
    def of(cls, *infos: OCdtInfo) -> "OCdtVectorData":
        """A vector using the tables ``infos``, in order; CdtError for more than 8."""
        vector = cls()
        vector.SetNumData(len(infos))
        vector.info[: len(infos)] = infos
        return vector


def cdt_layer(y: np.ndarray, cr: np.ndarray, cb: np.ndarray, cdt: OCdtVectorData | None) -> np.ndarray:
    """The C layer for uint8 planes of one shape: bit k where channel k's box holds the pixel."""
    layer = np.zeros(y.shape, np.uint8)
    if cdt is None:
        return layer
    seen = set()
    for info in cdt.info[: cdt.numData]:
        k = info.channel_index()
        if k in seen:
            raise CdtError(f"two tables for channel {k}")
        seen.add(k)
        table = np.array(info.table, np.uint32)[y >> 3]
        inside = (
            (table != ocdtINIT)
            & (cr >= (table & 0xFF))
            & (cr <= (table >> 8 & 0xFF))
            & (cb >= (table >> 16 & 0xFF))
            & (cb <= (table >> 24))
        )
        layer |= inside.astype(np.uint8) << k
    return layer


def pink_ball_cdt(prmID: int = 0, chan: int = ocdtCHANNEL0) -> OCdtInfo:
    """Sony's sample table for the pink ball: Cr 150-230 (160-230 from segment 20), Cb 120-190."""
    info = OCdtInfo()
    info.Init(prmID, chan)
    for segment in range(ocdtMAX_Y_SEGMENT):
        info.Set(segment, 230, 150 if segment < 20 else 160, 190, 120)
    return info


def orange_ball_cdt(prmID: int = 0, chan: int = ocdtCHANNEL1) -> OCdtInfo:
    """A table for an orange ball under the forward colour model: Cr 155-200, Cb 30-95, Y >= 40.

    The oranges (255, 128, 0), (255, 100, 0), (255, 160, 40), (140, 60, 0) and
    (255, 190, 90) fall in it; red, yellow, pink, skin, brown, field green and white do not.
    """
    info = OCdtInfo()
    info.Init(prmID, chan)
    for segment in range(5, ocdtMAX_Y_SEGMENT):
        info.Set(segment, 200, 155, 95, 30)
    return info
