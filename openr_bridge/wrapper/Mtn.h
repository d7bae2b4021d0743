/*
 * Mtn.h: OPEN-R motion files ("OMTN" 1.0-1.2) for the wrapper's mtn_* functions, a C++ port of
 * aibo_sim/mtn.py (its reader, its checks and messages, its OPEN-R playback and its info text).
 * Bytes are read one by one (little-endian, as the robot's MIPS is): no structure of the file
 * is laid over memory, so nothing here depends on the machine's word size.
 */
#ifndef AIBO_WRAPPER_MTN_H
#define AIBO_WRAPPER_MTN_H

#include <string>
#include <vector>
#include <Types.h>

namespace wrapper {

const int SUBFRAME_MS = 8;   /* OPEN-R plays a motion in 8 ms frames */
const char* const ERS7_DESIGN = "DRX-1000";  /* the robot design an ERS-7 motion names */

/* A motion: keyframes in micro-radians as stored, and its OPEN-R playback. */
struct Motion {
    std::string name, creator, design;
    std::string source;                   /* the file, as its errors name it */
    int frameTimeMs;
    std::vector<std::string> locators;
    std::vector<slongword> keyframes;     /* numKeyframes rows of locators.size() values */
    std::vector<slongword> interpolate;   /* numInterpolate of each segment k -> k+1 */
    int numKeyframes;

    double LengthMs() const;              /* the segments' (numInterpolate + 1) * frame time */
    /* For playback (frame time a multiple of 8 ms): the 8 ms frames, the last keyframe
     * included, and the values of frame `i` (locators.size() of them). */
    long NumFrames() const;
    void Frame(long i, slongword* values) const;
    void Prepare();                        /* computes what Frame reads; after a successful parse */

private:
    std::vector<long> start_;             /* the first 8 ms frame of each segment, then the total */
    std::vector<slongword> delta_;        /* per segment and joint: the step of one 8 ms frame */
};

/* Parses a file's bytes; false with `error` set to what aibo_sim.mtn.parse_mtn raises. */
bool ParseMotion(const std::vector<byte>& data, const std::string& source, Motion* motion, std::string* error);

/* `text` (latin-1) safe to print, as aibo_sim.mtn.printable shows it (UTF-8 out); `limit`
 * characters at most (0: all), with a note of the full length. */
std::string Printable(const std::string& text, size_t limit);

/* aibo_sim.mtn.another_robot: for a motion of another design, "a motion for DRX-900, the
 * ERS-210/220, not the ERS-7's DRX-1000"; "" for the ERS-7's. */
std::string AnotherRobot(const Motion& motion);

/* aibo_sim.mtn.format_motion_info: what mtn_fprint prints (without its last newline). */
std::string FormatMotionInfo(const Motion& motion);

}  // namespace wrapper

#endif
