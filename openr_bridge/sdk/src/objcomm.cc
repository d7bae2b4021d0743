/*
 * objcomm.cc: OObject, RCRegion, OSubject and OObserver over the runtime's mailbox.
 *
 * Connection (at boot): the system sends the observer's Connect entry the subject's Control
 * entry; the observer calls it with its Notify entry and its buffer parameters (skip, min, max),
 * and the subject answers with its Ready entry. Data come in units of GetNotifyUnitSize()
 * SetData() calls. SetData() queues a region for each observer (one reference each), except in
 * the units its `skip` leaves out; a queue holds the newest `max` units (and no more than
 * SetBufferSize() regions), the oldest dropped. NotifyObservers(), and an observer's
 * AssertReady(), send the oldest `min` units to an observer that is ready and has them; the
 * observer's next AssertReady() gives them back (the references are removed).
 *
 * Where Sony's manual is silent (UNCONFIRMED): a notification carries `min` units (not all
 * that are held), and skipping counts units per observer from its connection.
 */
#include <OPENR/OObject.h>
#include <OPENR/OSubject.h>
#include <OPENR/OObserver.h>
#include <OPENR/OSyslog.h>
#include "host.h"

/* OObject */

OObject::OObject() : myOID_(host::Constructing()) {}
OObject::~OObject() {}

static void Report(const char* hook, OStatus status) {
    if (status != oSUCCESS) osyslog(osyslogWARNING, "%s returned %u", hook, (unsigned)status);
}

void OObject::Init(const OSystemEvent& event) { Report("DoInit", DoInit(event)); }
void OObject::Start(const OSystemEvent& event) { Report("DoStart", DoStart(event)); }
void OObject::Stop(const OSystemEvent& event) { Report("DoStop", DoStop(event)); }
void OObject::Destroy(const OSystemEvent& event) { Report("DoDestroy", DoDestroy(event)); }
OStatus OObject::DoInit(const OSystemEvent&) { return oSUCCESS; }
OStatus OObject::DoStart(const OSystemEvent&) { return oSUCCESS; }
OStatus OObject::DoStop(const OSystemEvent&) { return oSUCCESS; }
OStatus OObject::DoDestroy(const OSystemEvent&) { return oSUCCESS; }

OStatus OObject::RegisterServiceEntry(const OServiceEntry& entry, const char* name) {
    return host::Register(entry, name);
}

ostream& operator<<(ostream& os, const OServiceEntry& id) {
    return os << "(" << id.oid.GetAddress() << ", " << id.selector << ")";
}

/* RCRegion */

RCRegion::RCRegion() : refCounter_(0), status_(UNDEF), memID_(0), offset_(0), size_(0), baseAddr_(NULL) {}

RCRegion::RCRegion(size_t size) : refCounter_(1), status_(SELF_ALLOCATED), offset_(0), size_(size) {
    void* base;
    memID_ = host::NewRegion(size, &base);
    baseAddr_ = (char*)base;
}

RCRegion::RCRegion(MemoryRegionID memID, offset_t offset, void* baseAddr, size_t size)
    : refCounter_(1), status_(REFERENCE_V20), memID_(memID), offset_(offset), size_(size), baseAddr_((char*)baseAddr) {
    if (baseAddr_ == NULL) {
        char* base = (char*)host::RegionBase(memID, size_ ? NULL : &size_);
        baseAddr_ = base ? base + offset : NULL;
    }
}

RCRegion::~RCRegion() {
    if (status_ == SELF_ALLOCATED) host::DeleteRegion(memID_);
}

void RCRegion::AddReference() { refCounter_++; }

void RCRegion::RemoveReference() {
    if (--refCounter_ <= 0) delete this;
}

/* OSubject */

OSubject::OSubject() : maxBufferSize_(MAX_NUM_DATA + 1), notifyUnitSize_(1) {}

OSubject::~OSubject() {
    for (ObserverIterator it = observers_.begin(); it != observers_.end(); ++it) {
        Clear(it->impl_);
        GiveBack(it->impl_->sent);
        delete it->impl_;
    }
}

