// Talker: sends 1, 2, ... 12 to its observers, one a sensor vector (aibo-sim's runtime tests).
#ifndef Talker_h_DEFINED
#define Talker_h_DEFINED

#include <OPENR/OObject.h>
#include <OPENR/OSubject.h>
#include <OPENR/OObserver.h>
#include "def.h"

class Talker : public OObject {
public:
    Talker() : count(0) {}
    OSubject*  subject[numOfSubject];
    OObserver* observer[numOfObserver];
    virtual OStatus DoInit(const OSystemEvent& event);
    virtual OStatus DoStart(const OSystemEvent& event);
    virtual OStatus DoStop(const OSystemEvent& event);
    virtual OStatus DoDestroy(const OSystemEvent& event);
    void NotifySensor(const ONotifyEvent& event);

private:
    int count;
};

#endif
