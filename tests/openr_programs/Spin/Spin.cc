#include <OPENR/OSyslog.h>
#include <OPENR/core_macro.h>
#include "Spin.h"

OStatus Spin::DoInit(const OSystemEvent&) {
    NEW_ALL_SUBJECT_AND_OBSERVER;
    REGISTER_ALL_ENTRY;
    SET_ALL_READY_AND_NOTIFY_ENTRY;
    return oSUCCESS;
}

OStatus Spin::DoStart(const OSystemEvent&) {
    ASSERT_READY_TO_ALL_OBSERVER;
    return oSUCCESS;
}

void Spin::NotifySensor(const ONotifyEvent& event) {
    OSYSPRINT(("sensor vector %d\n", ++vectors));
    if (vectors == 2) OSYSPRINT(("spinning> "));  // a prompt, as a program waiting for its console
    for (volatile int i = 0; vectors == 2; i++) {
    }
    observer[event.ObsIndex()]->AssertReady();
}
