#include <OPENR/OPENRAPI.h>
#include <OPENR/OFbkImage.h>
#include <OPENR/OSyslog.h>
#include <OPENR/core_macro.h>
#include "CdtProbe.h"

CdtProbe::CdtProbe() : camera(oprimitiveID_UNDEF), images(0) {}

OStatus CdtProbe::DoInit(const OSystemEvent&) {
    NEW_ALL_SUBJECT_AND_OBSERVER;
    REGISTER_ALL_ENTRY;
    SET_ALL_READY_AND_NOTIFY_ENTRY;
    OPENR::OpenPrimitive("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1", &camera);
    MemoryRegionID id;
    OCdtVectorData* cdt;
    OPENR::NewCdtVectorData(&id, &cdt);
    cdt->SetNumData(2);
    OCdtInfo* pink = cdt->GetInfo(0);
    pink->Init(camera, ocdtCHANNEL0);
    for (int s = 0; s < ocdtMAX_Y_SEGMENT; s++) pink->Set(s, 230, s < 20 ? 150 : 160, 190, 120);
    OCdtInfo* orange = cdt->GetInfo(1);
    orange->Init(camera, ocdtCHANNEL1);
    for (int s = 5; s < ocdtMAX_Y_SEGMENT; s++) orange->Set(s, 200, 155, 95, 30);
    OSYSPRINT(("SetCdtVectorData %u\n", (unsigned)OPENR::SetCdtVectorData(id)));
    orange->Init(camera, ocdtCHANNEL7);  // the ERS-7 has channels 0-6
    OSYSPRINT(("channel 7 %u\n", (unsigned)OPENR::SetCdtVectorData(id)));
    orange->Init(camera, ocdtCHANNEL0);  // two tables for one channel
    OSYSPRINT(("channel 0 twice %u\n", (unsigned)OPENR::SetCdtVectorData(id)));
    OPENR::DeleteCdtVectorData(id);
    return oSUCCESS;
}

OStatus CdtProbe::DoStart(const OSystemEvent&) {
    ASSERT_READY_TO_ALL_OBSERVER;
    return oSUCCESS;
}

void CdtProbe::Notify(const ONotifyEvent& event) {
    OFbkImageVectorData* image = (OFbkImageVectorData*)event.Data(0);
    OFbkImage c(image->GetInfo(ofbkimageLAYER_C), image->GetData(ofbkimageLAYER_C), ofbkimageBAND_CDT);
    OFbkImage y(image->GetInfo(ofbkimageLAYER_H), image->GetData(ofbkimageLAYER_H), ofbkimageBAND_Y);
    long count = 0, sumX = 0, sumY = 0;
    for (int row = 0; row < c.Height() - 1; row++) {  // the last row holds the tag
        for (int x = 0; x < c.Width(); x++) {
            if (c.Pixel(x, row) & ocdtCHANNEL1) {
                count++;
                sumX += x;
                sumY += row;
            }
        }
    }
    OSYSPRINT(("image %u frame %u field %u camera %d C %dx%d orange %ld %ld %ld freq %u %u Y(10,20) %u\n",
               (unsigned)images, (unsigned)image->GetInfo(ofbkimageLAYER_C)->frameNumber, (unsigned)c.FieldCounter(),
               image->GetInfo(ofbkimageLAYER_H)->primitiveID == camera, c.Width(), c.Height(), count, sumX, sumY,
               (unsigned)c.ColorFrequency(ocdtCHANNEL0), (unsigned)c.ColorFrequency(ocdtCHANNEL1),
               (unsigned)y.Pixel(10, 20)));
    images++;
    observer[event.ObsIndex()]->AssertReady();
}
