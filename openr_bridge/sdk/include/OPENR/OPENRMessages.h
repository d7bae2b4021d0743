/* OPENRMessages.h: the messages the system sends to objects' entries. */
#ifndef _OPENRMessages_h_DEFINED
#define _OPENRMessages_h_DEFINED

#include <string.h>
#include <OPENR/OPENR.h>
#include <OPENR/ODataFormats.h>
#include <OPENR/OTime.h>
#include <OPENR/OPower.h>
#include <OPENR/OSyslog.h>

typedef longword OMessageType;
const OMessageType OMessageSystemBase  = 0;
const OMessageType OMessageRoboticBase = 1024;
const OMessageType omsgNULL         = 0;
const OMessageType omsgREASON       = 3;
const OMessageType omsgCONNECT      = 6;
const OMessageType omsgPOWER_STATUS = OMessageRoboticBase + 6;

/* Init, Start, Stop and Destroy: why the entry is called, and its parameter. */
struct OReasonMessage {
    OMessageType msgType;
    OReason      reason;
    size_t       paramSize;
    byte         param[oreasonPARAM_MAX_SIZE];

    OReasonMessage(OReason r = oreasonUNDEF) : msgType(omsgREASON), reason(r), paramSize(0) {}
    OReasonMessage(OReason r, const void* p, size_t size) : msgType(omsgREASON), reason(r), paramSize(size) {
        memcpy(param, p, size);
    }
};

/* What an entry registered with OPENR::ObservePowerStatus receives. */
struct OPowerStatusMessage {
    OMessageType msgType;
    OPowerStatus powerStatus;

    OPowerStatusMessage() : msgType(omsgPOWER_STATUS) {}
    OPowerStatusMessage(const OPowerStatus& status) : msgType(omsgPOWER_STATUS), powerStatus(status) {}
};

#endif /* _OPENRMessages_h_DEFINED */
