// FileProbe: what an object may read and write (the memory stick as /MS, the run's folder),
// the robot's design and design data, then Shutdown (aibo-sim's runtime tests read its console).
#ifndef FileProbe_h_DEFINED
#define FileProbe_h_DEFINED

#include <OPENR/OObject.h>
#include <OPENR/OSubject.h>
#include <OPENR/OObserver.h>
#include "def.h"

class FileProbe : public OObject {
public:
    OSubject*  subject[numOfSubject];
    OObserver* observer[numOfObserver];
    virtual OStatus DoStart(const OSystemEvent& event);
};

#endif
