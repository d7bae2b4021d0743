/*
 * OObserver.h: the receiving end of connections. AssertReady() asks every connected subject
 * (or one) for its next data and gives back what it sent last; DeassertReady() refuses data
 * until the next AssertReady(). SetBufCtrlParam() (before the connection: in DoInit) says how
 * the subjects buffer data for it; by default they hold only the newest unit.
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
    /* How the subjects this observer connects to buffer its data (Level2 Reference Guide): keep
     * one data unit in `skip` + 1, send `min` units a notification, hold at most `max`. */
    void    SetSkip(size_t skip) { SetBufCtrlParam(skip, 1, 1); }
    void    SetBufCtrlParam(size_t skip, size_t min, size_t max) {
        skip_ = skip;
        min_ = min;
        max_ = max;
    }

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
    size_t             skip_, min_, max_;
    list<OSubjectInfo> subjects_;
};

#endif /* _OObserver_h_DEFINED */
