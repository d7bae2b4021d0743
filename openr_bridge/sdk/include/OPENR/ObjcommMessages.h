/* ObjcommMessages.h: the messages subjects and observers exchange (host layouts). */
#ifndef ObjcommMessages_h_DEFINED
#define ObjcommMessages_h_DEFINED

#include <string.h>
#include <OPENR/OPENR.h>
#include <OPENR/ObjcommTypes.h>
#include <OPENR/OPENRMessages.h>
#include <OPENR/RCRegion.h>

/* The most data one notification carries. */
#define MAX_NUM_DATA 13

/* Sony's message types (those of versions 2.1 and 2.2 too); the messages here carry the ones
 * Sony's do. */
const OMessageType omsgCONTROL           = OMessageSystemBase + 12;
const OMessageType omsgCONTROL_REPLY     = OMessageSystemBase + 13;
const OMessageType omsgREADY             = OMessageSystemBase + 14;
const OMessageType omsgNOTIFY            = OMessageSystemBase + 15;
const OMessageType omsgCONTROL_V21       = OMessageSystemBase + 256;
const OMessageType omsgCONTROL_REPLY_V21 = OMessageSystemBase + 257;
const OMessageType omsgREADY_V21         = OMessageSystemBase + 258;
const OMessageType omsgNOTIFY_V21        = OMessageSystemBase + 259;
const OMessageType omsgNOTIFY_L10        = OMessageSystemBase + 260;
const OMessageType omsgREADY_V22         = OMessageSystemBase + 261;
const OMessageType omsgNOTIFY_V22        = OMessageSystemBase + 262;

/* Observer to subject, at connection: add (or remove) me. */
struct OControlMessage {
    OMessageType   msgType;
    ObjcommCommand command;
    ObserverID     observerID;
    size_t         d_skip;
    size_t         d_min;
    size_t         d_max;
    char           subName[oserviceNAME_MAX + 1];

    OControlMessage() : msgType(omsgCONTROL), command(objcommCMD_UNDEF), d_skip(0), d_min(1), d_max(1) {
        subName[0] = 0;
    }
};

struct OControlReplyMessage {
    OMessageType msgType;
    OStatus      status;
    SubjectID    subjectID;

    OControlReplyMessage() : msgType(omsgCONTROL_REPLY), status(oUNDEF) {}
};

/* Observer to subject: ready (or not) for more; gives back the data it was sent. */
struct OReadyMessage {
    OMessageType   msgType;
    ObjcommCommand command;
    ObserverID     observerID;

    OReadyMessage() : msgType(omsgREADY_V22), command(objcommCMD_UNDEF) {}
};

/* Subject to observer: the data. */
struct ONotifyMessage {
    OMessageType msgType;
    SubjectID    subjectID;
    short        numOfData;
    short        numOfNotify;
    RCRegion*    data[MAX_NUM_DATA];

    ONotifyMessage() : msgType(omsgNOTIFY_V22), numOfData(0), numOfNotify(0) {}
    int NumberOfData() const { return numOfData; }
    int NumberOfNotify() const { return numOfNotify; }
};

/* System to observer, at boot: connect to the subject whose Control entry is subjectID. */
struct OConnectMessage {
    OMessageType msgType;
    OConnectCmd  command;
    SubjectID    subjectID;
    char         subName[oserviceNAME_MAX + 1];

    OConnectMessage() : msgType(omsgCONNECT), command(oconnectcmdCONNECT) { subName[0] = 0; }
};

#endif /* ObjcommMessages_h_DEFINED */
