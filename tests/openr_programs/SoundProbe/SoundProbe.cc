#include <math.h>
#include <string.h>
#include <OPENR/OPENRAPI.h>
#include <OPENR/OSyslog.h>
#include <OPENR/core_macro.h>
#include "SoundProbe.h"

OStatus SoundProbe::DoInit(const OSystemEvent&) {
    NEW_ALL_SUBJECT_AND_OBSERVER;
    REGISTER_ALL_ENTRY;
    SET_ALL_READY_AND_NOTIFY_ENTRY;
    OPENR::OpenPrimitive("PRM:/s1-Speaker:S1", &speaker);
    OPrimitiveControl_SpeakerSoundType type(ospksndMONO16K16B);
    OPENR::ControlPrimitive(speaker, oprmreqSPEAKER_SET_SOUND_TYPE, &type, sizeof type, 0, 0);
    OPrimitiveControl_SpeakerVolume volume(ospkvol10dB);
    OPENR::ControlPrimitive(speaker, oprmreqSPEAKER_SET_VOLUME, &volume, sizeof volume, 0, 0);
    for (int i = 0; i < 2; i++) {
        MemoryRegionID id;
        OSoundVectorData* vector;
        OPENR::NewSoundVectorData(1, SAMPLES * 2, &id, &vector);
        vector->SetNumData(1);
        OSoundInfo* info = vector->GetInfo(0);
        info->Set(odataSOUND_VECTOR, speaker, SAMPLES * 2);
        info->samplingRate = 16000;
        info->bitsPerSample = 16;
        region[i] = new RCRegion(vector->vectorInfo.memRegionID, vector->vectorInfo.offset, (void*)vector,
                                 vector->vectorInfo.totalSize);
    }
    return oSUCCESS;
}

OStatus SoundProbe::DoStart(const OSystemEvent&) {
    ODesignDataID id;
    byte* data;
    size_t size;
    if (OPENR::FindDesignData("SOUNDPROBE_MODE", &id, &data, &size) == oSUCCESS) {
        waits = size >= 4 && memcmp(data, "wait", 4) == 0;
        OPENR::DeleteDesignData(id);
    }
    Send();
    Send();
    subject[sbjSpeaker]->NotifyObservers();
    started = true;
    return oSUCCESS;
}

void SoundProbe::Send() {
    RCRegion* free = region[0]->NumberOfReference() == 1 ? region[0] : region[1];
    if (sent == VECTORS) return;
    if (free->NumberOfReference() != 1) {  // where Sony's SoundPlay would crash (a NULL region)
        OSYSPRINT(("no free region\n"));
        return;
    }
    sword* samples = (sword*)((OSoundVectorData*)free->Base())->GetData(0);
    for (int k = 0; k < SAMPLES; k++) samples[k] = (sword)(10000 * sin(2 * M_PI * 1000 * (sent * SAMPLES + k) / 16000.0));
    ((OSoundVectorData*)free->Base())->vectorInfo.wait = waits && sent == 2 ? WAIT : 0;
    subject[sbjSpeaker]->SetData(free);
    sent++;
}

// The speaker's first ready comes at boot, before DoStart; then one after each vector.
void SoundProbe::Ready(const OReadyEvent&) {
    readies++;
    OSYSPRINT(("ready %d refs %d %d%s\n", readies, region[0]->NumberOfReference(), region[1]->NumberOfReference(),
               started ? "" : " before start"));
    if (!started) return;
    for (int i = 0; i < 2; i++) {  // the frame each region's sound starts in, as the speaker wrote it
        OSoundVectorData* data = (OSoundVectorData*)region[i]->Base();
        OSYSPRINT(("started region %d frame %u\n", i, (unsigned)data->GetInfo(0)->frameNumber));
    }
    Send();
    subject[sbjSpeaker]->NotifyObservers();
}
