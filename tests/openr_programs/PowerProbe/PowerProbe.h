// PowerProbe: the battery's status, and what ObservePowerStatus reports when the motors are
// powered (aibo-sim's runtime tests read its console).
#ifndef PowerProbe_h_DEFINED
#define PowerProbe_h_DEFINED

#include <OPENR/OObject.h>
#include <OPENR/OSubject.h>
#include <OPENR/OObserver.h>
#include "def.h"

class PowerProbe : public OObject {
public:
    OSubject*  subject[numOfSubject];
    OObserver* observer[numOfObserver];
    virtual OStatus DoStart(const OSystemEvent& event);
    void UpdatePowerStatus(void* message);
};

#endif
