// Spin: never returns from its second sensor vector's handler (aibo-sim's runtime tests).
#ifndef Spin_h_DEFINED
#define Spin_h_DEFINED

#include <OPENR/OObject.h>
#include <OPENR/OSubject.h>
#include <OPENR/OObserver.h>
#include "def.h"

class Spin : public OObject {
public:
    Spin() : vectors(0) {}
    OSubject*  subject[numOfSubject];
    OObserver* observer[numOfObserver];
    virtual OStatus DoInit(const OSystemEvent& event);
    virtual OStatus DoStart(const OSystemEvent& event);
    void NotifySensor(const ONotifyEvent& event);

private:
    int vectors;
};

#endif
