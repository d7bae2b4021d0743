// Listener: observes Talker three ways (aibo-sim's runtime tests): Newest with Sony's default
// buffer, asking again every 4th sensor vector; Skip with SetSkip(1); Pair with
// SetBufCtrlParam(0, 2, 3). Skip and Pair ask again at once.
#ifndef Listener_h_DEFINED
#define Listener_h_DEFINED

#include <OPENR/OObject.h>
#include <OPENR/OSubject.h>
#include <OPENR/OObserver.h>
#include "def.h"

class Listener : public OObject {
public:
    Listener() : vectors(0) {}
    OSubject*  subject[numOfSubject];
    OObserver* observer[numOfObserver];
    virtual OStatus DoInit(const OSystemEvent& event);
    virtual OStatus DoStart(const OSystemEvent& event);
    virtual OStatus DoStop(const OSystemEvent& event);
    virtual OStatus DoDestroy(const OSystemEvent& event);
    void NotifySensor(const ONotifyEvent& event);
    void NotifyNewest(const ONotifyEvent& event);
    void NotifySkip(const ONotifyEvent& event);
    void NotifyPair(const ONotifyEvent& event);

private:
    void Print(const char* name, const ONotifyEvent& event);
    int vectors;
};

#endif
