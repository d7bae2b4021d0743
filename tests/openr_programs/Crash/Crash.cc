#include <stdlib.h>
#include <string.h>
#include <OPENR/OSyslog.h>
#include <OPENR/core_macro.h>
#include "Crash.h"

static bool How(const char* how) {
    const char* chosen = getenv("CRASH_HOW");
    return chosen != 0 && strcmp(chosen, how) == 0;
}

Crash::Crash() : vectors(0) {
    if (How("say")) OSYSPRINT(("made\n"));
}

OStatus Crash::DoInit(const OSystemEvent&) {
    for (volatile int i = 0; How("init"); i++) {
    }
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
    if (vectors == 3 && How("exit")) exit(3);
    if (vectors == 3) *(volatile int*)0 = 1;
    observer[event.ObsIndex()]->AssertReady();
}
