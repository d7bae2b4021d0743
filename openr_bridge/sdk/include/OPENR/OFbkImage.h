/*
 * OFbkImage.h: one band of one layer of an OFbkImageVectorData. The constructor (in the host
 * libOPENR, as in Sony's) finds the band's first byte, the layer's width and height and the
 * skip from one row of the band to the next. The tag (field counter, colour frequencies) is in
 * the first bytes of the band's last row.
 */
#ifndef _OFbkImage_h_DEFINED
#define _OFbkImage_h_DEFINED

#include <OPENR/ODataFormats.h>

typedef longword OFbkImageBand;
const OFbkImageBand ofbkimageBAND_Y    = 0;
const OFbkImageBand ofbkimageBAND_Cr   = 1;
const OFbkImageBand ofbkimageBAND_Cb   = 2;
const OFbkImageBand ofbkimageBAND_CDT  = 3;
const OFbkImageBand ofbkimageBAND_Y_LH = 4;
const OFbkImageBand ofbkimageBAND_Y_HL = 5;
const OFbkImageBand ofbkimageBAND_Y_HH = 6;

class OFbkImage {
public:
    OFbkImage(OFbkImageInfo* info, byte* data, OFbkImageBand band);
    ~OFbkImage() {}
    OFbkImage& operator=(const OFbkImage& other) {
        image_ = other.image_;
        width_ = other.width_;
        height_ = other.height_;
        skip_ = other.skip_;
        return *this;
    }

    bool  IsValid() const { return image_ != 0; }
    byte* Pointer() const { return image_; }
    int   Width() const { return width_; }
    int   Height() const { return height_; }
    int   Skip() const { return skip_; }
    byte  Pixel(int x, int y) const { return image_[(width_ + skip_) * y + x]; }

    word FieldCounter() const {
        const byte* tag = Tag();
        return (word)((tag[1] << 8) | tag[0]);
    }
    byte ColorFrequency(OCdtChannel channel) const {
        static const OCdtChannel order[8] = {ocdtCHANNEL4, ocdtCHANNEL5, ocdtCHANNEL6, ocdtCHANNEL7,
                                             ocdtCHANNEL0, ocdtCHANNEL1, ocdtCHANNEL2, ocdtCHANNEL3};
        for (int k = 0; k < 8; k++) {
            if (order[k] == channel) return Tag()[4 + k];
        }
        return 0;
    }
    longword GetTagInfo();

private:
    const byte* Tag() const { return image_ + (width_ + skip_) * (height_ - 1); }

    byte* image_;
    int   width_;
    int   height_;
    int   skip_;
};

#endif /* _OFbkImage_h_DEFINED */
