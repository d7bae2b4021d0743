/*
 * RCRegion.h: a region of shared memory with a reference count. The last RemoveReference()
 * frees it (and its memory, when the region allocated it). A subject's SetData() adds a
 * reference that is given back when the observer asserts ready again; the robot's effector
 * holds one while it plays a command vector: a program may reuse a region once
 * NumberOfReference() is 1 again.
 */
#ifndef RCRegion_h_DEFINED
#define RCRegion_h_DEFINED

#include <iostream>
#include <Types.h>

using std::cout;
using std::endl;

typedef unsigned int offset_t;

#define OBJCOMM_VERSION_21
#define OBJCOMM_VERSION_22

class RCRegion {
public:
    enum RegionType { SELF_ALLOCATED, REFERENCE_V20, REFERENCE_V10, UNDEF };

    RCRegion();
    explicit RCRegion(size_t size);
    RCRegion(MemoryRegionID memID, offset_t offset, void* baseAddr = NULL, size_t size = 0);

    void AddReference();
    void RemoveReference();
    int  NumberOfReference() const { return refCounter_; }

    char*          Base() const { return baseAddr_; }
    size_t         Size() const { return size_; }
    MemoryRegionID MemID() const { return memID_; }
    offset_t       Offset() const { return offset_; }
    RegionType     GetType() const { return status_; }
    void           SetSize(size_t size) { size_ = size; }

private:
    ~RCRegion();
    RCRegion(const RCRegion&);
    RCRegion& operator=(const RCRegion&);

    int            refCounter_;
    RegionType     status_;
    MemoryRegionID memID_;
    offset_t       offset_;
    size_t         size_;
    char*          baseAddr_;
};

typedef RCRegion RCRegionBase;

#endif /* RCRegion_h_DEFINED */
