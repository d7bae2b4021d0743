/*
 * OSubject.h: the sending end of a connection. SetData() queues data for every connected
 * observer (each queue holds GetBufferSize() entries; a full one loses its oldest);
 * NotifyObservers() sends it to the observers that asserted ready, drops it for those that
 * deasserted, and keeps it for the others until they assert ready.
 */
#ifndef _OSubject_h_DEFINED
#define _OSubject_h_DEFINED

#include <list>
#include <Types.h>
#include <OPENR/OPENR.h>
#include <OPENR/ObjcommTypes.h>
#include <OPENR/ObjcommMessages.h>
#include <OPENR/OObserverInfo.h>

using std::list;

typedef list<OObserverInfo>::iterator       ObserverIterator;
typedef list<OObserverInfo>::const_iterator ObserverConstIterator;

class OSubject {
public:
    OSubject();
    ~OSubject();

    OStatus          SetReadyEntry(const OServiceEntry& readyEntry);
    const SubjectID& GetID() const { return myID_; }
    OStatus          SetBufferSize(size_t size);
    size_t           GetBufferSize() const { return maxBufferSize_; }
    OStatus          SetNotifyUnitSize(size_t size);
    size_t           GetNotifyUnitSize() const { return notifyUnitSize_; }

    OStatus SetData(const OObserverInfo& info, RCRegion* region);
    OStatus SetData(const ObserverID& id, RCRegion* region);
    OStatus SetData(RCRegion* region);
    OStatus SetData(const OObserverInfo& info, const void* buf, size_t size);
    OStatus SetData(const ObserverID& id, const void* buf, size_t size);
    OStatus SetData(const void* buf, size_t size);

    OStatus NotifyObserver(const OObserverInfo& observer);
    OStatus NotifyObserver(const ObserverID& observer);
    OStatus NotifyObservers();

    size_t  RemainBuffer(const OObserverInfo& observer) const;
    size_t  RemainBuffer(const ObserverID& id) const;
    size_t  RemainBuffer() const;
    OStatus ClearBuffer(const OObserverInfo& info);
    OStatus ClearBuffer(const ObserverID& id);
    OStatus ClearBuffer();

    /* Called by the stub. */
    OStatus ControlHandler(const OControlMessage& msg, OStatus status = oSUCCESS);
    OStatus ReadyHandler(const OReadyMessage& msg);
    OStatus ControlHandler(OControlMessage* msg) { return ControlHandler(*msg); }
    OStatus ReadyHandler(OReadyMessage* msg) { return ReadyHandler(*msg); }

    int                   NumberOfObservers() const { return (int)observers_.size(); }
    ObserverConstIterator begin() const { return observers_.begin(); }
    ObserverConstIterator end() const { return observers_.end(); }
    ObserverConstIterator FindObserver(const ObserverID& id) const;

    int ReadyStatus(const ObserverID& id) const;
    int ReadyStatus(const OObserverInfo& info) const { return info.impl_->ready_flag; }
    int IsAllReady() const;
    int IsAnyReady() const;
    int IsReady() const { return IsAnyReady(); }
    int IsReady(const ObserverID& id) const { return ReadyStatus(id) > 0; }
    int IsReady(const OObserverInfo& info) const { return info.impl_->ready_flag > 0; }

private:
    OSubject(const OSubject&);
    OSubject& operator=(const OSubject&);

    size_t Capacity(const _OObserverInfo* info) const;
    size_t NotifySize(const _OObserverInfo* info) const;
    bool Due(const _OObserverInfo* info) const;
    void Queue(_OObserverInfo* info, RCRegion* region);
    void Send(_OObserverInfo* info);
    void Clear(_OObserverInfo* info);
    static void GiveBack(std::deque<RCRegion*>& regions);

    SubjectID           myID_;
    list<OObserverInfo> observers_;
    size_t              maxBufferSize_;
    size_t              notifyUnitSize_;
};

#endif /* _OSubject_h_DEFINED */
