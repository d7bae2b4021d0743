/*
 * core_macro.h: the lifecycle macros an object's DoInit/DoStart/DoStop/DoDestroy use. They
 * read the names stubgen2 generates (def.h, entry.h): numOfSubject, numOfObserver,
 * subjectService[], observerService[], Entry_Control[], Entry_Ready[], Entry_Connect[],
 * Entry_Notify[], and the object's members subject[] and observer[].
 */
#ifndef New_core_macro_h_DEFINED
#define New_core_macro_h_DEFINED

#include "entry.h"
#include <OPENR/OPENR.h>
#include <OPENR/OSubject.h>
#include <OPENR/OObserver.h>

#define NEW_ALL_SUBJECT_AND_OBSERVER \
{ \
    for (int i = 0; i < numOfSubject; ++i) subject[i] = new OSubject(); \
    for (int i = 0; i < numOfObserver; ++i) observer[i] = new OObserver(); \
}

#define DELETE_ALL_SUBJECT_AND_OBSERVER \
{ \
    for (int i = 0; i < numOfSubject; ++i) { delete subject[i]; subject[i] = 0; } \
    for (int i = 0; i < numOfObserver; ++i) { delete observer[i]; observer[i] = 0; } \
}

#define REGISTER_ALL_ENTRY \
{ \
    for (int i = 0; i < numOfSubject; ++i) \
        RegisterServiceEntry(OServiceEntry(myOID_, Entry_Control[i]), subjectService[i]); \
    for (int i = 0; i < numOfObserver; ++i) \
        RegisterServiceEntry(OServiceEntry(myOID_, Entry_Connect[i]), observerService[i]); \
}

#define SET_ALL_READY_AND_NOTIFY_ENTRY \
{ \
    for (int i = 0; i < numOfSubject; ++i) subject[i]->SetReadyEntry(OServiceEntry(myOID_, Entry_Ready[i])); \
    for (int i = 0; i < numOfObserver; ++i) observer[i]->SetNotifyEntry(OServiceEntry(myOID_, Entry_Notify[i])); \
}

/* Subjects send as soon as they are connected: nothing to enable. */
#define ENABLE_ALL_SUBJECT

#define DISABLE_ALL_SUBJECT \
{ \
    for (int i = 0; i < numOfSubject; ++i) subject[i]->ClearBuffer(); \
}

#define ASSERT_READY_TO_ALL_OBSERVER \
{ \
    for (int i = 0; i < numOfObserver; ++i) observer[i]->AssertReady(); \
}

#define DEASSERT_READY_TO_ALL_OBSERVER \
{ \
    for (int i = 0; i < numOfObserver; ++i) observer[i]->DeassertReady(); \
}

/* Older names. */
#define ASSERT_TO_ALL_OBSERVER ASSERT_READY_TO_ALL_OBSERVER
#define DEASSERT_TO_ALL_OBSERVER DEASSERT_READY_TO_ALL_OBSERVER
#define NewComData NEW_ALL_SUBJECT_AND_OBSERVER
#define DeleteComData DELETE_ALL_SUBJECT_AND_OBSERVER
#define SetComData REGISTER_ALL_ENTRY SET_ALL_READY_AND_NOTIFY_ENTRY

#endif /* New_core_macro_h_DEFINED */
