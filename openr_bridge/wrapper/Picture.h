/*
 * Picture.h: a camera image as a file, for camera_save_image: a PNG or a baseline JPEG, written
 * here (the robot has no zlib and no JPEG library).
 */
#ifndef Picture_h_DEFINED
#define Picture_h_DEFINED

#include <vector>
#include <Types.h>

namespace wrapper {

/* A PNG of `rgb` (rows from the top, 3 bytes a pixel), its data in deflate's stored blocks. */
std::vector<byte> Png(const byte* rgb, int width, int height);

/* A baseline JFIF JPEG of `rgb` at `quality` 1-100 (the IJG scaling of the standard tables),
 * colour not subsampled, the standard Huffman tables. */
std::vector<byte> Jpeg(const byte* rgb, int width, int height, int quality);

}  // namespace wrapper

#endif
