// SoundProbe: plays a 1 kHz tone through the speaker, ten 32 ms vectors of 16 kHz 16-bit samples
// from two regions, from t = 0 (aibo-sim's runtime tests read the recorded sound). As Sony's
// SoundPlay: both regions filled in DoStart, then on each ready the one the speaker gave back.
// Design data SOUNDPROBE_MODE "wait": the third vector waits WAIT frames (its vectorInfo's wait).
#ifndef SoundProbe_h_DEFINED
#define SoundProbe_h_DEFINED

#include <OPENR/OObject.h>
#include <OPENR/OSubject.h>
#include <OPENR/OObserver.h>
#include "def.h"

class SoundProbe : public OObject {
public:
    SoundProbe() : started(false), waits(false), sent(0), readies(0) {}
    OSubject*  subject[numOfSubject];
    OObserver* observer[numOfObserver];
    virtual OStatus DoInit(const OSystemEvent& event);
    virtual OStatus DoStart(const OSystemEvent& event);
    void Ready(const OReadyEvent& event);

private:
    void Send();

    static const int VECTORS = 10;
    static const int SAMPLES = 512;  // 32 ms at 16 kHz
    static const int WAIT = 10;
    OPrimitiveID speaker;
    RCRegion*    region[2];
    bool         started;
    bool         waits;
    int          sent;
    int          readies;
};

#endif
