#include <OPENR/OSyslog.h>
#include <OPENR/core_macro.h>
#include "Talker.h"

OStatus Talker::DoInit(const OSystemEvent&) {
    NEW_ALL_SUBJECT_AND_OBSERVER;
    REGISTER_ALL_ENTRY;
    SET_ALL_READY_AND_NOTIFY_ENTRY;
    return oSUCCESS;
}

OStatus Talker::DoStart(const OSystemEvent&) {
    ASSERT_READY_TO_ALL_OBSERVER;
    return oSUCCESS;
}

OStatus Talker::DoStop(const OSystemEvent&) {
    OSYSPRINT(("stop\n"));
    return oSUCCESS;
}

OStatus Talker::DoDestroy(const OSystemEvent&) {
    OSYSPRINT(("destroy\n"));
    return oSUCCESS;
}

void Talker::NotifySensor(const ONotifyEvent& event) {
    if (count < 12) {
        count++;
        subject[sbjCount]->SetData(&count, sizeof count);
        subject[sbjCount]->NotifyObservers();
        OSYSPRINT(("sent %d\n", count));
    }
    observer[event.ObsIndex()]->AssertReady();
}
