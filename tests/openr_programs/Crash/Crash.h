// Crash: writes through a null pointer on its third sensor vector (aibo-sim's runtime tests). With
// CRASH_HOW in the environment: exit, it calls exit(3) there instead; thread, a thread of its own
// writes through the null pointer 50 ms later (outside any handler); stack, it recurses without
// end; live, it runs on; init, it never returns from DoInit; say, its constructor prints "made";
// load, its constructor writes through the null pointer (while the runtime loads its file); fatal,
// it calls OPENR::Fatal there instead; fatal init, DoInit calls it and fails, as Sony's RMain does;
// fatal load, its constructor calls it.
// clock, it prints GetSystemTime's at each vector and runs on. In the fatal modes DoStart and
// DoStop say they ran.
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
    virtual OStatus DoStop(const OSystemEvent& event);
    void NotifySensor(const ONotifyEvent& event);

private:
    int vectors;
};

#endif
