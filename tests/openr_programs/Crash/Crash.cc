#include <OPENR/OSyslog.h>
#include <OPENR/core_macro.h>
#include "Crash.h"

OStatus Crash::DoInit(const OSystemEvent&) {
    NEW_ALL_SUBJECT_AND_OBSERVER;
    REGISTER_ALL_ENTRY;
    SET_ALL_READY_AND_NOTIFY_ENTRY;
    return oSUCCESS;
}

OStatus Crash::DoStart(const OSystemEvent&) {
    ASSERT_READY_TO_ALL_OBSERVER;
    return oSUCCESS;
}

void Crash::NotifySensor(const ONotifyEvent& event) {
    OSYSPRINT(("sensor vector %d\n", ++vectors));
    if (vectors == 3) *(volatile int*)0 = 1;
    observer[event.ObsIndex()]->AssertReady();
}
