#include <math.h>
#include <OPENR/OPENRAPI.h>
#include <OPENR/OFbkImage.h>
#include <OPENR/OUnits.h>
#include <OPENR/core_macro.h>
#include "HeadSwing.h"

HeadSwing::HeadSwing() : pan(oprimitiveID_UNDEF), frame(0), sensorIndex(-1), panAngle(0), pixels(0) {}

OStatus HeadSwing::DoInit(const OSystemEvent&) {
    NEW_ALL_SUBJECT_AND_OBSERVER;
    REGISTER_ALL_ENTRY;
    SET_ALL_READY_AND_NOTIFY_ENTRY;
    OPENR::OpenPrimitive("PRM:/r1/c1/c2-Joint2:12", &pan);
    OPENR::SetMotorPower(opowerON);
    OPENR::EnableJointGain(pan);
    OPENR::SetJointGain(pan, 0x08, 0x02, 0x04, 0x0E, 0x02, 0x0F);
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

OStatus HeadSwing::DoStart(const OSystemEvent&) {
    Send();
    Send();
    subject[sbjMove]->NotifyObservers();
    ASSERT_READY_TO_ALL_OBSERVER;
    return oSUCCESS;
}

void HeadSwing::Send() {
    RCRegion* free = region[0]->NumberOfReference() == 1 ? region[0] : region[1];
    if (free->NumberOfReference() != 1) return;
    OCommandVectorData* vector = (OCommandVectorData*)free->Base();
    OJointCommandValue2* value = (OJointCommandValue2*)vector->GetData(0)->value;
    for (int k = 0; k < FRAMES; k++, frame++) value[k].value = oradians(60 * sin(2 * M_PI * frame * 0.008 / 4));
    subject[sbjMove]->SetData(free);
}

void HeadSwing::Ready(const OReadyEvent&) {
    Send();
    subject[sbjMove]->NotifyObservers();
}

void HeadSwing::NotifySensor(const ONotifyEvent& event) {
    OSensorFrameVectorData* sensors = (OSensorFrameVectorData*)event.Data(0);
    for (longword i = 0; sensorIndex < 0 && i < sensors->vectorInfo.numData; i++) {
        if (sensors->GetInfo(i)->primitiveID == pan) sensorIndex = (int)i;
    }
    panAngle = sensors->GetData(sensorIndex)->frame[3].value / 1e6;
    observer[event.ObsIndex()]->AssertReady();
}

void HeadSwing::NotifyImage(const ONotifyEvent& event) {
    OFbkImageVectorData* image = (OFbkImageVectorData*)event.Data(0);
    OFbkImage y(image->GetInfo(ofbkimageLAYER_H), image->GetData(ofbkimageLAYER_H), ofbkimageBAND_Y);
    pixels += y.Pixel(y.Width() / 2, y.Height() / 2);
    observer[event.ObsIndex()]->AssertReady();
}
