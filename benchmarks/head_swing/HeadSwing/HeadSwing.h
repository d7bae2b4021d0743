// HeadSwing: the benchmark's OPEN-R program. It swings the head pan, 60 sin(2 pi t / 4 s) degrees,
// one set-point every 8 ms frame (4-frame command vectors from two regions), reads the head's
// angle from each sensor vector and a pixel of each camera image, as benchmarks/head_swing/head_swing.py
// does through the Webots-era API.
#ifndef HeadSwing_h_DEFINED
#define HeadSwing_h_DEFINED

#include <OPENR/OObject.h>
#include <OPENR/OSubject.h>
#include <OPENR/OObserver.h>
#include "def.h"

class HeadSwing : public OObject {
public:
    HeadSwing();
    OSubject*  subject[numOfSubject];
    OObserver* observer[numOfObserver];

    virtual OStatus DoInit(const OSystemEvent& event);
    virtual OStatus DoStart(const OSystemEvent& event);
    void Ready(const OReadyEvent& event);
    void NotifySensor(const ONotifyEvent& event);
    void NotifyImage(const ONotifyEvent& event);

private:
    void Send();

    static const int FRAMES = 4;
    OPrimitiveID pan;
    RCRegion*    region[2];
    long         frame;        // the set-points' frame count
    int          sensorIndex;
    double       panAngle;     // the newest sensor value, radians
    unsigned     pixels;       // a sum of pixels, so that the images are read
};

#endif
