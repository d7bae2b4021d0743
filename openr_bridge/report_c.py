"""The report's C decoding, compiled at run time: the reference for tests and benchmarks.

``REPORT_C_SOURCE`` holds the report's ``YCrCb2RGB`` (section 3.2.4), operation for
operation, and the loop of its ``camera_get_image`` over an HPF layer, with ``OFbkImage``'s
accessor ``image_[(W + skip) * y + x]``; all ``static`` in one file, so the compiler may
inline them as it would in the wrapper's translation unit. ``compile_report_c`` builds it with the system C
compiler at ``-O2``, adding ``-ffp-contract=off`` so that no multiply-add is fused and every
double operation is rounded as the source (and numpy) rounds it.
"""

import ctypes
import shutil
import subprocess
from pathlib import Path

import numpy as np

REPORT_C_SOURCE = r"""
#include <time.h>

typedef unsigned char byte;
typedef signed char sbyte;

static void YCrCb2RGB(byte y, byte cr, byte cb, byte* r, byte* g, byte* b) {
    double Y, Cr, Cb, R, G, B;
    sbyte scr = (sbyte)(cr ^ 0x80);
    sbyte scb = (sbyte)(cb ^ 0x80);
    Y = (double)y / 255.0;
    Cr = (double)scr / 128.0;
    Cb = (double)scb / 128.0;
    R = 255.0*(Y + Cr);
    G = 255.0*(Y - 0.51*Cr - 0.19*Cb);
    B = 255.0*(Y + Cb);
    if (R > 255.0) { *r = 255; } else if (R < 0.0) { *r = 0; } else { *r = (byte)R; }
    if (G > 255.0) { *g = 255; } else if (G < 0.0) { *g = 0; } else { *g = (byte)G; }
    if (B > 255.0) { *b = 255; } else if (B < 0.0) { *b = 0; } else { *b = (byte)B; }
}

typedef struct { const byte* image_; int width_; int height_; int skip_; } OFbkImage;

static byte Pixel(const OFbkImage* image, int x, int y) {
    return image->image_[(image->width_ + image->skip_) * y + x];
}

/* camera_get_image's loop over an HPF layer (rows Y, Cr, Cb, Y_LH, Y_HL, Y_HH). */
static void decode_layer_h(const byte* data, int w, int h, byte* VectorImage) {
    OFbkImage yImage = {data, w, h, 5 * w};
    OFbkImage crImage = {data + w, w, h, 5 * w};
    OFbkImage cbImage = {data + 2 * w, w, h, 5 * w};
    enum { B_PIXEL = 0, G_PIXEL = 1, R_PIXEL = 2 };
    byte pixel[3];
    int f = 0;
    for (int y = 0; y < h; y++) {
        for (int x = 0; x < w; x++) {
            YCrCb2RGB(Pixel(&yImage, x, y), Pixel(&crImage, x, y), Pixel(&cbImage, x, y),
                      &pixel[R_PIXEL], &pixel[G_PIXEL], &pixel[B_PIXEL]);
            VectorImage[f] = pixel[R_PIXEL];
            VectorImage[f + 1] = pixel[G_PIXEL];
            VectorImage[f + 2] = pixel[B_PIXEL];
            f = f + 3;
        }
    }
}

void camera_get_image(const byte* data, int w, int h, byte* VectorImage) {
    decode_layer_h(data, w, h, VectorImage);
}

double seconds_per_image(const byte* data, int w, int h, byte* VectorImage, int iterations) {
    struct timespec start, end;
    clock_gettime(CLOCK_MONOTONIC, &start);
    for (int i = 0; i < iterations; i++) decode_layer_h(data, w, h, VectorImage);
    clock_gettime(CLOCK_MONOTONIC, &end);
    return ((end.tv_sec - start.tv_sec) + 1e-9 * (end.tv_nsec - start.tv_nsec)) / iterations;
}

/* YCrCb2RGB of every (Y, Cr, Cb) with Y in [y_first, y_first + y_count), RGB in index order. */
void all_inputs(int y_first, int y_count, byte* out) {
    long k = 0;
    for (int y = y_first; y < y_first + y_count; y++)
        for (int cr = 0; cr < 256; cr++)
            for (int cb = 0; cb < 256; cb++, k += 3)
                YCrCb2RGB(y, cr, cb, &out[k], &out[k + 1], &out[k + 2]);
}
"""

_POINTER = ctypes.c_void_p


class ReportC:
    """The compiled reference."""

    def __init__(self, library: Path):
        self._lib = ctypes.CDLL(str(library))
        self._lib.camera_get_image.argtypes = [_POINTER, ctypes.c_int, ctypes.c_int, _POINTER]
        self._lib.seconds_per_image.argtypes = [_POINTER, ctypes.c_int, ctypes.c_int, _POINTER, ctypes.c_int]
        self._lib.seconds_per_image.restype = ctypes.c_double
        self._lib.all_inputs.argtypes = [ctypes.c_int, ctypes.c_int, _POINTER]

    def camera_get_image(self, layer: np.ndarray) -> np.ndarray:
        """The report's RGB bytes of a (h, 6, w) HPF layer."""
        layer = np.ascontiguousarray(layer, np.uint8)
        height, _, width = layer.shape
        out = np.empty(height * width * 3, np.uint8)
        self._lib.camera_get_image(layer.ctypes.data, width, height, out.ctypes.data)
        return out

    def seconds_per_image(self, layer: np.ndarray, iterations: int) -> float:
        """Mean time of camera_get_image's loop, measured in C."""
        layer = np.ascontiguousarray(layer, np.uint8)
        height, _, width = layer.shape
        out = np.empty(height * width * 3, np.uint8)
        return self._lib.seconds_per_image(layer.ctypes.data, width, height, out.ctypes.data, iterations)

    def all_inputs(self, y_first: int, y_count: int) -> np.ndarray:
        """(y_count, 256, 256, 3) uint8: YCrCb2RGB of every input with Y from y_first."""
        out = np.empty((y_count, 256, 256, 3), np.uint8)
        self._lib.all_inputs(y_first, y_count, out.ctypes.data)
        return out


def compile_report_c(directory) -> ReportC | None:
    """Build the reference in ``directory``; None when there is no C compiler."""
    compiler = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
    if compiler is None:
        return None
    source = Path(directory) / "report_camera.c"
    library = Path(directory) / "report_camera.so"
    source.write_text(REPORT_C_SOURCE)
    flags = ["-O2", "-ffp-contract=off", "-shared", "-fPIC"]
    subprocess.run([compiler, *flags, "-o", str(library), str(source)], check=True, capture_output=True)
    return ReportC(library)
