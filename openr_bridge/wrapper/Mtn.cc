/*
 * Mtn.cc: the OMTN reader and OPEN-R playback of aibo_sim/mtn.py, in C++ (see Mtn.h).
 */
#include <stdarg.h>
#include <stdio.h>
#include "Mtn.h"

namespace wrapper {
namespace {

const char MAGIC[] = "OMTN";
const unsigned long SECTION0_SIZE = 24;
const double MAX_LENGTH_MS = 10 * 60 * 1000;
const slongword MAX_JOINT_URAD = 6283185;   /* round(2 pi 1e6): a full turn */
const size_t NAME_LIMIT = 200;               /* characters of a file name quoted in an error */

std::string Format(const char* format, ...) {
    char text[512];
    va_list arguments;
    va_start(arguments, format);
    vsnprintf(text, sizeof text, format, arguments);
    va_end(arguments);
    return text;
}

/* A latin-1 character as UTF-8. */
void AppendLatin1(std::string* out, unsigned char c) {
    if (c < 0x80) {
        *out += (char)c;
    } else {
        *out += (char)(0xC0 | (c >> 6));
        *out += (char)(0x80 | (c & 0x3F));
    }
}

/* Whether Python's str.isprintable() holds for this latin-1 character. */
bool IsPrintable(unsigned char c) { return !(c < 0x20 || (c >= 0x7F && c <= 0xA0) || c == 0xAD); }

/* Python's escape of a character that is not printable. */
std::string Escape(unsigned char c) {
    if (c == '\t') return "\\t";
    if (c == '\n') return "\\n";
    if (c == '\r') return "\\r";
    return Format("\\x%02x", c);
}

/* Python's repr() of a str (latin-1 text) or of a bytes object. */
std::string Repr(const std::string& text, bool bytes) {
    char quote = text.find('\'') != std::string::npos && text.find('"') == std::string::npos ? '"' : '\'';
    std::string out = bytes ? "b" : "";
    out += quote;
    for (size_t i = 0; i < text.size(); i++) {
        unsigned char c = (unsigned char)text[i];
        if (c == '\\' || c == (unsigned char)quote) {
            out += '\\';
            out += (char)c;
        } else if (bytes ? (c < 0x20 || c >= 0x7F) : !IsPrintable(c)) {
            out += Escape(c);
        } else {
            AppendLatin1(&out, c);
        }
    }
    return out + quote;
}

unsigned long U16(const std::vector<byte>& d, size_t at) {
    return (unsigned long)d[at] | (unsigned long)d[at + 1] << 8;
}

unsigned long U32(const std::vector<byte>& d, size_t at) {
    return U16(d, at) | (unsigned long)d[at + 2] << 16 | (unsigned long)d[at + 3] << 24;
}

slongword S32(const std::vector<byte>& d, size_t at) { return (slongword)(longword)U32(d, at); }

/* Bounds-checked reads; the first failure is kept as the message parse_mtn raises. */
class Reader {
public:
    Reader(const std::vector<byte>& data, const std::string& source) : data_(data), source_(source) {}

    bool Fail(size_t offset, const std::string& message) {
        error_ = Printable(source_, NAME_LIMIT) + Format(": byte %lu (0x%lx): ", (unsigned long)offset,
                                                         (unsigned long)offset) + message;
        return false;
    }

    bool Need(size_t offset, size_t size, const std::string& what, size_t end) {
        if (offset + size <= end) return true;
        const char* where = end == data_.size() ? "file" : "section";
        return Fail(offset, Format("truncated: %s needs %lu bytes, the %s ends at byte %lu", what.c_str(),
                                   (unsigned long)size, where, (unsigned long)end));
    }

    /* Checks section `number`'s header at `offset` (its number field unread, as by Sony's
     * MTNFile); its end in `end`. */
    bool Section(size_t offset, unsigned long number, size_t* end) {
        if (!Need(offset, 8, Format("section %lu header", number), data_.size())) return false;
        unsigned long size = U32(data_, offset + 4);
        if (size < 8) {
            return Fail(offset + 4, Format("section %lu size %lu is less than its 8-byte header", number, size));
        }
        if (offset + size > data_.size()) {
            return Fail(offset + 4, Format("section %lu size %lu overruns the file (%lu bytes)", number, size,
                                           (unsigned long)data_.size()));
        }
        *end = offset + size;
        return true;
    }

    /* A u8-length string at `*at`, before `end`; `*at` moves past it. */
    bool String(size_t* at, const std::string& what, size_t end, std::string* text) {
        if (!Need(*at, 1, what + " length", end)) return false;
        size_t length = data_[*at];
        if (!Need(*at + 1, length, what, end)) return false;
        text->assign((const char*)&data_[*at + 1], length);
        *at += 1 + length;
        return true;
    }

