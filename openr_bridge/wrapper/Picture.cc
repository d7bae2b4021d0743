/*
 * Picture.cc: PNG and JPEG files of a camera image (see Picture.h). The JPEG follows ITU T.81:
 * its Annex K's quantisation and Huffman tables, a float DCT, one scan of 8x8 blocks, Y Cb Cr.
 */
#include <math.h>
#include "Picture.h"

namespace wrapper {
namespace {

void PutBigEndian(std::vector<byte>* out, unsigned long value, int bytes) {
    for (int shift = 8 * (bytes - 1); shift >= 0; shift -= 8) out->push_back((byte)((value >> shift) & 0xFF));
}

/* ---- PNG */

unsigned long Crc32(const byte* data, size_t size) {
    static unsigned long table[256];
    if (table[1] == 0) {
        for (unsigned long n = 0; n < 256; n++) {
            unsigned long c = n;
            for (int k = 0; k < 8; k++) c = (c & 1) ? 0xEDB88320UL ^ (c >> 1) : c >> 1;
            table[n] = c;
        }
    }
    unsigned long crc = 0xFFFFFFFFUL;
    for (size_t i = 0; i < size; i++) crc = table[(crc ^ data[i]) & 0xFF] ^ (crc >> 8);
    return crc ^ 0xFFFFFFFFUL;
}

void PutChunk(std::vector<byte>* png, const char* type, const std::vector<byte>& data) {
    PutBigEndian(png, data.size(), 4);
    size_t start = png->size();
    png->insert(png->end(), type, type + 4);
    png->insert(png->end(), data.begin(), data.end());
    PutBigEndian(png, Crc32(&(*png)[start], png->size() - start), 4);
}

/* ---- JPEG */

const byte ZIGZAG[64] = {0,  1,  8,  16, 9,  2,  3,  10, 17, 24, 32, 25, 18, 11, 4,  5,  12, 19, 26, 33, 40, 48,
                         41, 34, 27, 20, 13, 6,  7,  14, 21, 28, 35, 42, 49, 56, 57, 50, 43, 36, 29, 22, 15, 23,
                         30, 37, 44, 51, 58, 59, 52, 45, 38, 31, 39, 46, 53, 60, 61, 54, 47, 55, 62, 63};

/* Annex K.1, in the blocks' natural order. */
const byte LUMINANCE_Q[64] = {16, 11, 10, 16, 24,  40,  51,  61,  12, 12, 14, 19, 26,  58,  60,  55,
                              14, 13, 16, 24, 40,  57,  69,  56,  14, 17, 22, 29, 51,  87,  80,  62,
                              18, 22, 37, 56, 68,  109, 103, 77,  24, 35, 55, 64, 81,  104, 113, 92,
                              49, 64, 78, 87, 103, 121, 120, 101, 72, 92, 95, 98, 112, 100, 103, 99};
const byte CHROMINANCE_Q[64] = {17, 18, 24, 47, 99, 99, 99, 99, 18, 21, 26, 66, 99, 99, 99, 99,
                                24, 26, 56, 99, 99, 99, 99, 99, 47, 66, 99, 99, 99, 99, 99, 99,
                                99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99,
                                99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99};

/* Annex K.3: the number of codes of each length 1-16, then the symbols in code order. */
const byte DC_LUMINANCE[16 + 12] = {0, 1, 5, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0,
                                    0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
const byte DC_CHROMINANCE[16 + 12] = {0, 3, 1, 1, 1, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0,
                                      0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
const byte AC_LUMINANCE[16 + 162] = {
    0,    2,    1,    3,    3,    2,    4,    3,    5,    5,    4,    4,    0,    0,    1,    0x7d,
    0x01, 0x02, 0x03, 0x00, 0x04, 0x11, 0x05, 0x12, 0x21, 0x31, 0x41, 0x06, 0x13, 0x51, 0x61, 0x07,
    0x22, 0x71, 0x14, 0x32, 0x81, 0x91, 0xa1, 0x08, 0x23, 0x42, 0xb1, 0xc1, 0x15, 0x52, 0xd1, 0xf0,
    0x24, 0x33, 0x62, 0x72, 0x82, 0x09, 0x0a, 0x16, 0x17, 0x18, 0x19, 0x1a, 0x25, 0x26, 0x27, 0x28,
    0x29, 0x2a, 0x34, 0x35, 0x36, 0x37, 0x38, 0x39, 0x3a, 0x43, 0x44, 0x45, 0x46, 0x47, 0x48, 0x49,
    0x4a, 0x53, 0x54, 0x55, 0x56, 0x57, 0x58, 0x59, 0x5a, 0x63, 0x64, 0x65, 0x66, 0x67, 0x68, 0x69,
    0x6a, 0x73, 0x74, 0x75, 0x76, 0x77, 0x78, 0x79, 0x7a, 0x83, 0x84, 0x85, 0x86, 0x87, 0x88, 0x89,
    0x8a, 0x92, 0x93, 0x94, 0x95, 0x96, 0x97, 0x98, 0x99, 0x9a, 0xa2, 0xa3, 0xa4, 0xa5, 0xa6, 0xa7,
    0xa8, 0xa9, 0xaa, 0xb2, 0xb3, 0xb4, 0xb5, 0xb6, 0xb7, 0xb8, 0xb9, 0xba, 0xc2, 0xc3, 0xc4, 0xc5,
    0xc6, 0xc7, 0xc8, 0xc9, 0xca, 0xd2, 0xd3, 0xd4, 0xd5, 0xd6, 0xd7, 0xd8, 0xd9, 0xda, 0xe1, 0xe2,
    0xe3, 0xe4, 0xe5, 0xe6, 0xe7, 0xe8, 0xe9, 0xea, 0xf1, 0xf2, 0xf3, 0xf4, 0xf5, 0xf6, 0xf7, 0xf8,
    0xf9, 0xfa};
const byte AC_CHROMINANCE[16 + 162] = {
    0,    2,    1,    2,    4,    4,    3,    4,    7,    5,    4,    4,    0,    1,    2,    0x77,
    0x00, 0x01, 0x02, 0x03, 0x11, 0x04, 0x05, 0x21, 0x31, 0x06, 0x12, 0x41, 0x51, 0x07, 0x61, 0x71,
    0x13, 0x22, 0x32, 0x81, 0x08, 0x14, 0x42, 0x91, 0xa1, 0xb1, 0xc1, 0x09, 0x23, 0x33, 0x52, 0xf0,
    0x15, 0x62, 0x72, 0xd1, 0x0a, 0x16, 0x24, 0x34, 0xe1, 0x25, 0xf1, 0x17, 0x18, 0x19, 0x1a, 0x26,
    0x27, 0x28, 0x29, 0x2a, 0x35, 0x36, 0x37, 0x38, 0x39, 0x3a, 0x43, 0x44, 0x45, 0x46, 0x47, 0x48,
    0x49, 0x4a, 0x53, 0x54, 0x55, 0x56, 0x57, 0x58, 0x59, 0x5a, 0x63, 0x64, 0x65, 0x66, 0x67, 0x68,
    0x69, 0x6a, 0x73, 0x74, 0x75, 0x76, 0x77, 0x78, 0x79, 0x7a, 0x82, 0x83, 0x84, 0x85, 0x86, 0x87,
    0x88, 0x89, 0x8a, 0x92, 0x93, 0x94, 0x95, 0x96, 0x97, 0x98, 0x99, 0x9a, 0xa2, 0xa3, 0xa4, 0xa5,
    0xa6, 0xa7, 0xa8, 0xa9, 0xaa, 0xb2, 0xb3, 0xb4, 0xb5, 0xb6, 0xb7, 0xb8, 0xb9, 0xba, 0xc2, 0xc3,
    0xc4, 0xc5, 0xc6, 0xc7, 0xc8, 0xc9, 0xca, 0xd2, 0xd3, 0xd4, 0xd5, 0xd6, 0xd7, 0xd8, 0xd9, 0xda,
    0xe2, 0xe3, 0xe4, 0xe5, 0xe6, 0xe7, 0xe8, 0xe9, 0xea, 0xf2, 0xf3, 0xf4, 0xf5, 0xf6, 0xf7, 0xf8,
    0xf9, 0xfa};

/* A Huffman table's code and length of each symbol (Annex C's canonical codes). */
struct Huffman {
    unsigned short code[256];
    byte length[256];
    explicit Huffman(const byte* table) {
        for (int i = 0; i < 256; i++) length[i] = 0;
        unsigned short next = 0;
        const byte* symbol = table + 16;
        for (int bits = 1; bits <= 16; bits++, next <<= 1) {
            for (int n = 0; n < table[bits - 1]; n++, next++, symbol++) {
                code[*symbol] = next;
                length[*symbol] = (byte)bits;
            }
        }
    }
};

class BitWriter {
public:
    explicit BitWriter(std::vector<byte>* out) : out_(out), bits_(0), count_(0) {}
    void Put(unsigned long value, int size) {
        for (int i = size - 1; i >= 0; i--) {
            bits_ = (bits_ << 1) | ((value >> i) & 1);
            if (++count_ == 8) Flush();
        }
    }
    void Finish() {  /* the last byte filled with ones */
        while (count_ != 0) Put(1, 1);
    }

private:
    void Flush() {
        out_->push_back((byte)bits_);
        if (bits_ == 0xFF) out_->push_back(0);  /* stuffed: no marker inside the data */
        bits_ = 0;
        count_ = 0;
    }
    std::vector<byte>* out_;
    unsigned bits_;
    int count_;
};

int Category(int value) {
    int magnitude = value < 0 ? -value : value, size = 0;
    while (magnitude) {
        size++;
        magnitude >>= 1;
    }
    return size;
}

/* A value of `size` bits as JPEG stores it: negative ones as value - 1 in those bits. */
unsigned long Amplitude(int value, int size) {
    return (unsigned long)(value < 0 ? value - 1 : value) & ((1UL << size) - 1);
}

void EncodeBlock(BitWriter* bits, const double* samples, const byte* quant, const Huffman& dc, const Huffman& ac,
                 int* previousDc) {
    static double cosines[8][8];  /* C(u)/2 cos((2x + 1) u pi / 16) */
    if (cosines[0][0] == 0) {
        for (int u = 0; u < 8; u++) {
            for (int x = 0; x < 8; x++) cosines[u][x] = (u ? 0.5 : 0.5 / sqrt(2.0)) * cos((2 * x + 1) * u * M_PI / 16);
        }
    }
    int coefficients[64];
    for (int v = 0; v < 8; v++) {
        for (int u = 0; u < 8; u++) {
            double sum = 0;
            for (int y = 0; y < 8; y++) {
                for (int x = 0; x < 8; x++) sum += samples[y * 8 + x] * cosines[u][x] * cosines[v][y];
            }
            double q = sum / quant[v * 8 + u];  /* rounded half away from zero, as libjpeg: white's 63.5 */
            coefficients[v * 8 + u] = (int)(q < 0 ? -floor(-q + 0.5 + 1e-6) : floor(q + 0.5 + 1e-6));
        }
    }
    int difference = coefficients[0] - *previousDc, size = Category(difference);
    *previousDc = coefficients[0];
    bits->Put(dc.code[size], dc.length[size]);
    bits->Put(Amplitude(difference, size), size);
    int run = 0;
    for (int k = 1; k < 64; k++) {
        int value = coefficients[ZIGZAG[k]];
        if (value == 0) {
            run++;
            continue;
        }
        for (; run > 15; run -= 16) bits->Put(ac.code[0xF0], ac.length[0xF0]);  /* sixteen zeros */
        size = Category(value);
        bits->Put(ac.code[run << 4 | size], ac.length[run << 4 | size]);
        bits->Put(Amplitude(value, size), size);
        run = 0;
    }
    if (run) bits->Put(ac.code[0], ac.length[0]);  /* the end of the block */
}

void PutSegment(std::vector<byte>* jpeg, byte marker, const std::vector<byte>& data) {
    jpeg->push_back(0xFF);
    jpeg->push_back(marker);
    PutBigEndian(jpeg, data.size() + 2, 2);
    jpeg->insert(jpeg->end(), data.begin(), data.end());
}

}  // namespace

std::vector<byte> Png(const byte* rgb, int width, int height) {
    std::vector<byte> rows;
    for (int y = 0; y < height; y++) {
        rows.push_back(0);  /* no filter */
        rows.insert(rows.end(), rgb + (size_t)y * width * 3, rgb + (size_t)(y + 1) * width * 3);
    }
    std::vector<byte> zlib;
    zlib.push_back(0x78);  /* deflate, 32 kB window; with the next byte a multiple of 31 */
    zlib.push_back(0x01);
    unsigned long a = 1, b = 0;
    for (size_t at = 0; at < rows.size();) {
        size_t size = rows.size() - at < 65535 ? rows.size() - at : 65535;
        zlib.push_back(at + size == rows.size() ? 1 : 0);  /* the last block, stored */
        zlib.push_back((byte)(size & 0xFF));
        zlib.push_back((byte)(size >> 8));
        zlib.push_back((byte)(~size & 0xFF));
        zlib.push_back((byte)((~size >> 8) & 0xFF));
        for (size_t i = at; i < at + size; i++) {
            a = (a + rows[i]) % 65521;
            b = (b + a) % 65521;
        }
        zlib.insert(zlib.end(), rows.begin() + at, rows.begin() + at + size);
        at += size;
    }
    PutBigEndian(&zlib, (b << 16) | a, 4);
    std::vector<byte> header;
    PutBigEndian(&header, width, 4);
    PutBigEndian(&header, height, 4);
    const byte format[] = {8, 2, 0, 0, 0};  /* 8 bits, RGB, deflate, adaptive filters, not interlaced */
    header.insert(header.end(), format, format + 5);
    const byte signature[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    std::vector<byte> png(signature, signature + 8);
    PutChunk(&png, "IHDR", header);
    PutChunk(&png, "IDAT", zlib);
    PutChunk(&png, "IEND", std::vector<byte>());
    return png;
}

std::vector<byte> Jpeg(const byte* rgb, int width, int height, int quality) {
    int scale = quality < 50 ? 5000 / quality : 200 - 2 * quality;
    byte quant[2][64];
    const byte* const bases[2] = {LUMINANCE_Q, CHROMINANCE_Q};
    std::vector<byte> tables;
    for (int t = 0; t < 2; t++) {
        tables.push_back((byte)t);  /* 8-bit entries, table t */
        for (int i = 0; i < 64; i++) {
            int q = (bases[t][i] * scale + 50) / 100;
            quant[t][i] = (byte)(q < 1 ? 1 : q > 255 ? 255 : q);
        }
        for (int k = 0; k < 64; k++) tables.push_back(quant[t][ZIGZAG[k]]);
    }
    const byte app0[] = {'J', 'F', 'I', 'F', 0, 1, 1, 0, 0, 1, 0, 1, 0, 0};  /* version 1.1, no units, 1:1 */
    std::vector<byte> frame;
    frame.push_back(8);
    PutBigEndian(&frame, height, 2);
    PutBigEndian(&frame, width, 2);
    frame.push_back(3);
    for (int c = 0; c < 3; c++) {  /* Y, Cb, Cr: not subsampled; Y quantised by table 0, the others by 1 */
        frame.push_back((byte)(c + 1));
        frame.push_back(0x11);
        frame.push_back(c ? 1 : 0);
    }
    std::vector<byte> huffman;
    const byte* const specs[4] = {DC_LUMINANCE, AC_LUMINANCE, DC_CHROMINANCE, AC_CHROMINANCE};
    const byte classes[4] = {0x00, 0x10, 0x01, 0x11};
    for (int t = 0; t < 4; t++) {
        int symbols = 0;
        for (int i = 0; i < 16; i++) symbols += specs[t][i];
        huffman.push_back(classes[t]);
        huffman.insert(huffman.end(), specs[t], specs[t] + 16 + symbols);
    }
    const byte scan[] = {3, 1, 0x00, 2, 0x11, 3, 0x11, 0, 63, 0};
    std::vector<byte> jpeg;
    jpeg.push_back(0xFF);
    jpeg.push_back(0xD8);
    PutSegment(&jpeg, 0xE0, std::vector<byte>(app0, app0 + sizeof app0));
    PutSegment(&jpeg, 0xDB, tables);
    PutSegment(&jpeg, 0xC0, frame);
    PutSegment(&jpeg, 0xC4, huffman);
    PutSegment(&jpeg, 0xDA, std::vector<byte>(scan, scan + sizeof scan));
    const Huffman dc[2] = {Huffman(DC_LUMINANCE), Huffman(DC_CHROMINANCE)};
    const Huffman ac[2] = {Huffman(AC_LUMINANCE), Huffman(AC_CHROMINANCE)};
    BitWriter bits(&jpeg);
    int previousDc[3] = {0, 0, 0};
    double block[3][64];
    for (int top = 0; top < height; top += 8) {
        for (int left = 0; left < width; left += 8) {
            for (int i = 0; i < 64; i++) {  /* past the image's edge, its last row and column again */
                int x = left + i % 8, y = top + i / 8;
                const byte* p = rgb + 3 * ((size_t)(y < height ? y : height - 1) * width + (x < width ? x : width - 1));
                block[0][i] = 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2] - 128;
                block[1][i] = -0.168736 * p[0] - 0.331264 * p[1] + 0.5 * p[2];
                block[2][i] = 0.5 * p[0] - 0.418688 * p[1] - 0.081312 * p[2];
            }
            for (int c = 0; c < 3; c++) EncodeBlock(&bits, block[c], quant[c ? 1 : 0], dc[c ? 1 : 0], ac[c ? 1 : 0],
                                                    &previousDc[c]);
        }
    }
    bits.Finish();
    jpeg.push_back(0xFF);
    jpeg.push_back(0xD9);
    return jpeg;
}

}  // namespace wrapper
