/*
 * OObserver.h: the receiving end of connections. AssertReady() asks every connected subject
 * (or one) for its next data and gives back what it sent last; DeassertReady() refuses data
 * until the next AssertReady().
 */
#ifndef _OObserver_h_DEFINED
#define _OObserver_h_DEFINED

#include <iostream>
#include <list>
#include <Types.h>
#include <OPENR/OPENR.h>
#include <OPENR/ObjcommTypes.h>
#include <OPENR/ObjcommMessages.h>
#include <OPENR/ObjcommEvent.h>
#include <OPENR/OSubjectInfo.h>

using std::cout;
using std::endl;
using std::list;

typedef list<OSubjectInfo>::iterator       SubjectIterator;
typedef list<OSubjectInfo>::const_iterator SubjectConstIterator;

class OObserver {
public:
    OObserver();
    virtual ~OObserver();

    OStatus SetNotifyEntry(const OServiceEntry& entry);
    void    SetSkip(size_t skip) { skip_ = skip; }
    void    SetBufCtrlParam(size_t skip, size_t, size_t) { skip_ = skip; }

    /* Called by the stub. */
    OStatus ConnectHandler(const OConnectMessage& msg, OStatus status = oSUCCESS);
    OStatus NotifyHandler(const ONotifyMessage& msg, ONotifyEvent* event);
    OStatus ConnectHandler(OConnectMessage* msg) { return ConnectHandler(*msg); }
    OStatus NotifyHandler(ONotifyMessage* msg, ONotifyEvent* event) { return NotifyHandler(*msg, event); }

    OStatus AssertReady() { return SendReadyAll(objcommCMD_ASSERT_READY); }
    OStatus DeassertReady() { return SendReadyAll(objcommCMD_DEASSERT_READY); }
    OStatus AssertReady(const SubjectID& id) { return SendReady(objcommCMD_ASSERT_READY, id); }
    OStatus DeassertReady(const SubjectID& id) { return SendReady(objcommCMD_DEASSERT_READY, id); }

    SubjectConstIterator begin() const { return subjects_.begin(); }
    SubjectConstIterator end() const { return subjects_.end(); }
    int                  NumberOfSubjects() const { return (int)subjects_.size(); }
    const ObserverID&    GetObserverID() const { return myID_; }
    const ObserverID&    GetID() const { return myID_; }

private:
    OObserver(const OObserver&);
    OObserver& operator=(const OObserver&);

    OStatus SendReadyAll(ObjcommCommand command);
    OStatus SendReady(ObjcommCommand command, const SubjectID& subject);

    ObserverID         myID_;
    size_t             skip_;
    list<OSubjectInfo> subjects_;
};

#endif /* _OObserver_h_DEFINED */
