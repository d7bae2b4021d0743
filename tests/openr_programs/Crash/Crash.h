// Crash: writes through a null pointer on its third sensor vector (aibo-sim's runtime tests); with
// CRASH_HOW=exit in the environment it calls exit(3) there instead, with CRASH_HOW=init it never
// returns from DoInit, with CRASH_HOW=say its constructor prints "made".
#ifndef Crash_h_DEFINED
#define Crash_h_DEFINED

#include <OPENR/OObject.h>
#include <OPENR/OSubject.h>
#include <OPENR/OObserver.h>
#include "def.h"

class Crash : public OObject {
public:
    Crash();
    OSubject*  subject[numOfSubject];
    OObserver* observer[numOfObserver];
    virtual OStatus DoInit(const OSystemEvent& event);
    virtual OStatus DoStart(const OSystemEvent& event);
    void NotifySensor(const ONotifyEvent& event);

private:
    int vectors;
};

#endif
