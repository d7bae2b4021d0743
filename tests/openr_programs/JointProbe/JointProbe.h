// JointProbe: drives the head pan through the effector, six 4-frame command vectors from two
// regions, and prints what OPEN-R tells it (aibo-sim's runtime tests read its console).
// /MS/OPEN-R/MW/DATA/P/MODE.TXT (design data JOINTPROBE_MODE) may hold "nopower" (no
// SetMotorPower), "nogain" (no joint gain) or "wait" (the third vector waits WAIT frames).
#ifndef JointProbe_h_DEFINED
#define JointProbe_h_DEFINED

#include <OPENR/OObject.h>
#include <OPENR/OSubject.h>
#include <OPENR/OObserver.h>
#include "def.h"

class JointProbe : public OObject {
public:
    JointProbe();
    OSubject*  subject[numOfSubject];
    OObserver* observer[numOfObserver];

    virtual OStatus DoInit(const OSystemEvent& event);
    virtual OStatus DoStart(const OSystemEvent& event);
    void Ready(const OReadyEvent& event);
    void NotifySensor(const ONotifyEvent& event);

private:
    void Send(int vector);

    static const int VECTORS = 6;
    static const int FRAMES = 4;
    static const int WAIT = 25;
    OPrimitiveID pan;
    RCRegion*    region[2];
    bool         started;
    bool         waits;
    int          sent;
    int          sensorIndex;
};

#endif
