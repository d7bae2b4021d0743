/*
 * MCOOP.h: the Aperios calls a stub ends its entries with. On the host an entry simply
 * returns, so Exit() and Return() do nothing.
 */
#ifndef _MCOOP_h_DEFINED
#define _MCOOP_h_DEFINED

#include <Types.h>
#include <OID.h>

extern "C" {
    void Exit();
    void Return(void* msg = 0, size_t sizeOfMsg = 0);
    sError WhoAmI(OID* object);
}

#endif /* _MCOOP_h_DEFINED */
