/* OObserverInfo.h: what a subject knows of an observer connected to it. */
#ifndef OObserverInfo_h_DEFINED
#define OObserverInfo_h_DEFINED

#include <deque>
#include <OPENR/ObjcommTypes.h>
#include <OPENR/RCRegion.h>

struct _OObserverInfo {
    ObserverID id;
    int ready_flag;                 /* 1: asserted ready, 0: neither, -1: deasserted */
    std::deque<RCRegion*> queue;    /* data waiting to be sent */
    std::deque<RCRegion*> sent;     /* data sent, until the observer gives it back */
    size_t dropped;                 /* data overwritten in a full buffer */

    _OObserverInfo(const ObserverID& i) : id(i), ready_flag(0), dropped(0) {}
};

class OObserverInfo {
public:
    OObserverInfo() : impl_(0) {}
    const ObserverID& GetObserverID() const { return impl_->id; }

private:
    friend class OSubject;
    OObserverInfo(_OObserverInfo* info) : impl_(info) {}
    _OObserverInfo* impl_;
};
typedef OObserverInfo ObserverInfo;

#endif
