/* OObserverInfo.h: what a subject knows of an observer connected to it. */
#ifndef OObserverInfo_h_DEFINED
#define OObserverInfo_h_DEFINED

#include <deque>
#include <OPENR/ObjcommTypes.h>
#include <OPENR/RCRegion.h>

struct _OObserverInfo {
    ObserverID id;
    size_t d_skip, d_min, d_max;    /* the observer's SetBufCtrlParam: skip, min and max, in data units */
    int ready_flag;                 /* 1: asserted ready, 0: neither, -1: deasserted */
    std::deque<RCRegion*> queue;    /* data waiting to be sent */
    std::deque<RCRegion*> sent;     /* data sent, until the observer gives it back */
    size_t dropped;                 /* data overwritten in a full buffer */
    size_t n_data;                  /* SetData() calls for this observer */
    size_t skip_counter;            /* units still to skip */
    bool taking;                    /* whether the unit being set is kept (not skipped) */

    _OObserverInfo(const ObserverID& i, size_t skip, size_t min, size_t max)
        : id(i), d_skip(skip), d_min(min ? min : 1), d_max(max > d_min ? max : d_min), ready_flag(0), dropped(0),
          n_data(0), skip_counter(0), taking(true) {}
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