OStatus OSubject::SetReadyEntry(const OServiceEntry& entry) {
    myID_ = entry;
    return oSUCCESS;
}

OStatus OSubject::SetBufferSize(size_t size) {
    if (size < 1) return oINVALID_ARG;
    maxBufferSize_ = size;
    return oSUCCESS;
}

OStatus OSubject::SetNotifyUnitSize(size_t size) {
    if (size < 1 || size > MAX_NUM_DATA) return oINVALID_ARG;
    notifyUnitSize_ = size;
    return oSUCCESS;
}

ObserverConstIterator OSubject::FindObserver(const ObserverID& id) const {
    for (ObserverConstIterator it = observers_.begin(); it != observers_.end(); ++it) {
        if (it->impl_->id == id) return it;
    }
    return observers_.end();
}

/* The regions an observer's queue holds at most: its `max` units, within SetBufferSize(). */
size_t OSubject::Capacity(const _OObserverInfo* info) const {
    size_t units = info->d_max * notifyUnitSize_ <= maxBufferSize_ ? info->d_max : maxBufferSize_ / notifyUnitSize_;
    return (units ? units : 1) * notifyUnitSize_;
}

void OSubject::Queue(_OObserverInfo* info, RCRegion* region) {
    if (info->n_data++ % notifyUnitSize_ == 0) {  /* a new unit: kept, or skipped */
        info->taking = info->skip_counter == 0;
        info->skip_counter = info->taking ? info->d_skip : info->skip_counter - 1;
    }
    if (!info->taking) return;
    region->AddReference();
    info->queue.push_back(region);
    while (info->queue.size() > Capacity(info)) {  /* the oldest unit makes room */
        for (size_t k = 0; k < notifyUnitSize_ && !info->queue.empty(); k++) {
            info->queue.front()->RemoveReference();
            info->queue.pop_front();
            info->dropped++;
        }
    }
}

/* The regions a notification carries: `min` units, as far as the queue and a message hold them. */
size_t OSubject::NotifySize(const _OObserverInfo* info) const {
    size_t size = info->d_min * notifyUnitSize_, capacity = Capacity(info);
    if (size > capacity) size = capacity;
    size_t most = MAX_NUM_DATA - MAX_NUM_DATA % notifyUnitSize_;
    return size < most ? size : most;  /* SetNotifyUnitSize keeps a unit within MAX_NUM_DATA */
}

/* Whether an observer is ready and its queue holds a notification's data. */
bool OSubject::Due(const _OObserverInfo* info) const {
    return info->ready_flag > 0 && !info->queue.empty() && info->queue.size() >= NotifySize(info);
}

OStatus OSubject::SetData(const OObserverInfo& info, RCRegion* region) {
    if (info.impl_ == NULL || region == NULL) return oINVALID_ARG;
    Queue(info.impl_, region);
    return oSUCCESS;
}

OStatus OSubject::SetData(const ObserverID& id, RCRegion* region) {
    ObserverConstIterator it = FindObserver(id);
    return it == observers_.end() ? oINVALID_ARG : SetData(*it, region);
}

OStatus OSubject::SetData(RCRegion* region) {
    if (region == NULL) return oINVALID_ARG;
    for (ObserverIterator it = observers_.begin(); it != observers_.end(); ++it) Queue(it->impl_, region);
    return oSUCCESS;
}

static RCRegion* CopyToRegion(const void* buf, size_t size) {
    RCRegion* region = new RCRegion(size);
    memcpy(region->Base(), buf, size);
    return region;
}

OStatus OSubject::SetData(const OObserverInfo& info, const void* buf, size_t size) {
    RCRegion* region = CopyToRegion(buf, size);
    OStatus status = SetData(info, region);
    region->RemoveReference();
    return status;
}

OStatus OSubject::SetData(const ObserverID& id, const void* buf, size_t size) {
    RCRegion* region = CopyToRegion(buf, size);
    OStatus status = SetData(id, region);
    region->RemoveReference();
    return status;
}

