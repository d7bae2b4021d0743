#include <OPENR/OSyslog.h>
#include <OPENR/core_macro.h>
#include "Listener.h"

OStatus Listener::DoInit(const OSystemEvent&) {
    NEW_ALL_SUBJECT_AND_OBSERVER;
    REGISTER_ALL_ENTRY;
    SET_ALL_READY_AND_NOTIFY_ENTRY;
    observer[obsSkip]->SetSkip(1);
    observer[obsPair]->SetBufCtrlParam(0, 2, 3);
    return oSUCCESS;
}

OStatus Listener::DoStart(const OSystemEvent&) {
    ASSERT_READY_TO_ALL_OBSERVER;
    return oSUCCESS;
}

OStatus Listener::DoStop(const OSystemEvent&) {
    OSYSPRINT(("stop\n"));
    return oSUCCESS;
}

OStatus Listener::DoDestroy(const OSystemEvent&) {
    OSYSPRINT(("destroy\n"));
    return oSUCCESS;
}

void Listener::NotifySensor(const ONotifyEvent& event) {
    if (++vectors % 4 == 0) observer[obsNewest]->AssertReady();
    observer[event.ObsIndex()]->AssertReady();
}

void Listener::Print(const char* name, const ONotifyEvent& event) {
    char values[64] = "";
    for (int i = 0, n = 0; i < event.NumOfData(); i++) {
        n += snprintf(values + n, sizeof values - n, " %d", *(const int*)event.Data(i));
    }
    OSYSPRINT(("%s data %d notify %d:%s\n", name, event.NumOfData(), event.NumOfNotify(), values));
}

void Listener::NotifyNewest(const ONotifyEvent& event) { Print("newest", event); }

void Listener::NotifySkip(const ONotifyEvent& event) {
    Print("skip", event);
    observer[event.ObsIndex()]->AssertReady();
}

void Listener::NotifyPair(const ONotifyEvent& event) {
    Print("pair", event);
    observer[event.ObsIndex()]->AssertReady();
}
