#include <stdio.h>  // gets
#include <string.h>
#include <OPENR/OSyslog.h>
#include <OPENR/core_macro.h>
#include "Asker.h"

OStatus Asker::DoInit(const OSystemEvent&) {
    NEW_ALL_SUBJECT_AND_OBSERVER;
    REGISTER_ALL_ENTRY;
    SET_ALL_READY_AND_NOTIFY_ENTRY;
    return oSUCCESS;
}

OStatus Asker::DoStart(const OSystemEvent&) {
    char line[80];
    do {
        OSYSPRINT(("go on? (y/n) "));
        gets(line);
    } while (strcmp(line, "y") != 0);
    OSYSPRINT(("going on\n"));
    return oSUCCESS;
}
