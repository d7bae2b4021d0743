"""Decode and encode speed of the OPEN-R camera path.

Decode: the wrapper's ``camera_get_image`` (layer H, 208x160, to RGB) against the report's
per-pixel loop compiled as C with ``cc -O2`` in the same run, on the same messages: a
synthetic field scene, colour noise (the worst case for the table lookup), and random
bytes (the worst case for the C loop's branches). Encode: 416x320 and 208x160 RGB frames
to ``OFbkImageVectorData``. Each time is the best of 5 means over many runs.

    python -m benchmarks.decode
"""

import tempfile
from functools import partial

import numpy as np

from openr_bridge import FULL_HEIGHT, FULL_WIDTH, LAYER_SIZE, OpenRSystem, encode_frame, ofbkimageLAYER_H
from openr_bridge.report_c import compile_report_c

from .common import REPEATS, best_mean_seconds, row

WIDTH, HEIGHT = LAYER_SIZE[ofbkimageLAYER_H]  # layer H


def field_scene(height: int = 320, width: int = 416) -> np.ndarray:
    """Sky over green carpet, a white line and an orange ball, with a little shading."""
    y, x = np.mgrid[0:height, 0:width]
    frame = np.zeros((height, width, 3), np.float64)
    horizon = height * 0.35
    frame[y < horizon] = (150, 180, 230)
    frame[y >= horizon] = (40, 140, 60)
    frame[np.abs(y - 0.75 * height) < height * 0.02] = (245, 245, 245)
    ball = (x - 0.6 * width) ** 2 + (y - 0.6 * height) ** 2 < (0.12 * height) ** 2
    frame[ball] = (255, 120, 20)
    frame *= (0.75 + 0.25 * (1 - y / height))[..., np.newaxis]
    return frame.astype(np.uint8)


def decode_cases() -> dict:
    """Messages whose layer H is a field scene, colour noise, and uniformly random bytes."""
    rng = np.random.default_rng(0)
    random_bytes = encode_frame(np.zeros((HEIGHT, WIDTH, 3), np.uint8))
    random_bytes.GetData(ofbkimageLAYER_H)[:] = rng.integers(0, 256, HEIGHT * 6 * WIDTH, dtype=np.uint8)
    return {
        "scene": encode_frame(field_scene()),
        "noise": encode_frame(rng.integers(0, 256, (HEIGHT, WIDTH, 3), dtype=np.uint8)),
        "random bytes": random_bytes,
    }


def measure() -> list[dict]:
    rows = []
    with tempfile.TemporaryDirectory() as directory:
        report_c = compile_report_c(directory)
        for name, message in decode_cases().items():
            system = OpenRSystem.from_memory_stick()
            system.robot_comm.publish_image(message)
            python_s = best_mean_seconds(system.controller.camera_get_image, 300)
            reference, ratio = None, None
            if report_c is not None:
                layer_h = message.GetData(ofbkimageLAYER_H).reshape(HEIGHT, 6, WIDTH)
                c_s = min(report_c.seconds_per_image(layer_h, 300) for _ in range(REPEATS))
                reference = f"report C loop, cc -O2 ({name})"
                ratio = c_s / python_s
                rows.append(row(reference, c_s * 1e6, "us"))
            rows.append(
                row(
                    f"camera_get_image, layer H to RGB ({name})",
                    python_s * 1e6,
                    "us",
                    reference,
                    ratio,
                    target=("ratio", ">=", 1) if report_c is not None else None,
                )
            )
    for height, width in [(FULL_HEIGHT, FULL_WIDTH), (HEIGHT, WIDTH)]:
        seconds = best_mean_seconds(partial(encode_frame, field_scene(height, width)), 30)
        rows.append(row(f"encode_frame {width}x{height} RGB to OFbkImageVectorData", seconds * 1e3, "ms"))
    return rows


if __name__ == "__main__":
    for entry in measure():
        ratio = "" if entry["ratio"] is None else f"  {entry['ratio']:.2f}x vs {entry['reference']}"
        print(f"{entry['name']:<58} {entry['value']:9.1f} {entry['unit']}{ratio}")
