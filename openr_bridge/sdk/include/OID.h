/*
 * OID.h: an object's identity. On the host an OID is the address of the runtime's record
 * of the object (OID_UNDEF when invalid).
 */
#ifndef _OID_h_DEFINED
#define _OID_h_DEFINED

#include <Types.h>

#define OID_UNDEF 0xFFFFFFFF

struct structOID {
    void* address;
};

#ifdef __cplusplus
class OID : public structOID {
public:
    OID() { address = (void*)OID_UNDEF; }
    OID(void* value) { address = value; }
    void  SetAddress(void* value) { address = value; }
    void* GetAddress() const { return address; }
    bool  IsValid() const { return address != (void*)OID_UNDEF; }
    void  MakeInvalid() { address = (void*)OID_UNDEF; }
    bool operator==(const OID& other) const { return address == other.address; }
    bool operator!=(const OID& other) const { return address != other.address; }
    bool operator<(const OID& other) const { return address < other.address; }
    bool operator<=(const OID& other) const { return address <= other.address; }
    bool operator>(const OID& other) const { return address > other.address; }
    bool operator>=(const OID& other) const { return address >= other.address; }
};
#else
typedef struct structOID OID;
#endif

#endif /* _OID_h_DEFINED */