    const std::string& Error() const { return error_; }

private:
    const std::vector<byte>& data_;
    const std::string& source_;
    std::string error_;
};

}  // namespace

std::string Printable(const std::string& text, size_t limit) {
    bool cut = limit > 0 && text.size() > limit;
    size_t shown = cut ? limit : text.size();
    std::string out;
    for (size_t i = 0; i < shown; i++) {
        unsigned char c = (unsigned char)text[i];
        if (IsPrintable(c)) {
            AppendLatin1(&out, c);
        } else {
            out += Escape(c);
        }
    }
    return cut ? out + Format("... (%lu characters)", (unsigned long)text.size()) : out;
}

bool ParseMotion(const std::vector<byte>& data, const std::string& source, Motion* motion, std::string* error) {
    Reader r(data, source);
    const size_t size = data.size();
    bool ok = r.Need(0, 4, "magic", size);
    if (ok && std::string((const char*)&data[0], 4) != MAGIC) {
        ok = r.Fail(0, "wrong magic " + Repr(std::string((const char*)&data[0], 4), true) + " (should be b'OMTN')");
    }
    /* Section 0's size, the section count and the version are not read, as Sony's MTNFile does
     * not: section 1 starts at byte 28. */
    size_t end0 = 4 + SECTION0_SIZE, end1 = 0, end2 = 0;
    ok = ok && r.Need(4, SECTION0_SIZE, "section 0", size);
    unsigned long numKeyframes = 0, frameTime = 0;
    if (ok) {
        numKeyframes = U16(data, 20);
        frameTime = U16(data, 22);
        if (numKeyframes == 0) {
            ok = r.Fail(20, "zero keyframes");
        } else if (frameTime == 0) {
            ok = r.Fail(22, "frame rate 0 ms");
        }
    }
    ok = ok && r.Section(end0, 1, &end1);
    size_t at = end0 + 8;
    ok = ok && r.String(&at, "motion name", end1, &motion->name) && r.String(&at, "creator", end1, &motion->creator)
         && r.String(&at, "robot design", end1, &motion->design);
    ok = ok && r.Section(end1, 2, &end2) && r.Need(end1 + 8, 2, "joint count", end2);
    unsigned long numJoints = ok ? U16(data, end1 + 8) : 0;
    if (ok && numJoints == 0) {
        ok = r.Fail(end1 + 8, "zero joints");
    } else if (ok && end1 + 10 + numJoints > end2) {
        ok = r.Fail(end1 + 8, Format("%lu joints cannot fit in section 2's %lu bytes of locators", numJoints,
                                     (unsigned long)(end2 - end1 - 10)));
    }
    motion->locators.clear();
    at = end1 + 10;
    for (unsigned long i = 0; ok && i < numJoints; i++) {
        size_t here = at;
        std::string locator;
        ok = r.String(&at, Format("locator %lu", i), end2, &locator);
        for (size_t k = 0; ok && k < motion->locators.size(); k++) {
            if (motion->locators[k] == locator) ok = r.Fail(here, "duplicate locator " + Repr(locator, false));
        }
        motion->locators.push_back(locator);
    }
    ok = ok && r.Need(end2, 12, "section 3 header", size);
    if (!ok) {
        *error = r.Error();
        return false;
    }
    unsigned long sizeField = U32(data, end2 + 4);  /* the number and the data type unread, as by MTNFile */
    const size_t words = 3 + numJoints;
    const size_t section3 = 12 + numKeyframes * 4 * words + 4 * (numKeyframes - 1);
    /* A wrong joint count shows as nonsense in the keyframes: the joints the size field fits,
     * where it differs from section 2's, are named with the error (OPEN-R never reads the field). */
    std::string hint;
    double rest = (double)sizeField - 12.0 - 4.0 * (double)(numKeyframes - 1);
    double implied = rest >= 0 ? (double)(unsigned long)(rest / (4.0 * numKeyframes)) : -1.0;
    if (rest >= 0 && implied * 4.0 * numKeyframes == rest && implied > 3 && implied - 3 != numJoints) {
        hint = Format("; section 3's size field fits %lu joints, section 2 lists %lu", (unsigned long)implied - 3,
                      numJoints);
    }
    ok = r.Need(end2, section3, Format("section 3 (%lu keyframes of %lu joints", numKeyframes, numJoints) + hint + ")",
                size);
    /* Keyframe 0, then (numInterpolate, keyframe) pairs: row k's word m is at body + (k (1 +
     * words) + m - 1) * 4, row 0 having no numInterpolate. */
    const size_t body = end2 + 12;
    motion->interpolate.assign(numKeyframes - 1, 0);
    motion->keyframes.assign(numKeyframes * numJoints, 0);
    for (unsigned long k = 1; ok && k < numKeyframes; k++) {
        slongword count = S32(data, body + (k * (1 + words)) * 4 - 4);
        if (count < 0) {
            ok = r.Fail(body + k * 4 * (1 + words) - 4, Format("negative interpolation count %ld before keyframe %lu",
                                                                  (long)count, k) + hint);
        }
        motion->interpolate[k - 1] = count;
    }
    for (unsigned long k = 0; ok && k < numKeyframes; k++) {
        for (unsigned long j = 0; j < numJoints; j++) {
            motion->keyframes[k * numJoints + j] = S32(data, body + (k * (1 + words) + 4 + j) * 4 - 4);
        }
    }
    motion->frameTimeMs = (int)frameTime;
    motion->numKeyframes = (int)numKeyframes;
    if (ok) {
        /* The limits no real motion reaches: its length, then each value within a full turn. */
        double length = motion->LengthMs();
        if (length > MAX_LENGTH_MS) {
            size_t k = 0;  /* the segment in which the motion passes the limit */
            double elapsed = ((double)motion->interpolate[0] + 1) * frameTime;
            while (elapsed <= MAX_LENGTH_MS) elapsed += ((double)motion->interpolate[++k] + 1) * frameTime;
            ok = r.Fail(body + ((k + 1) * (1 + words)) * 4 - 4,
                        Format("the motion lasts %.0f s, longer than the %.0f s a motion may last (it passes them "
                               "in segment %lu -> %lu of %lu: numInterpolate %ld of %lu ms frames)",
                               length / 1000, MAX_LENGTH_MS / 1000, (unsigned long)k, (unsigned long)k + 1,
                               (unsigned long)motion->interpolate.size(), (long)motion->interpolate[k],
                               frameTime) + hint);
        }
        for (unsigned long k = 0; ok && k < numKeyframes; k++) {
            for (unsigned long j = 0; ok && j < numJoints; j++) {
                slongword value = motion->keyframes[k * numJoints + j];
                if (value > MAX_JOINT_URAD || value < -MAX_JOINT_URAD) {
                    ok = r.Fail(body + (k * (1 + words) + 4 + j) * 4 - 4,
                                Format("keyframe %lu, ", k) + Printable(motion->locators[j], 0)
                                + Format(": %g rad is beyond a full turn", value / 1e6) + hint);
                }
            }
        }
    }
    if (!ok) {
        *error = r.Error();
        return false;
    }
    motion->source = source;
    return true;
}

double Motion::LengthMs() const {
    double length = 0;
    for (size_t k = 0; k < interpolate.size(); k++) length += ((double)interpolate[k] + 1) * frameTimeMs;
    return length;
}

void Motion::Prepare() {
    const size_t joints = locators.size();
    const long perFrame = frameTimeMs / SUBFRAME_MS;
    start_.assign(1, 0);
    delta_.assign(interpolate.size() * joints, 0);
    for (size_t k = 0; k < interpolate.size(); k++) {
        long subframes = ((long)interpolate[k] + 1) * perFrame;
        start_.push_back(start_.back() + subframes);
        for (size_t j = 0; j < joints; j++) {
            slongword difference = keyframes[(k + 1) * joints + j] - keyframes[k * joints + j];
            /* C's division, truncating toward zero, whatever the compiler's for negative values */
            slongword step = (slongword)((difference < 0 ? -difference : difference) / subframes);
            delta_[k * joints + j] = difference < 0 ? -step : step;
        }
    }
}

long Motion::NumFrames() const { return start_.back() + 1; }

void Motion::Frame(long i, slongword* values) const {
    const size_t joints = locators.size();
    size_t k = 0;
    while (k + 1 < start_.size() && start_[k + 1] <= i) k++;
    if (k + 1 >= (size_t)numKeyframes) {
        for (size_t j = 0; j < joints; j++) values[j] = keyframes[(numKeyframes - 1) * joints + j];
        return;
    }
    for (size_t j = 0; j < joints; j++) {
        values[j] = keyframes[k * joints + j] + (slongword)(i - start_[k]) * delta_[k * joints + j];
    }
}

std::string AnotherRobot(const Motion& motion) {
    if (motion.design == ERS7_DESIGN) return "";
    std::string design = Printable(motion.design, 0);
    if (motion.design == "DRX-900") design += ", the ERS-210/220";
    return "a motion for " + design + ", not the ERS-7's " + ERS7_DESIGN;
}

std::string FormatMotionInfo(const Motion& motion) {
    double length = motion.LengthMs();
    std::string text = "name:        " + Printable(motion.name, 0) + "\ncreator:     " + Printable(motion.creator, 0)
                       + "\ndesign:      " + Printable(motion.design, 0)
                       + Format("\nframe time:  %d ms\nkeyframes:   %d", motion.frameTimeMs, motion.numKeyframes)
                       + Format("\nlength:      %.0f ms (%.3f s)\njoints:      %lu", length, length / 1000,
                                (unsigned long)motion.locators.size());
    for (size_t i = 0; i < motion.locators.size(); i++) {
        text += Format("\n  %2lu ", (unsigned long)i) + Printable(motion.locators[i], 0);
    }
    return text;
}

}  // namespace wrapper