OStatus OSubject::SetData(const void* buf, size_t size) {
    RCRegion* region = CopyToRegion(buf, size);
    OStatus status = SetData(region);
    region->RemoveReference();
    return status;
}

void OSubject::Send(_OObserverInfo* info) {
    ONotifyMessage message;
    message.subjectID = myID_;
    size_t count = NotifySize(info);
    while (!info->queue.empty() && (size_t)message.numOfData < count && message.numOfData < MAX_NUM_DATA) {
        RCRegion* region = info->queue.front();
        info->queue.pop_front();
        info->sent.push_back(region);
        message.data[message.numOfData++] = region;
    }
    message.numOfNotify = (int)(message.numOfData / notifyUnitSize_);
    info->ready_flag = 0;
    host::Send(info->id, &message, sizeof message);
}

void OSubject::GiveBack(std::deque<RCRegion*>& regions) {
    while (!regions.empty()) {
        regions.front()->RemoveReference();
        regions.pop_front();
    }
}

void OSubject::Clear(_OObserverInfo* info) { GiveBack(info->queue); }

OStatus OSubject::NotifyObserver(const OObserverInfo& observer) {
    _OObserverInfo* info = observer.impl_;
    if (info == NULL) return oINVALID_ARG;
    if (Due(info)) {
        Send(info);
    } else if (info->ready_flag < 0) {
        Clear(info);
    }
    return oSUCCESS;
}

OStatus OSubject::NotifyObserver(const ObserverID& id) {
    ObserverConstIterator it = FindObserver(id);
    return it == observers_.end() ? oINVALID_ARG : NotifyObserver(*it);
}

OStatus OSubject::NotifyObservers() {
    for (ObserverIterator it = observers_.begin(); it != observers_.end(); ++it) NotifyObserver(*it);
    return oSUCCESS;
}

size_t OSubject::RemainBuffer(const OObserverInfo& observer) const {
    size_t capacity = Capacity(observer.impl_), held = observer.impl_->queue.size();
    return held < capacity ? capacity - held : 0;  /* held beyond it after SetBufferSize shrank */
}

size_t OSubject::RemainBuffer(const ObserverID& id) const {
    ObserverConstIterator it = FindObserver(id);
    return it == observers_.end() ? 0 : RemainBuffer(*it);
}

size_t OSubject::RemainBuffer() const {
    size_t least = maxBufferSize_;
    for (ObserverConstIterator it = observers_.begin(); it != observers_.end(); ++it) {
        size_t remain = RemainBuffer(*it);
        if (remain < least) least = remain;
    }
    return least;
}

OStatus OSubject::ClearBuffer(const OObserverInfo& info) {
    if (info.impl_ == NULL) return oINVALID_ARG;
    Clear(info.impl_);
    return oSUCCESS;
}

OStatus OSubject::ClearBuffer(const ObserverID& id) {
    ObserverConstIterator it = FindObserver(id);
    return it == observers_.end() ? oINVALID_ARG : ClearBuffer(*it);
}

OStatus OSubject::ClearBuffer() {
    for (ObserverIterator it = observers_.begin(); it != observers_.end(); ++it) Clear(it->impl_);
    return oSUCCESS;
}

OStatus OSubject::ControlHandler(const OControlMessage& msg, OStatus status) {
    OControlReplyMessage reply;
    reply.status = status;
    reply.subjectID = myID_;
    bool adding = msg.command == objcommCMD_ADDOBSERVER || msg.command == objcommCMD_ADDOBSERVER_V22
               || msg.command == objcommCMD_ADDOBSERVER_SELF;
    bool removing = msg.command == objcommCMD_REMOVEOBSERVER || msg.command == objcommCMD_REMOVEOBSERVER_V22
                 || msg.command == objcommCMD_REMOVEOBSERVER_SELF;
    ObserverIterator found = observers_.begin();
    while (found != observers_.end() && !(found->impl_->id == msg.observerID)) ++found;
    if (status == oSUCCESS && adding && found == observers_.end()) {
        observers_.push_back(OObserverInfo(new _OObserverInfo(msg.observerID, msg.d_skip, msg.d_min, msg.d_max)));
    } else if (status == oSUCCESS && removing && found != observers_.end()) {
        Clear(found->impl_);
        GiveBack(found->impl_->sent);
        delete found->impl_;
        observers_.erase(found);
    } else if (!adding && !removing) {
        reply.status = oINVALID_ARG;
    }
    host::Reply(&reply, sizeof reply);
    return reply.status;
}

