/*
 * stub_macro.h: the entry functions stubgen2 writes into <Name>Stub.cc. Each receives the
 * message of its entry, lets the subject or observer handle it, then calls the object's
 * member function named in stub.cfg (if any). `Self` is the object, defined by the stub.
 */
#ifndef stub_macro_h_DEFINED
#define stub_macro_h_DEFINED

#include <OPENR/OSubject.h>
#include <OPENR/OObserver.h>
#include <OPENR/ObjcommMessages.h>
#include <OPENR/OPENREvent.h>
#include <OPENR/OPENRMessages.h>
#include <MCOOP.h>

#define StubFuncDeclare_Basic(name) extern void _##name(OReasonMessage*);
#define StubFuncDeclare_Subject(id) \
    extern void _Control##id(OControlMessage*); \
    extern void _Ready##id(OReadyMessage*);
#define StubFuncDeclare_Observer(id) \
    extern void _Connect##id(OConnectMessage*); \
    extern void _Notify##id(ONotifyMessage*);

#define StubFuncDefine_Basic(name) \
extern "C" void _##name(OReasonMessage* msg) \
{ \
    Self.name(OSystemEvent(msg->reason, msg->param, msg->paramSize)); \
    Exit(); \
}

#define StubFuncDefine_Control_nofunc(id) \
extern "C" void _Control##id(OControlMessage* msg) \
{ \
    Self.subject[id]->ControlHandler(*msg); \
    Exit(); \
}

#define StubFuncDefine_Control(id, function) \
extern "C" void _Control##id(OControlMessage* msg) \
{ \
    OStatus status = Self.function(OControlEvent(id, msg->observerID, msg->subName, msg->command)); \
    Self.subject[id]->ControlHandler(*msg, status); \
    Exit(); \
}

#define StubFuncDefine_Ready_nofunc(id) \
extern "C" void _Ready##id(OReadyMessage* msg) \
{ \
    Self.subject[id]->ReadyHandler(*msg); \
    Exit(); \
}

#define StubFuncDefine_Ready(id, function) \
extern "C" void _Ready##id(OReadyMessage* msg) \
{ \
    Self.subject[id]->ReadyHandler(*msg); \
    Self.function(OReadyEvent(id, msg->observerID, msg->command)); \
    Exit(); \
}

#define StubFuncDefine_Connect_nofunc(id) \
extern "C" void _Connect##id(OConnectMessage* msg) \
{ \
    Self.observer[id]->ConnectHandler(*msg); \
    Exit(); \
}

#define StubFuncDefine_Connect(id, function) \
extern "C" void _Connect##id(OConnectMessage* msg) \
{ \
    OStatus status = Self.function(OConnectEvent(id, msg->subName, msg->command)); \
    Self.observer[id]->ConnectHandler(*msg, status); \
    Exit(); \
}

#define StubFuncDefine_Notify(id, function) \
extern "C" void _Notify##id(ONotifyMessage* msg) \
{ \
    ONotifyEvent event; \
    event.SetIndex(id); \
    Self.observer[id]->NotifyHandler(*msg, &event); \
    Self.function(event); \
    Exit(); \
}

#define StubFuncDefine_Notify_nofunc(id) \
extern "C" void _Notify##id(ONotifyMessage* msg) \
{ \
    ONotifyEvent event; \
    event.SetIndex(id); \
    Self.observer[id]->NotifyHandler(*msg, &event); \
    Exit(); \
}

#endif /* stub_macro_h_DEFINED */
