#include <stdlib.h>
#include <OPENR/OPENRAPI.h>
#include <OPENR/OSyslog.h>
#include <OPENR/OUnits.h>
#include <OPENR/core_macro.h>
#include "JointProbe.h"

static const char* const PAN = "PRM:/r1/c1/c2-Joint2:12";
static bool overfull = false;  /* the first vector claims more data than it holds */

JointProbe::JointProbe() : pan(oprimitiveID_UNDEF), started(false), waits(false), sent(0), sensorIndex(-1) {
    if (getenv("JPROBE_SAY") != 0) OSYSPRINT(("made\n"));
}

OStatus JointProbe::DoInit(const OSystemEvent&) {
    NEW_ALL_SUBJECT_AND_OBSERVER;
    REGISTER_ALL_ENTRY;
    SET_ALL_READY_AND_NOTIFY_ENTRY;
    OPENR::OpenPrimitive(PAN, &pan);
    for (int i = 0; i < 2; i++) {
        MemoryRegionID id;
        OCommandVectorData* vector;
        OPENR::NewCommandVectorData(1, &id, &vector);
        vector->SetNumData(1);
        vector->GetInfo(0)->Set(odataJOINT_COMMAND2, pan, FRAMES);
        region[i] = new RCRegion(vector->vectorInfo.memRegionID, vector->vectorInfo.offset, (void*)vector,
                                 vector->vectorInfo.totalSize);
    }
    return oSUCCESS;
}

OStatus JointProbe::DoStart(const OSystemEvent&) {
    char mode[16] = "";
    ODesignDataID id;
    byte* data;
    size_t size;
    if (OPENR::FindDesignData("JOINTPROBE_MODE", &id, &data, &size) == oSUCCESS) {
        memcpy(mode, data, size < sizeof mode - 1 ? size : sizeof mode - 1);
        OPENR::DeleteDesignData(id);
    }
    OSYSPRINT(("mode [%s]\n", mode));
    waits = strncmp(mode, "wait", 4) == 0;
    overfull = strncmp(mode, "overfull", 8) == 0;
    if (strncmp(mode, "closed", 6) == 0) {  /* a primitive's values, open and closed */
        OPrimitiveID accel, tilt;
        OSensorValue sensor;
        OJointValue joint;
        OPENR::OpenPrimitive("PRM:/a1-Sensor:a1", &accel);
        OPENR::OpenPrimitive("PRM:/r1/c1-Joint2:11", &tilt);
        OStatus openSensor = OPENR::GetSensorValue(accel, &sensor), openJoint = OPENR::GetJointValue(tilt, &joint);
        OPENR::ClosePrimitive(accel);
        OPENR::ClosePrimitive(tilt);
        OSYSPRINT(("open %u %u closed %u %u\n", (unsigned)openSensor, (unsigned)openJoint,
                   (unsigned)OPENR::GetSensorValue(accel, &sensor), (unsigned)OPENR::GetJointValue(tilt, &joint)));
    }
    if (strncmp(mode, "nopower", 7) != 0) OPENR::SetMotorPower(opowerON);
    if (strncmp(mode, "nogain", 6) != 0) {
        word g[6] = {1, 1, 1, 1, 1, 1};
        OStatus status = OPENR::GetJointGain(pan, &g[0], &g[1], &g[2], &g[3], &g[4], &g[5]);
        OSYSPRINT(("gain before enabled %u: %u %u %u %u %u %u\n", (unsigned)status, g[0], g[1], g[2], g[3], g[4], g[5]));
        OSYSPRINT(("cancel undefined sync key %u\n", (unsigned)OPENR::CancelSyncKey(ovrsynckeyUNDEF)));
        OPENR::EnableJointGain(pan);
        OPENR::SetJointGain(pan, 0x08, 0x02, 0x04, 0x0E, 0x02, 0x0F);
    }
    Send(0);
    Send(1);
    subject[sbjMove]->NotifyObservers();
    started = true;
    ASSERT_READY_TO_ALL_OBSERVER;
    return oSUCCESS;
}

// Vector v: frame k holds the pan at 10 + 4v + k degrees.
void JointProbe::Send(int vector) {
    RCRegion* free = region[0]->NumberOfReference() == 1 ? region[0] : region[1];
    if (free->NumberOfReference() != 1) {
        OSYSPRINT(("no free region\n"));
        return;
    }
    OCommandVectorData* data = (OCommandVectorData*)free->Base();
    OJointCommandValue2* value = (OJointCommandValue2*)data->GetData(0)->value;
    for (int k = 0; k < FRAMES; k++) value[k].value = oradians(10 + 4 * vector + k);
    data->vectorInfo.wait = waits && vector == 2 ? WAIT : 0;
    data->vectorInfo.optOffset = 4;  // for the sensor vectors: which vector played last
    data->vectorInfo.optSize = 1;
    data->vectorInfo.optional[4] = (byte)('A' + vector);
    if (overfull && vector == 0) data->vectorInfo.numData = 100000;
    subject[sbjMove]->SetData(free);
    sent++;
}

void JointProbe::Ready(const OReadyEvent& event) {
    if (!started) {  // the effector's ready at boot, before DoStart (as Sony's samples expect it)
        OSYSPRINT(("ready before start\n"));
        return;
    }
    OSYSPRINT(("ready %s refs %d %d\n", event.IsAssert() ? "assert" : "deassert", region[0]->NumberOfReference(),
               region[1]->NumberOfReference()));
    for (int i = 0; i < 2; i++) {  // the frame each region's vector started in, as the effector wrote it
        OCommandVectorData* data = (OCommandVectorData*)region[i]->Base();
        OSYSPRINT(("started region %d frame %u\n", i, (unsigned)data->GetInfo(0)->frameNumber));
    }
    if (sent < VECTORS) {
        Send(sent);
        subject[sbjMove]->NotifyObservers();
    }
}

void JointProbe::NotifySensor(const ONotifyEvent& event) {
    OSensorFrameVectorData* sensors = (OSensorFrameVectorData*)event.Data(0);
    if (sensorIndex < 0) {
        for (longword i = 0; i < sensors->vectorInfo.numData; i++) {
            if (sensors->GetInfo(i)->primitiveID == pan) sensorIndex = (int)i;
        }
    }
    OSensorFrameInfo* info = sensors->GetInfo(sensorIndex);
    OJointValue* joint = (OJointValue*)sensors->GetData(sensorIndex)->frame;
    OJointValue now;
    OPENR::GetJointValue(pan, &now);
    const ODataVectorInfo& vector = sensors->vectorInfo;
    OSYSPRINT(("sensor %u %u %d %d %d %d ref %d now %d optional %u %u %c\n", (unsigned)info->frameNumber,
               (unsigned)info->numFrames, (int)joint[0].value, (int)joint[1].value, (int)joint[2].value,
               (int)joint[3].value, (int)joint[3].refValue, (int)now.value, (unsigned)vector.optOffset,
               (unsigned)vector.optSize, vector.optional[4] ? vector.optional[4] : '-'));
    observer[event.ObsIndex()]->AssertReady();
}
