/*
 * core_macro2.h: REGISTER_ALL_ENTRY for objects loaded under another name: each service name
 * takes the object's runtime name `myname` in place of its first component.
 */
#ifndef New_core_macro2_h_DEFINED
#define New_core_macro2_h_DEFINED

#include <string>
#include <OPENR/core_macro.h>

#undef REGISTER_ALL_ENTRY
#define REGISTER_ALL_ENTRY \
{ \
    for (int i = 0; i < numOfSubject; ++i) { \
        std::string name(subjectService[i]); \
        name.replace(0, name.find('.'), myname); \
        RegisterServiceEntry(OServiceEntry(myOID_, Entry_Control[i]), name.c_str()); \
    } \
    for (int i = 0; i < numOfObserver; ++i) { \
        std::string name(observerService[i]); \
        name.replace(0, name.find('.'), myname); \
        RegisterServiceEntry(OServiceEntry(myOID_, Entry_Connect[i]), name.c_str()); \
    } \
}

#endif
