"""Seeded random mutations of valid messages and config files: only OpenRError (or success) comes out."""

import random
import struct

import numpy as np
import pytest

from openr_bridge import (
    OFbkImage,
    OFbkImageVectorData,
    OObject,
    OpenRError,
    OpenRSystem,
    encode_frame,
    ofbkimageLAYER_H,
    parse_connect_cfg,
    parse_stub_cfg,
    reconstruct_luma,
)
from openr_bridge.wiring import DATA_DIR

MESSAGE_MUTATIONS = 2000
CONFIG_MUTATIONS = 1500
WORDS = [0, 1, 4, 5, 19, 20, 24, 31, 32, 192, 320, 1027, 8320, 199680, 270720, 2**31, 2**32 - 1]


@pytest.fixture(scope="module")
def valid_message() -> bytes:
    rgb = np.random.default_rng(0).integers(0, 256, (160, 208, 3), dtype=np.uint8)
    return bytes(encode_frame(rgb, frame_number=12, field_counter=3))


def mutate_message(data: bytes, rng: random.Random) -> bytes:
    buffer = bytearray(data)
    kind = rng.randrange(5)
    if kind == 0:  # flip bytes of the header and infos
        for _ in range(rng.randint(1, 4)):
            buffer[rng.randrange(320)] ^= 1 << rng.randrange(8)
    elif kind == 1:  # overwrite a header or info field with a telling value
        offset = rng.randrange(0, 320, 4)
        value = rng.choice(WORDS) + rng.choice([-1, 0, 0, 1])
        buffer[offset : offset + 4] = struct.pack("<I", value % 2**32)
    elif kind == 2:
        del buffer[rng.randrange(len(buffer)) :]
    elif kind == 3:
        buffer += bytes(rng.randrange(256) for _ in range(rng.randint(1, 64)))
    else:  # random bytes anywhere
        for _ in range(rng.randint(1, 32)):
            buffer[rng.randrange(len(buffer))] = rng.randrange(256)
    return bytes(buffer)


def use_message(data: bytes) -> None:
    """Everything a consumer does with a message."""
    message = OFbkImageVectorData(data)
    for layer in range(message.numData):
        info = message.GetInfo(layer)
        for band in range(7):
            image = OFbkImage(info, message.GetData(layer), band)
            if image.IsValid():
                image.Pixel(image.Width() - 1, image.Height() - 1)
                image.FieldCounter()
                image.ColorFrequency(1)
    system = OpenRSystem.from_memory_stick()
    system.robot_comm.publish_image(message)
    system.controller.camera_get_image()
    reconstruct_luma(message, ofbkimageLAYER_H)


@pytest.mark.slow
def test_mutated_messages_raise_only_openr_errors(valid_message):
    rng = random.Random(1)
    outcomes = {"ok": 0, "error": 0}
    for _ in range(MESSAGE_MUTATIONS):
        try:
            use_message(mutate_message(valid_message, rng))
            outcomes["ok"] += 1
        except OpenRError:
            outcomes["error"] += 1
    assert sum(outcomes.values()) == MESSAGE_MUTATIONS
    assert min(outcomes.values()) > MESSAGE_MUTATIONS // 10  # both paths exercised


TOKENS = [
    '"',
    ":",
    ".",
    ",",
    "()",
    "null",
    "S",
    "O",
    "#",
    "//",
    "\n",
    "\r",
    "\t",
    " ",
    "0",
    "-1",
    "9" * 30,
    "\x00",
    "\xe9",
]


def mutate_text(text: str, rng: random.Random) -> bytes:
    data = bytearray(text.encode())
    kind = rng.randrange(5)
    if kind == 0:
        for _ in range(rng.randint(1, 3)):
            data[rng.randrange(len(data))] = rng.randrange(256)
    elif kind == 1:
        at = rng.randrange(len(data) + 1)
        data[at:at] = rng.choice(TOKENS).encode("latin-1")
    elif kind == 2:
        at = rng.randrange(len(data))
        del data[at : at + rng.randint(1, 12)]
    elif kind == 3:
        lines = data.split(b"\n")
        line = rng.randrange(len(lines))
        lines.insert(rng.randrange(len(lines) + 1), lines[line])
        data = bytearray(b"\n".join(lines))
    else:
        del data[rng.randrange(len(data)) :]
    return bytes(data)


class Notified(OObject):
    def Notify(self, event):
        pass


def test_mutated_stub_cfg_raises_only_openr_errors():
    text = (DATA_DIR / "Controller" / "stub.cfg").read_text()
    rng = random.Random(2)
    errors = 0
    for _ in range(CONFIG_MUTATIONS):
        try:
            Notified(parse_stub_cfg(mutate_text(text, rng), "stub.cfg"))
        except OpenRError:
            errors += 1
    assert 0 < errors < CONFIG_MUTATIONS


def test_mutated_connect_cfg_raises_only_openr_errors():
    text = (DATA_DIR / "ms" / "OPEN-R" / "MW" / "CONF" / "CONNECT.CFG").read_text()
    rng = random.Random(3)
    errors = 0
    for _ in range(CONFIG_MUTATIONS):
        try:
            OpenRSystem(parse_connect_cfg(mutate_text(text, rng)))
        except OpenRError:
            errors += 1
    assert 0 < errors < CONFIG_MUTATIONS