OStatus OSubject::ReadyHandler(const OReadyMessage& msg) {
    for (ObserverIterator it = observers_.begin(); it != observers_.end(); ++it) {
        _OObserverInfo* info = it->impl_;
        if (!(info->id == msg.observerID)) continue;
        GiveBack(info->sent);
        if (msg.command == objcommCMD_ASSERT_READY) {
            info->ready_flag = 1;
            if (Due(info)) Send(info);
        } else if (msg.command == objcommCMD_DEASSERT_READY) {
            info->ready_flag = -1;
            Clear(info);
        }
        return oSUCCESS;
    }
    return oINVALID_ARG;
}

int OSubject::ReadyStatus(const ObserverID& id) const {
    ObserverConstIterator it = FindObserver(id);
    return it == observers_.end() ? 0 : it->impl_->ready_flag;
}

int OSubject::IsAllReady() const {
    bool any = false;
    for (ObserverConstIterator it = observers_.begin(); it != observers_.end(); ++it) {
        if (it->impl_->ready_flag == 0) return 0;
        any = any || it->impl_->ready_flag > 0;
    }
    return any;
}

int OSubject::IsAnyReady() const {
    for (ObserverConstIterator it = observers_.begin(); it != observers_.end(); ++it) {
        if (it->impl_->ready_flag > 0) return 1;
    }
    return 0;
}

/* OObserver */

OObserver::OObserver() : skip_(0), min_(1), max_(1) {}
OObserver::~OObserver() {}

OStatus OObserver::SetNotifyEntry(const OServiceEntry& entry) {
    myID_ = entry;
    return oSUCCESS;
}

OStatus OObserver::ConnectHandler(const OConnectMessage& msg, OStatus status) {
    if (status != oSUCCESS) return status;
    if (msg.command != oconnectcmdCONNECT) return oNOT_SUPPORTED;
    OControlMessage control;
    control.command = objcommCMD_ADDOBSERVER_V22;
    control.observerID = myID_;
    control.d_skip = skip_;
    control.d_min = min_;
    control.d_max = max_;
    memcpy(control.subName, msg.subName, sizeof control.subName);
    OControlReplyMessage reply;
    if (host::Call(msg.subjectID, &control, &reply, sizeof reply) != oSUCCESS) return oFAIL;
    if (reply.status != oSUCCESS) return reply.status;
    subjects_.push_back(OSubjectInfo(reply.subjectID, objcommVERSION22));
    return oSUCCESS;
}

OStatus OObserver::NotifyHandler(const ONotifyMessage& msg, ONotifyEvent* event) {
    for (SubjectConstIterator it = subjects_.begin(); it != subjects_.end(); ++it) {
        if (it->GetSubjectID() == msg.subjectID) event->SetSubjectInfo(*it);
    }
    event->SetNumOfData(msg.numOfData);
    event->SetNumOfNotify(msg.numOfNotify);
    for (int i = 0; i < msg.numOfData; i++) event->SetData(i, msg.data[i]);
    return oSUCCESS;
}

OStatus OObserver::SendReady(ObjcommCommand command, const SubjectID& subject) {
    OReadyMessage message;
    message.command = command;
    message.observerID = myID_;
    host::Send(subject, &message, sizeof message);
    return oSUCCESS;
}

OStatus OObserver::SendReadyAll(ObjcommCommand command) {
    for (SubjectConstIterator it = subjects_.begin(); it != subjects_.end(); ++it) SendReady(command, *it);
    return oSUCCESS;
}
