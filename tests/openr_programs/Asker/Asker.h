// Asker: asks on the console until it reads "y", as Sony's PIDControl7 does (aibo-sim's runtime tests).
#ifndef Asker_h_DEFINED
#define Asker_h_DEFINED

#include <OPENR/OObject.h>
#include <OPENR/OSubject.h>
#include <OPENR/OObserver.h>
#include "def.h"

class Asker : public OObject {
public:
    OSubject*  subject[numOfSubject];
    OObserver* observer[numOfObserver];
    virtual OStatus DoInit(const OSystemEvent& event);
    virtual OStatus DoStart(const OSystemEvent& event);
};

#endif
