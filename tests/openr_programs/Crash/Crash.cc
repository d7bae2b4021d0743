#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <MCOOP.h>
#include <OPENR/OPENRAPI.h>
#include <OPENR/OSyslog.h>
#include <OPENR/core_macro.h>
#include "Crash.h"

static bool How(const char* how) {
    const char* chosen = getenv("CRASH_HOW");
    return chosen != 0 && strcmp(chosen, how) == 0;
}

static void* CrashLater(void*) {
    usleep(50000);
    *(volatile int*)0 = 1;
    return 0;
}

static int Deeper(int depth) {
    volatile char frame[4096];
    frame[0] = (char)depth;
    return Deeper(depth + 1) + frame[0];
}

Crash::Crash() : vectors(0) {
    if (How("say")) OSYSPRINT(("made\n"));
    if (How("load")) *(volatile int*)0 = 1;
    if (How("fatal load")) OPENR::Fatal(ofatalPAUSE_SW);
    if (How("exit load")) exit(5);
}

OStatus Crash::DoInit(const OSystemEvent&) {
    for (volatile int i = 0; How("init"); i++) {
    }
    NEW_ALL_SUBJECT_AND_OBSERVER;
    REGISTER_ALL_ENTRY;
    SET_ALL_READY_AND_NOTIFY_ENTRY;
    if (How("fatal init")) {
        OPENR::Fatal(ofatalMEMORY_STICK);
        return oFAIL;
    }
    return oSUCCESS;
}

OStatus Crash::DoStart(const OSystemEvent&) {
    if (How("fatal") || How("fatal init") || How("fatal load")) OSYSPRINT(("DoStart\n"));
    ASSERT_READY_TO_ALL_OBSERVER;
    return oSUCCESS;
}

OStatus Crash::DoStop(const OSystemEvent&) {
    if (How("fatal") || How("fatal init") || How("fatal load")) OSYSPRINT(("DoStop\n"));
    for (volatile int i = 0; How("stop"); i++) {
    }
    return oSUCCESS;
}

void Crash::NotifySensor(const ONotifyEvent& event) {
    OSYSPRINT(("sensor vector %d\n", ++vectors));
    if (How("clock")) {
        SystemTime now;
        GetSystemTime(&now);
        OSYSPRINT(("system time %u.%06u, OTime %u bytes, OBootCondition %u\n", (unsigned)now.seconds,
                   (unsigned)now.useconds, (unsigned)sizeof(OTime), (unsigned)sizeof(OBootCondition)));
    }
    if (vectors == 3 && !How("live") && !How("clock") && !How("stop")) {
        pthread_t later;
        if (How("exit")) exit(3);
        if (How("fatal")) {
            OPENR::Fatal(ofatalUNDEF);
            observer[event.ObsIndex()]->AssertReady();  /* its next vector never comes: the power is off */
            return;
        }
        if (How("thread")) {
            pthread_create(&later, 0, CrashLater, 0);
        } else if (How("stack")) {
            Deeper(0);
        } else {
            *(volatile int*)0 = 1;
        }
    }
    observer[event.ObsIndex()]->AssertReady();
}
