/*
 * MCOOP.h: the Aperios calls a stub ends its entries with (on the host an entry simply returns,
 * so Exit() and Return() do nothing), WhoAmI and GetSystemTime (the simulated time since boot).
 */
#ifndef _MCOOP_h_DEFINED
#define _MCOOP_h_DEFINED

#include <Types.h>
#include <OID.h>
#include <SystemTime.h>

extern "C" {
    void Exit();
    void Return(void* msg = 0, size_t sizeOfMsg = 0);
    sError WhoAmI(OID* object);
    sError GetSystemTime(SystemTime* sysTime);
}

#endif /* _MCOOP_h_DEFINED */
