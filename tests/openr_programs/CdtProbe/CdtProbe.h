// CdtProbe: sets two colour tables (Sony's pink-ball table on channel 0, an orange one on
// channel 1) and prints what the camera's layers say (aibo-sim's runtime tests read it).
#ifndef CdtProbe_h_DEFINED
#define CdtProbe_h_DEFINED

#include <OPENR/OObject.h>
#include <OPENR/OSubject.h>
#include <OPENR/OObserver.h>
#include "def.h"

class CdtProbe : public OObject {
public:
    CdtProbe();
    OSubject*  subject[numOfSubject];
    OObserver* observer[numOfObserver];
    virtual OStatus DoInit(const OSystemEvent& event);
    virtual OStatus DoStart(const OSystemEvent& event);
    void Notify(const ONotifyEvent& event);

private:
    OPrimitiveID camera;
    int          images;
};

#endif
