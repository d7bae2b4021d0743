/*
 * robot.cc: the robot behind the OPENR:: calls, and the system objects OVirtualRobotComm and
 * OVirtualRobotAudioComm, on the simulator's data.
 *
 * - Primitives are the simulator's table (SETUP); an OPrimitiveID is the index in it.
 * - Sensors: every frame the simulator gives each sensor entry's values; every
 *   AIBO_OPENR_SENSOR_FRAMES frames OVirtualRobotComm.Sensor sends an OSensorFrameVectorData
 *   of them, numbered by the frames' OPEN-R frame numbers.
 * - Images: OVirtualRobotComm.FbkImageSensor sends each camera frame's OFbkImageVectorData,
 *   in a region that is the shared memory the simulator wrote it to (a slot no object holds).
 *   These two subjects keep only the newest data for an observer not yet ready.
 * - Lookahead: each answer foretells the frames after it in which no object code runs
 *   (host_protocol.py), which the simulator may step without a message.
 * - The effector (OVirtualRobotComm.Effector) plays the command vectors of each subject connected
 *   to it, one at a time from the frame it takes it, holding a reference to its region until its
 *   frames are played; it asserts ready to the subject at the start and after each vector's last
 *   frame, in time for the subject's next vector (a program primes its buffer with two, as
 *   Sony's samples do) to play from the next frame. Joint values change every frame; LED and
 *   Joint4 values last their `period` in frames.
 * - The speaker (OVirtualRobotAudioComm.Speaker) plays sound vectors one after the other in
 *   the same way, at their sampling rate; the microphone sends 32 ms of silence each 32 ms.
 * - Motors are unpowered until SetMotorPower(opowerON); joint gains are off until
 *   EnableJointGain and SetJointGain (Sony's registers, passed to the simulator as they are).
 */
#include <deque>
#include <new>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <math.h>
#include <OPENR/OObject.h>
#include <OPENR/OSubject.h>
#include <OPENR/OObserver.h>
#include <OPENR/OPENRAPI.h>
#include <OPENR/OPENRMessages.h>
#include <OPENR/OFbkImage.h>
#include <OPENR/OSyslog.h>
#include <OPENR/stub_macro.h>
#include <openr_host_protocol.h>
#include "host.h"

namespace host {
namespace {

const time_t CLOCK_START = 1121212800;  /* GetTime at t = 0: 2005-07-13 00:00 UTC (RoboCup 2005, Osaka) */

struct Gain {
    bool enabled;
    word values[6];      /* P, I, D, P shift, I shift, D shift */
    bool hasDefault;
    word defaults[6];
    Gain() : enabled(false), hasDefault(false) {
        memset(values, 0, sizeof values);
        memset(defaults, 0, sizeof defaults);
    }
};

struct PowerObserver {
    OPowerStatus  mask;
    OServiceEntry entry;
};

std::string design;
std::vector<Primitive> primitives;
std::vector<int> sensorOrder, sensorKinds;
std::vector<int> sensorIndexOf;           /* per primitive: its sensor entry, or -1 */
int cameraIndex = -1, speakerIndex = -1, micIndex = -1;
std::vector<slongword> latest;            /* the newest frame's values */
std::vector<std::vector<slongword> > pending;
longword pendingFrame = 0;
std::vector<bool> opened;
std::map<int, Gain> gains;
std::map<int, slongword> commanded;       /* the last JOINT or LED record per primitive */
bool motorPower = false;
OPowerStatus power;
std::vector<PowerObserver> powerObservers;
std::map<std::string, std::string> designData;
OSpeakerSoundType soundType = ospksndMONO16K16B;
bool speakerMuted = false;
double speakerGain = 1.0;
OVolumeSwitch volumeSwitch = ovolumeSW2;
long clockOffset = 0;
sbyte timeDifference = 9;
OVRSyncKey nextSyncKey = 1;
bool stopped = false;                     /* OPENR::Shutdown was called: the run ends with this frame */
/* Images: the simulator writes each into a slot of the shared memory that the runtime named
 * (AnnounceImageSlot), and the image's region is that memory while the objects hold it; when
 * every slot is held, into the last area, which the runtime copies. */
char* imageSlots = NULL;
MemoryRegionID slotImage[AIBO_OPENR_IMAGE_SLOTS] = {0};  /* the region of each slot's image (0: none yet) */
slongword announcedSlot = 0;
OCdtVectorData cdtInUse;                  /* the last SetCdtVectorData's tables */
bool cdtSet = false;

bool Valid(OPrimitiveID id) { return id < primitives.size(); }

OPrimitiveType TypeNamed(const std::string& locator) {
    static const struct { const char* name; OPrimitiveType type; } types[] = {
        {oprimitiveJOINT2_NAME, oprimitiveJOINT2}, {oprimitiveJOINT4_NAME, oprimitiveJOINT4},
        {oprimitiveJOINT3_NAME, oprimitiveJOINT3}, {oprimitiveSENSOR_NAME, oprimitiveSENSOR},
        {oprimitiveLED2_NAME, oprimitiveLED2}, {oprimitiveLED3_NAME, oprimitiveLED3},
        {oprimitiveFBKIMAGESENSOR_NAME, oprimitiveFBKIMAGESENSOR}, {oprimitiveSPEAKER_NAME, oprimitiveSPEAKER},
        {oprimitiveMIC_NAME, oprimitiveMIC}};
    size_t dash = locator.rfind('-'), colon = locator.rfind(':');
    std::string name = dash == std::string::npos || colon < dash ? "" : locator.substr(dash + 1, colon - dash - 1);
    for (size_t i = 0; i < sizeof types / sizeof types[0]; i++) {
        if (name == types[i].name) return types[i].type;
    }
    return oprimitiveUNDEF;
}

void RecordValues(longword kind, const slongword* values, size_t count) {
    Record(kind, values, count * sizeof(slongword));
}

void Command(int primitive, slongword value, slongword mode = 0) {
    slongword key = value * 4 + mode;
    std::map<int, slongword>::iterator last = commanded.find(primitive);
    if (last != commanded.end() && last->second == key) return;
    commanded[primitive] = key;
    OPrimitiveType type = primitives[primitive].type;
    if (type == oprimitiveLED2 || type == oprimitiveLED3) {
        slongword led[3] = {primitive, value, mode};
        RecordValues(AIBO_OPENR_RECORD_LED, led, 3);
    } else {
        slongword joint[2] = {primitive, value};
        RecordValues(AIBO_OPENR_RECORD_JOINT, joint, 2);
    }
}

void RecordGain(int primitive) {
    const Gain& gain = gains[primitive];
    slongword values[8] = {primitive, gain.enabled};
    for (int k = 0; k < 6; k++) values[2 + k] = gain.values[k];
    RecordValues(AIBO_OPENR_RECORD_GAIN, values, 8);
}

void NotifyPower(const OPowerStatus& before) {
    longword changed = before.robotStatus ^ power.robotStatus;
    word batteryChanged = before.batteryStatus ^ power.batteryStatus;
    for (size_t i = 0; i < powerObservers.size(); i++) {
        const OPowerStatus& mask = powerObservers[i].mask;
        bool capacity = mask.remainingCapacity == opsoREMAINING_CAPACITY_NOTIFY_EVERY_CHANGE
                        && before.remainingCapacity != power.remainingCapacity;
        if ((changed & mask.robotStatus) || (batteryChanged & mask.batteryStatus) || capacity) {
            OPowerStatusMessage message(power);
            Send(powerObservers[i].entry, &message, sizeof message);
        }
    }
}

/* A subject's vectors queued at the effector or the speaker, with the frame each has reached and
 * the frames it still waits before it starts (its ODataVectorInfo's wait). */
struct Playing {
    RCRegion* region;
    longword  frame;
    longword  frames;
    longword  wait;
};

struct Queue {
    SubjectID subject;
    std::deque<Playing> vectors;
};

longword CommandFrames(OCommandVectorData* vector) {
    longword longest = 0;
    for (longword i = 0; i < vector->vectorInfo.numData; i++) {
        OCommandInfo* info = vector->GetInfo((int)i);
        longword frames = info->numFrames;
        if (info->type == odataLED_COMMAND2 || info->type == odataLED_COMMAND3 || info->type == odataJOINT_COMMAND4) {
            frames = 0;
            for (longword k = 0; k < info->numFrames && k < ocommandMAX_FRAMES; k++) {
                word period = info->type == odataLED_COMMAND3
                    ? ((OLEDCommandValue3*)vector->GetData((int)i)->value)[k].period
                    : ((OLEDCommandValue2*)vector->GetData((int)i)->value)[k].period;  /* Joint4: same place */
                frames += period ? period : 1;
            }
        }
        if (frames > longest) longest = frames;
    }
    return longest;
}

/* The value of command `info` (data `data`) at frame `frame` of its vector; false after its end. */
bool CommandAt(const OCommandInfo* info, OCommandData* data, longword frame, slongword* value, slongword* mode) {
    longword count = info->numFrames < ocommandMAX_FRAMES ? info->numFrames : ocommandMAX_FRAMES;
    if (info->type == odataJOINT_COMMAND2 || info->type == odataJOINT_COMMAND) {
        if (frame >= count) return false;
        *value = data->value[frame].value[0];
        *mode = 0;
        return true;
    }
    for (longword k = 0, start = 0; k < count; k++) {
        word period;
        if (info->type == odataLED_COMMAND3) {
            OLEDCommandValue3* led = &((OLEDCommandValue3*)data->value)[k];
            period = led->period;
            *value = led->intensity;
            *mode = led->mode;
        } else if (info->type == odataLED_COMMAND2) {
            OLEDCommandValue2* led = &((OLEDCommandValue2*)data->value)[k];
            period = led->period;
            *value = led->led == oledON ? 255 : 0;
            *mode = 0;
        } else if (info->type == odataJOINT_COMMAND4) {
            OJointCommandValue4* joint = &((OJointCommandValue4*)data->value)[k];
            period = joint->period;
            *value = (slongword)joint->value;
            *mode = 0;
        } else {
            return false;
        }
        start += period ? period : 1;
        if (frame < start) return true;
    }
    return false;
}

class VirtualRobotComm;
class VirtualRobotAudioComm;
VirtualRobotComm* robotComm = NULL;
VirtualRobotAudioComm* audioComm = NULL;

/* A vector a program sent in `region` that does not lie within it (numData beyond maxNumData, an
 * info or its data past the region's end) is not played: its numData is made 0 and the console
 * says why, naming the sender (reading it crashed the robot's own object, which was blamed). */
void RefuseMalformed(RCRegion* region, const SubjectID& sender, bool sound) {
    ODataVectorInfo* vector = (ODataVectorInfo*)region->Base();
    size_t size = region->Size(), infoSize = sound ? sizeof(OSoundInfo) : sizeof(OCommandInfo);
    char why[160] = "";
    if (vector->numData > vector->maxNumData) {
        snprintf(why, sizeof why, "numData %u is more than its maxNumData %u", (unsigned)vector->numData,
                 (unsigned)vector->maxNumData);
    } else if (sizeof(ODataVectorInfo) + (size_t)vector->numData * infoSize > size) {
        snprintf(why, sizeof why, "its %u infos pass the end of its %u bytes", (unsigned)vector->numData, (unsigned)size);
    }
    for (longword i = 0; !*why && i < vector->numData; i++) {
        size_t offset = sound ? ((OSoundVectorData*)vector)->GetInfo((int)i)->dataOffset
                              : ((OCommandVectorData*)vector)->GetInfo((int)i)->dataOffset;
        size_t bytes = sound ? ((OSoundVectorData*)vector)->GetInfo((int)i)->dataSize : sizeof(OCommandData);
        if (offset > size || bytes > size - offset) {
            snprintf(why, sizeof why, "the data of its info %u pass the end of its %u bytes", (unsigned)i, (unsigned)size);
        }
    }
    if (!*why) return;
    const Object* object = ObjectOf(sender.oid);
    osyslog(osyslogERROR, "a %s vector from %s: %s: not played", sound ? "sound" : "command",
            object != NULL ? object->name.c_str() : "an unknown object", why);
    vector->numData = 0;
}

/* Queues `region` (a vector of `frames` frames, after its vectorInfo's `wait` frames: Sony's "delays
 * commands and the output of sound") for the subject that sent it; the subject is asked for more
 * when its queue has been played. */
void TakeVector(std::vector<Queue>& queues, const SubjectID& sender, RCRegion* region, longword frames) {
    Queue* queue = NULL;
    for (size_t i = 0; i < queues.size(); i++) {
        if (queues[i].subject == sender) queue = &queues[i];
    }
    if (queue == NULL) {
        queues.push_back(Queue());
        queue = &queues.back();
        queue->subject = sender;
    }
    region->AddReference();
    Playing playing = {region, 0, frames ? frames : 1, ((ODataVectorInfo*)region->Base())->wait};
    queue->vectors.push_back(playing);
}

/* One frame of each subject's first vector (`start`: at its first frame; `play`: what it commands),
 * or of its wait; a vector's last frame gives its region back and asks its subject for the next. */
void PlayQueues(OObserver* observer, std::vector<Queue>& queues, void (*start)(Playing&), void (*play)(Playing&)) {
    for (size_t q = 0; q < queues.size(); q++) {
        Queue& queue = queues[q];
        if (queue.vectors.empty()) continue;
        Playing& playing = queue.vectors.front();
        if (playing.wait > 0) {
            playing.wait--;
            continue;
        }
        if (start != NULL && playing.frame == 0) start(playing);
        if (play != NULL) play(playing);
        if (++playing.frame >= playing.frames) {
            playing.region->RemoveReference();
            queue.vectors.pop_front();
            if (queue.vectors.empty()) observer->AssertReady(queue.subject);
        }
    }
}

/* Whether one more frame of `queues` would finish a subject's last vector: it would then be asked
 * for the next (a message: object code runs). */
bool AsksForMore(const std::vector<Queue>& queues) {
    for (size_t q = 0; q < queues.size(); q++) {
        const std::deque<Playing>& vectors = queues[q].vectors;
        if (vectors.size() == 1 && vectors.front().wait == 0 && vectors.front().frame + 1 >= vectors.front().frames) {
            return true;
        }
    }
    return false;
}

/* PlayQueues on a copy of the queues (Lookahead): the same frame, without giving regions back. */
void Advance(std::vector<Queue>& queues, void (*play)(Playing&)) {
    for (size_t q = 0; q < queues.size(); q++) {
        std::deque<Playing>& vectors = queues[q].vectors;
        if (vectors.empty()) continue;
        if (vectors.front().wait > 0) {
            vectors.front().wait--;
            continue;
        }
        if (play != NULL) play(vectors.front());
        if (++vectors.front().frame >= vectors.front().frames) vectors.pop_front();
    }
}

/* The optional data the command and sound vectors bring, for the sensor vectors (Level2 Reference
 * Guide, ODataVectorInfo: the range optOffset, optSize of a sender's optional[] "is updated, and the
 * data is copied to optional[] of OSensorFrameVectorData"). When: from the vector's first frame on
 * (UNCONFIRMED); each sensor vector carries the bytes as the vectors left them, and the range last given. */
byte optional[odataOPTIONAL_MAX];
longword optionalOffset = 0, optionalSize = 0;

void TakeOptional(Playing& playing) {
    const ODataVectorInfo* info = (const ODataVectorInfo*)playing.region->Base();
    if (info->optSize == 0 || info->optOffset > odataOPTIONAL_MAX
        || info->optSize > odataOPTIONAL_MAX - info->optOffset) {
        return;
    }
    memcpy(optional + info->optOffset, info->optional + info->optOffset, info->optSize);
    optionalOffset = info->optOffset;
    optionalSize = info->optSize;
}

/* The effector's first frame of a command vector: each OCommandInfo's frameNumber is this frame's
 * (Sony: "the frame sequence number when the first frame is processed by the command"); its optional data. */
void StampCommands(Playing& playing) {
    OCommandVectorData* vector = (OCommandVectorData*)playing.region->Base();
    for (longword i = 0; i < vector->vectorInfo.numData; i++) vector->GetInfo((int)i)->frameNumber = FrameNumber();
    TakeOptional(playing);
}

/* The effector's frame of a command vector: each joint's and LED's value. */
void PlayCommands(Playing& playing) {
    OCommandVectorData* vector = (OCommandVectorData*)playing.region->Base();
    for (longword i = 0; i < vector->vectorInfo.numData; i++) {
        OCommandInfo* info = vector->GetInfo((int)i);
        slongword value, mode;
        if (Valid(info->primitiveID) && CommandAt(info, vector->GetData((int)i), playing.frame, &value, &mode)) {
            Command((int)info->primitiveID, value, mode);
        }
    }
}

class VirtualRobotComm : public OObject {
public:
    OSubject*  subject[2];
    OObserver* observer[1];
    std::vector<Queue> effector;

    enum { SENSOR, IMAGE };

    OStatus DoInit(const OSystemEvent&) {
        static const char* const subjects[2] = {"OVirtualRobotComm.Sensor.OSensorFrameVectorData.S",
                                                "OVirtualRobotComm.FbkImageSensor.OFbkImageVectorData.S"};
        for (int i = 0; i < 2; i++) {
            subject[i] = new OSubject();
            subject[i]->SetBufferSize(1);
            subject[i]->SetReadyEntry(OServiceEntry(myOID_, 6 + i));
            RegisterServiceEntry(OServiceEntry(myOID_, 4 + i), subjects[i]);
        }
        observer[0] = new OObserver();
        observer[0]->SetNotifyEntry(OServiceEntry(myOID_, 9));
        observer[0]->SetBufCtrlParam(0, 1, MAX_NUM_DATA + 1);  /* a program's primed vectors wait their turn */
        RegisterServiceEntry(OServiceEntry(myOID_, 8), "OVirtualRobotComm.Effector.OCommandVectorData.O");
        return oSUCCESS;
    }

    OStatus DoStart(const OSystemEvent&) {
        observer[0]->AssertReady();
        return oSUCCESS;
    }

    void NotifyEffector(const ONotifyEvent& event) {
        for (int i = 0; i < event.NumOfData(); i++) {
            RCRegion* region = event.RCData(i);
            RefuseMalformed(region, event.SenderID(), false);
            TakeVector(effector, event.SenderID(), region, CommandFrames((OCommandVectorData*)region->Base()));
        }
    }

    void PlayFrame() { PlayQueues(observer[0], effector, StampCommands, PlayCommands); }
};

class VirtualRobotAudioComm : public OObject {
public:
    OSubject*  subject[1];
    OObserver* observer[1];
    std::vector<Queue> speaker;
    longword cursor;   /* the sample (at AIBO_OPENR_SPEAKER_RATE) where the next sound starts */

    VirtualRobotAudioComm() : cursor(0) {}

    OStatus DoInit(const OSystemEvent&) {
        subject[0] = new OSubject();
        subject[0]->SetBufferSize(1);
        subject[0]->SetReadyEntry(OServiceEntry(myOID_, 5));
        RegisterServiceEntry(OServiceEntry(myOID_, 4), "OVirtualRobotAudioComm.Mic.OSoundVectorData.S");
        observer[0] = new OObserver();
        observer[0]->SetNotifyEntry(OServiceEntry(myOID_, 7));
        observer[0]->SetBufCtrlParam(0, 1, MAX_NUM_DATA + 1);  /* as the effector's */
        RegisterServiceEntry(OServiceEntry(myOID_, 6), "OVirtualRobotAudioComm.Speaker.OSoundVectorData.O");
        return oSUCCESS;
    }

    OStatus DoStart(const OSystemEvent&) {
        observer[0]->AssertReady();
        return oSUCCESS;
    }

    void NotifySpeaker(const ONotifyEvent& event) {
        for (int i = 0; i < event.NumOfData(); i++) {
            RefuseMalformed(event.RCData(i), event.SenderID(), true);
            Play(event.SenderID(), event.RCData(i));
        }
    }

    /* A sound vector's samples, at AIBO_OPENR_SPEAKER_RATE and 16 bits, recorded now for the
     * simulator as played from `cursor` (after the sounds before it) and its vectorInfo's `wait`
     * frames more, each OSoundInfo's frameNumber that first frame's; its region is held as long. */
    void Play(const SubjectID& sender, RCRegion* region) {
        OSoundVectorData* vector = (OSoundVectorData*)region->Base();
        std::vector<sword> samples;
        for (longword i = 0; i < vector->vectorInfo.numData; i++) {
            OSoundInfo* info = vector->GetInfo((int)i);
            bool eightBit = info->bitsPerSample == 8 || (info->bitsPerSample == 0 && soundType == ospksndMONO8K8B);
            word rate = info->samplingRate ? info->samplingRate : (eightBit ? 8000 : 16000);
            int repeat = rate < AIBO_OPENR_SPEAKER_RATE ? AIBO_OPENR_SPEAKER_RATE / rate : 1;
            const byte* data = vector->GetData((int)i);
            size_t count = eightBit ? info->dataSize : info->dataSize / 2;
            for (size_t k = 0; k < count; k++) {
                double value = eightBit ? (double)(sbyte)data[k] * 256 : (double)(sword)(data[2 * k] | data[2 * k + 1] << 8);
                value = speakerMuted ? 0 : value * speakerGain;
                for (int r = 0; r < repeat; r++) samples.push_back((sword)value);
            }
        }
        if (samples.empty()) samples.push_back(0);
        const longword perFrame = AIBO_OPENR_SPEAKER_RATE * 8 / 1000;
        longword now = FrameNumber() * perFrame;
        longword start = (cursor > now ? cursor : now) + vector->vectorInfo.wait * perFrame;
        cursor = start + (longword)samples.size();
        for (longword i = 0; i < vector->vectorInfo.numData; i++) vector->GetInfo((int)i)->frameNumber = start / perFrame;
        std::string payload((const char*)&start, sizeof start);
        payload.append((const char*)&samples[0], samples.size() * sizeof(sword));
        Record(AIBO_OPENR_RECORD_SOUND, payload.data(), payload.size());
        TakeVector(speaker, sender, region, (longword)((samples.size() + perFrame - 1) / perFrame));
    }

    void PlayFrame() {
        PlayQueues(observer[0], speaker, TakeOptional, NULL);
        if (micIndex >= 0 && subject[0]->NumberOfObservers() > 0 && FrameNumber() % AIBO_OPENR_SENSOR_FRAMES == 0) {
            SendSilence();
        }
    }

    /* 32 ms of 16 kHz 16-bit stereo silence: what the microphones hear here. */
    void SendSilence() {
        const size_t bytes = 512 * sizeof(OSoundSampleStereo16);
        RCRegion* region = new RCRegion(sizeof(ODataVectorInfo) + sizeof(OSoundInfo) + bytes);
        OSoundVectorData* vector = (OSoundVectorData*)region->Base();
        vector->vectorInfo.memRegionID = region->MemID();
        vector->vectorInfo.totalSize = (longword)region->Size();
        vector->vectorInfo.type = odataSOUND_VECTOR;
        vector->vectorInfo.infoOffset = sizeof(ODataVectorInfo);
        vector->vectorInfo.infoSize = sizeof(OSoundInfo);
        vector->vectorInfo.maxNumData = vector->vectorInfo.numData = 1;
        OSoundInfo* info = vector->GetInfo(0);
        info->Set(odataSOUND, (OPrimitiveID)micIndex, bytes);
        info->frameNumber = FrameNumber();
        info->dataOffset = sizeof(ODataVectorInfo) + sizeof(OSoundInfo);
        info->maxDataSize = info->actualDataSize = (longword)bytes;
        info->format = osoundformatPCM;
        info->channel = osoundchannelSTEREO;
        info->samplingRate = 16000;
        info->bitsPerSample = 16;
        subject[0]->SetData(region);
        subject[0]->NotifyObservers();
        region->RemoveReference();
    }
};

/* The system objects' entries, numbered as stubgen2 numbers a generated object's. */
#define SYSTEM_HOOKS(Class, self) \
    void Class##Init(OReasonMessage* m) { self->Init(OSystemEvent(m->reason, m->param, m->paramSize)); } \
    void Class##Start(OReasonMessage* m) { self->Start(OSystemEvent(m->reason, m->param, m->paramSize)); } \
    void Class##Stop(OReasonMessage* m) { self->Stop(OSystemEvent(m->reason, m->param, m->paramSize)); } \
    void Class##Destroy(OReasonMessage* m) { self->Destroy(OSystemEvent(m->reason, m->param, m->paramSize)); }

SYSTEM_HOOKS(Robot, robotComm)
void RobotControl0(OControlMessage* m) { robotComm->subject[0]->ControlHandler(*m); }
void RobotControl1(OControlMessage* m) { robotComm->subject[1]->ControlHandler(*m); }
void RobotReady0(OReadyMessage* m) { robotComm->subject[0]->ReadyHandler(*m); }
void RobotReady1(OReadyMessage* m) { robotComm->subject[1]->ReadyHandler(*m); }
void RobotConnect0(OConnectMessage* m) { robotComm->observer[0]->ConnectHandler(*m); }
void RobotNotify0(ONotifyMessage* m) {
    ONotifyEvent event;
    robotComm->observer[0]->NotifyHandler(*m, &event);
    robotComm->NotifyEffector(event);
}

SYSTEM_HOOKS(Audio, audioComm)
void AudioControl0(OControlMessage* m) { audioComm->subject[0]->ControlHandler(*m); }
void AudioReady0(OReadyMessage* m) { audioComm->subject[0]->ReadyHandler(*m); }
void AudioConnect0(OConnectMessage* m) { audioComm->observer[0]->ConnectHandler(*m); }
void AudioNotify0(ONotifyMessage* m) {
    ONotifyEvent event;
    audioComm->observer[0]->NotifyHandler(*m, &event);
    audioComm->NotifySpeaker(event);
}

const ObjectEntry robotEntries[] = {
    {0, (Entry)RobotInit}, {1, (Entry)RobotStart}, {2, (Entry)RobotStop}, {3, (Entry)RobotDestroy},
    {4, (Entry)RobotControl0}, {5, (Entry)RobotControl1}, {6, (Entry)RobotReady0}, {7, (Entry)RobotReady1},
    {8, (Entry)RobotConnect0}, {9, (Entry)RobotNotify0}, {UNDEF, (Entry)ENTRY_UNDEF}};

const ObjectEntry audioEntries[] = {
    {0, (Entry)AudioInit}, {1, (Entry)AudioStart}, {2, (Entry)AudioStop}, {3, (Entry)AudioDestroy},
    {4, (Entry)AudioControl0}, {5, (Entry)AudioReady0}, {6, (Entry)AudioConnect0}, {7, (Entry)AudioNotify0},
    {UNDEF, (Entry)ENTRY_UNDEF}};

/* Images made here from the simulator's Y, Cr, Cb frame: the message openr_bridge.encoder's
 * encode_ycrcb makes of a frame of the H layer's size, byte for byte (the header and infos;
 * H: the frame's Y, Cr, Cb and flat detail bands; M and L: pyramid.next_level's Haar bands and
 * 2x2 means; C: cdt_layer's bits of M's Y, Cr, Cb; the tag in the last row of H, M, L and C);
 * tests/test_openr_runtime.py compares every image of runs with and without colour tables. */
const int IMAGE_W = AIBO_OPENR_IMAGE_WIDTH, IMAGE_H = AIBO_OPENR_IMAGE_HEIGHT;
OPENR_STATIC_ASSERT(IMAGE_W % 4 == 0 && IMAGE_H % 4 == 0, image_in_blocks_of_four);
const struct { int width, height, runs; ODataType type; } IMAGE_LAYERS[4] = {
    {IMAGE_W, IMAGE_H, 6, odataFBK_YCrCb_HPF},
    {IMAGE_W / 2, IMAGE_H / 2, 6, odataFBK_YCrCb_HPF},
    {IMAGE_W / 4, IMAGE_H / 4, 6, odataFBK_YCrCb_HPF},
    {IMAGE_W / 2, IMAGE_H / 2, 1, odataFBK_CDT}};
const size_t IMAGE_HEADER = sizeof(ODataVectorInfo) + 4 * sizeof(OFbkImageInfo);
const size_t IMAGE_BYTES = IMAGE_HEADER + (size_t)IMAGE_W * IMAGE_H * 6 + (size_t)IMAGE_W * IMAGE_H / 4 * 6
                         + (size_t)IMAGE_W * IMAGE_H / 16 * 6 + (size_t)IMAGE_W * IMAGE_H / 4;

#if defined(__GNUC__) && !defined(__clang__)
#define IMAGE_LOOP __attribute__((optimize("O3")))  /* the library is -O2: vectorise these loops */
#else
#define IMAGE_LOOP
#endif

/* H: the frame's Y, Cr, Cb (interleaved) as the rows' first three runs, four pixels (three
 * little-endian words) at a time; the detail runs flat. */
IMAGE_LOOP void LayerH(const byte* __restrict__ pixels, byte* __restrict__ layer) {
    for (int y = 0; y < IMAGE_H; y++) {
        byte* __restrict__ row = layer + (size_t)y * 6 * IMAGE_W;
        const byte* __restrict__ from = pixels + (size_t)y * IMAGE_W * 3;
        for (int x = 0; x < IMAGE_W; x += 4) {
            uint32_t w[3];
            memcpy(w, from + 3 * x, sizeof w);
            uint32_t Y = (w[0] & 0xFF) | (w[0] >> 24) << 8 | (w[1] >> 16 & 0xFF) << 16 | (w[2] >> 8 & 0xFF) << 24;
            uint32_t Cr = (w[0] >> 8 & 0xFF) | (w[1] & 0xFF) << 8 | (w[1] >> 24) << 16 | (w[2] >> 16 & 0xFF) << 24;
            uint32_t Cb = (w[0] >> 16 & 0xFF) | (w[1] >> 8 & 0xFF) << 8 | (w[2] & 0xFF) << 16 | (w[2] >> 24) << 24;
            memcpy(row + x, &Y, 4);
            memcpy(row + IMAGE_W + x, &Cr, 4);
            memcpy(row + 2 * IMAGE_W + x, &Cb, 4);
        }
        memset(row + 3 * IMAGE_W, 128, 3 * IMAGE_W);
    }
}

/* pyramid.next_level: the layer `dst` (width w, height h; rows of 6 runs) from `src`, twice its
 * size: the Haar bands of its Y (clipped to 255) and the 2x2 means of its Cr and Cb. */
IMAGE_LOOP void NextLevel(const byte* __restrict__ src, byte* __restrict__ dst, int w, int h) {
    const int sw = 2 * w;
    for (int y = 0; y < h; y++) {
        const byte* __restrict__ top = src + (size_t)(2 * y) * 6 * sw;
        const byte* __restrict__ bottom = top + 6 * sw;
        byte* __restrict__ row = dst + (size_t)y * 6 * w;
        for (int x = 0; x < w; x++) {
            int p00 = top[2 * x], p10 = top[2 * x + 1], p01 = bottom[2 * x], p11 = bottom[2 * x + 1];
            int lh = 128 + ((p01 + p11 - p00 - p10 + 2) >> 2), hl = 128 + ((p10 + p11 - p00 - p01 + 2) >> 2);
            int hh = 128 + ((p00 + p11 - p10 - p01 + 2) >> 2);
            row[x] = (byte)((p00 + p10 + p01 + p11 + 2) >> 2);
            row[3 * w + x] = (byte)(lh < 255 ? lh : 255);
            row[4 * w + x] = (byte)(hl < 255 ? hl : 255);
            row[5 * w + x] = (byte)(hh < 255 ? hh : 255);
        }
        for (int c = 1; c <= 2; c++) {
            const byte* __restrict__ t = top + c * sw;
            const byte* __restrict__ b = bottom + c * sw;
            byte* __restrict__ out = row + c * w;
            for (int x = 0; x < w; x++) out[x] = (byte)((t[2 * x] + t[2 * x + 1] + b[2 * x] + b[2 * x + 1] + 2) >> 2);
        }
    }
}

/* cdt_layer: bit k of a C pixel where channel k's Cr/Cb box of its Y segment (not ocdtINIT)
 * holds M's pixel, bounds inclusive. */
IMAGE_LOOP void LayerC(const byte* __restrict__ m, byte* __restrict__ c, int w, int h, const OCdtVectorData* cdt) {
    memset(c, 0, (size_t)w * h);
    for (longword n = 0; cdt != NULL && n < cdt->vectorInfo.numData && n < (longword)ocdtNUM_CHANNELS; n++) {
        const OCdtInfo& info = cdt->info[n];
        int k = 0;
        while (k < ocdtNUM_CHANNELS - 1 && !(info.channel & (1u << k))) k++;
        for (int y = 0; y < h; y++) {
            const byte* __restrict__ row = m + (size_t)y * 6 * w;
            byte* __restrict__ bits = c + (size_t)y * w;
            for (int x = 0; x < w; x++) {
                longword box = info.table[row[x] >> 3];
                longword cr = row[w + x], cb = row[2 * w + x];
                bool inside = box != ocdtINIT && cr >= (box & 0xFF) && cr <= (box >> 8 & 0xFF)
                           && cb >= (box >> 16 & 0xFF) && cb <= (box >> 24);
                bits[x] |= (byte)((inside ? 1u : 0u) << k);
            }
        }
    }
}

void BuildImage(byte* out, const byte* pixels, const ImageFrame& frame, const OCdtVectorData* cdt) {
    memset(out, 0, IMAGE_HEADER);
    OFbkImageVectorData* image = (OFbkImageVectorData*)out;
    image->vectorInfo.totalSize = (longword)IMAGE_BYTES;
    image->vectorInfo.type = odataFBKIMAGE_VECTOR;
    image->vectorInfo.infoOffset = sizeof(ODataVectorInfo);
    image->vectorInfo.infoSize = sizeof(OFbkImageInfo);
    image->vectorInfo.maxNumData = image->vectorInfo.numData = 4;
    byte* layer[4];
    size_t offset = IMAGE_HEADER;
    for (int i = 0; i < 4; i++) {
        OFbkImageInfo* info = &image->info[i];
        size_t size = (size_t)IMAGE_LAYERS[i].width * IMAGE_LAYERS[i].height * IMAGE_LAYERS[i].runs;
        info->type = IMAGE_LAYERS[i].type;
        info->frameNumber = frame.frameNumber;
        info->dataOffset = (longword)offset;
        info->dataSize = (longword)size;
        info->width = IMAGE_LAYERS[i].width;
        info->height = IMAGE_LAYERS[i].height;
        layer[i] = out + offset;
        offset += size;
    }
    LayerH(pixels, layer[0]);
    NextLevel(layer[0], layer[1], IMAGE_W / 2, IMAGE_H / 2);
    NextLevel(layer[1], layer[2], IMAGE_W / 4, IMAGE_H / 4);
    LayerC(layer[1], layer[3], IMAGE_W / 2, IMAGE_H / 2, cdt);
    longword pixelsIn[ocdtNUM_CHANNELS] = {0};  /* the tag: each channel's pixels / 16 */
    if (cdt != NULL && cdt->vectorInfo.numData > 0) {  /* else C is all 0 */
        longword values[4][256] = {{0}};  /* four histograms: no increment waits for the one before */
        for (int i = 0; i < IMAGE_W / 2 * IMAGE_H / 2; i++) values[i & 3][layer[3][i]]++;
        for (int v = 1; v < 256; v++) {
            longword n = values[0][v] + values[1][v] + values[2][v] + values[3][v];
            for (int k = 0; k < ocdtNUM_CHANNELS; k++) pixelsIn[k] += (v >> k & 1) ? n : 0;
        }
    }
    byte tag[AIBO_OPENR_TAG_LENGTH] = {(byte)(frame.fieldCounter & 0xFF), (byte)(frame.fieldCounter >> 8 & 0xFF), 0, 0};
    for (int k = 0; k < ocdtNUM_CHANNELS; k++) {  /* bytes 4-7 channels 4-7, 8-11 channels 0-3 */
        longword frequency = pixelsIn[k] / 16;
        tag[k < 4 ? 8 + k : k] = (byte)(frequency < 255 ? frequency : 255);
    }
    for (int i = 0; i < 4; i++) {  /* last: into the first bytes of each layer's last row */
        size_t row = (size_t)IMAGE_LAYERS[i].width * IMAGE_LAYERS[i].runs;
        memcpy(layer[i] + row * (IMAGE_LAYERS[i].height - 1), tag, sizeof tag);
    }
}

void PublishSensors() {
    size_t count = sensorOrder.size();
    size_t infos = sizeof(ODataVectorInfo) + count * sizeof(OSensorFrameInfo);
    RCRegion* region = new RCRegion(infos + count * sizeof(OSensorFrameData));
    OSensorFrameVectorData* vector = (OSensorFrameVectorData*)region->Base();
    vector->vectorInfo.memRegionID = region->MemID();
    vector->vectorInfo.totalSize = (longword)region->Size();
    vector->vectorInfo.type = odataSENSOR_FRAME_VECTOR;
    vector->vectorInfo.infoOffset = sizeof(ODataVectorInfo);
    vector->vectorInfo.infoSize = sizeof(OSensorFrameInfo);
    vector->vectorInfo.maxNumData = vector->vectorInfo.numData = (longword)count;
    vector->vectorInfo.optOffset = optionalOffset;
    vector->vectorInfo.optSize = optionalSize;
    memcpy(vector->vectorInfo.optional, optional, sizeof optional);
    static const ODataType types[] = {odataUNDEF, odataJOINT_VALUE, odataLENGTH, odataACCELERATION, odataSWITCH,
                                      odataNO_DIMENSION};
    for (size_t i = 0; i < count; i++) {
        OSensorFrameInfo* info = vector->GetInfo((int)i);
        info->Set(types[sensorKinds[i]], (OPrimitiveID)sensorOrder[i], pending.size());
        info->frameNumber = pendingFrame;
        info->frameSize = sizeof(OSensorValue);
        info->dataOffset = (longword)(infos + i * sizeof(OSensorFrameData));
        info->dataSize = sizeof(OSensorFrameData);
        OSensorFrameData* data = vector->GetData((int)i);
        for (size_t f = 0; f < pending.size(); f++) {
            const slongword* v = &pending[f][i * AIBO_OPENR_VALUES_PER_SENSOR];
            if (sensorKinds[i] == AIBO_OPENR_SENSOR_JOINT) {
                OJointValue* joint = (OJointValue*)&data->frame[f];
                *joint = OJointValue(v[0], (word)v[1], (sword)v[2], v[3], 0);
            } else {
                data->frame[f].value = v[0];
                data->frame[f].signal = (word)v[1];
            }
        }
    }
    OSubject* sensor = robotComm->subject[VirtualRobotComm::SENSOR];
    sensor->SetData(region);
    sensor->NotifyObservers();
    region->RemoveReference();
    pending.clear();
}

int SensorEntry(OPrimitiveID id) { return Valid(id) ? sensorIndexOf[id] : -1; }

}  // namespace

void SetRobot(const std::string& robotDesign, const std::vector<Primitive>& table, const std::vector<int>& order,
              int camera, int speakerPrimitive, int mic) {
    design = robotDesign;
    primitives = table;
    for (size_t i = 0; i < primitives.size(); i++) primitives[i].type = TypeNamed(primitives[i].locator);
    sensorOrder.clear();
    sensorKinds.clear();
    for (size_t i = 0; i < order.size(); i += 2) {
        sensorOrder.push_back(order[i]);
        sensorKinds.push_back(order[i + 1]);
    }
    sensorIndexOf.assign(primitives.size(), -1);
    for (size_t i = 0; i < sensorOrder.size(); i++) sensorIndexOf[sensorOrder[i]] = (int)i;
    latest.assign(sensorOrder.size() * AIBO_OPENR_VALUES_PER_SENSOR, 0);
    opened.assign(primitives.size(), false);
    cameraIndex = camera;
    speakerIndex = speakerPrimitive;
    micIndex = mic;
}

void SetDesignData(const std::map<std::string, std::string>& data) { designData = data; }

void StartSystemObjects() {
    SetConstructing(AddObject("OVirtualRobotComm", robotEntries, true));
    robotComm = new VirtualRobotComm();
    SetConstructing(AddObject("OVirtualRobotAudioComm", audioEntries, true));
    audioComm = new VirtualRobotAudioComm();
    SetConstructing(NULL);
}

void SetLatestValues(const std::vector<slongword>& values) { latest = values; }

void SetFrameValues(const slongword* values) {
    latest.assign(values, values + sensorOrder.size() * AIBO_OPENR_VALUES_PER_SENSOR);
    if (pending.empty()) pendingFrame = FrameNumber();
    pending.push_back(latest);
    if (pending.size() == AIBO_OPENR_SENSOR_FRAMES) PublishSensors();
}

void SetImageSlots(char* slots) { imageSlots = slots; }

void PublishImage(longword slot, size_t size, const ImageFrame* frame) {
    char* bytes = imageSlots + (size_t)slot * AIBO_OPENR_MAX_IMAGE_BYTES;
    if (frame != NULL) size = IMAGE_BYTES;
    if (slot < AIBO_OPENR_IMAGE_SLOTS) PlaceNextRegion(bytes);  /* the region is the slot: no copy */
    RCRegion* region = new RCRegion(size);
    if (slot < AIBO_OPENR_IMAGE_SLOTS) {
        slotImage[slot] = region->MemID();
    } else if (frame == NULL) {
        memcpy(region->Base(), bytes, size);
    }
    if (frame != NULL) {
        const byte* pixels = (const byte*)imageSlots + (size_t)AIBO_OPENR_IMAGE_SLOTS * AIBO_OPENR_MAX_IMAGE_BYTES;
        BuildImage((byte*)region->Base(), pixels, *frame, cdtSet ? &cdtInUse : NULL);
    }
    OFbkImageVectorData* image = (OFbkImageVectorData*)region->Base();
    image->vectorInfo.memRegionID = region->MemID();
    if (cameraIndex >= 0) image->SetPrimitiveID((OPrimitiveID)cameraIndex);
    OSubject* fbk = robotComm->subject[VirtualRobotComm::IMAGE];
    fbk->SetData(region);
    fbk->NotifyObservers();
    region->RemoveReference();
}

void AnnounceImageSlot() {
    slongword slot = 0;  /* a slot whose image's region is gone, else the copying one */
    while (slot < AIBO_OPENR_IMAGE_SLOTS && slotImage[slot] != 0 && RegionBase(slotImage[slot]) != NULL) slot++;
    if (slot != announcedSlot) {
        announcedSlot = slot;
        RecordValues(AIBO_OPENR_RECORD_IMAGE_SLOT, &slot, 1);
    }
}

void SetPowerStatus(const OPowerStatus& status) {
    OPowerStatus before = power;
    power = status;
    power.robotStatus = motorPower ? power.robotStatus | orsbMOTOR_POWER : power.robotStatus & ~orsbMOTOR_POWER;
    NotifyPower(before);
}

void PlayFrame() {
    robotComm->PlayFrame();
    audioComm->PlayFrame();
}

void StopRun() {
    stopped = true;
    Record(AIBO_OPENR_RECORD_SHUTDOWN, "", 0);
}

/* aibo-sim's extension for the wrapper object (which declares it weak: the robot has none): its
 * controller failed, so the run does too, not only the robot's shutdown that follows. */
extern "C" void aibo_sim_controller_failed(const char* message) {
    Record(AIBO_OPENR_RECORD_CONTROLLER_FAILED, message, strlen(message));
}

/* Another: its controller's camera took the image of this frame number (the run's --out writes it). */
extern "C" void aibo_sim_camera_captured(longword frameNumber) {
    Record(AIBO_OPENR_RECORD_CAMERA_CAPTURED, &frameNumber, sizeof frameNumber);
}

std::vector<std::string> Lookahead(longword frame, size_t limit) {
    std::vector<std::string> frames;
    if (stopped || !MailboxEmpty()) return frames;
    /* What would send a message in a coming frame: a sensor vector for an observer, the
     * microphone's 32 ms, a subject's last vector played (its ready event). Images and power
     * events come from the simulator, which knows when they come and answers before them. */
    bool sensorsObserved = robotComm->subject[VirtualRobotComm::SENSOR]->NumberOfObservers() > 0;
    bool micObserved = micIndex >= 0 && audioComm->subject[0]->NumberOfObservers() > 0;
    std::vector<Queue> effector, speaker;
    std::map<int, slongword> before;
    for (size_t ahead = 1; ahead <= limit; ahead++) {
        frame = frame >= oframeMAX_NUMBER ? 1 : frame + 1;
        if (sensorsObserved && (pending.size() + ahead) % AIBO_OPENR_SENSOR_FRAMES == 0) break;
        if (micObserved && frame % AIBO_OPENR_SENSOR_FRAMES == 0) break;
        if (ahead == 1) {  /* the queues as they are now, copied: this frame's play changes nothing */
            effector = robotComm->effector;
            speaker = audioComm->speaker;
        }
        if (AsksForMore(effector) || AsksForMore(speaker)) break;
        if (ahead == 1) before = commanded;
        Advance(effector, PlayCommands);
        Advance(speaker, NULL);
        frames.push_back(TakeRecords());
    }
    if (!frames.empty()) commanded.swap(before);  /* Command's memory of what it recorded, as it was */
    return frames;
}

}  // namespace host

using namespace host;

/* OFbkImage: a band of a layer of the image vector. */
OFbkImage::OFbkImage(OFbkImageInfo* info, byte* data, OFbkImageBand band)
    : image_(0), width_(0), height_(0), skip_(0) {
    if (info == NULL || data == NULL) return;
    int runs, run;
    if (info->type == odataFBK_YCrCb_HPF) {
        static const int hpf[] = {0, 1, 2, -1, 3, 4, 5};
        runs = 6;
        run = band < 7 ? hpf[band] : -1;
    } else if (info->type == odataFBK_YCrCb) {
        runs = 3;
        run = band < 3 ? (int)band : -1;
    } else if (info->type == odataFBK_CDT) {
        runs = 1;
        run = band == ofbkimageBAND_CDT ? 0 : -1;
    } else {
        return;
    }
    if (run < 0) return;
    width_ = (int)info->width;
    height_ = (int)info->height;
    skip_ = (runs - 1) * width_;
    image_ = data + run * width_;
}

longword OFbkImage::GetTagInfo() {
    const byte* tag = Tag();
    return (longword)tag[0] | (longword)tag[1] << 8 | (longword)tag[2] << 16 | (longword)tag[3] << 24;
}

void OPowerStatus::Print() const {
    osysprint("robotStatus 0x%08x batteryStatus 0x%04x remainingCapacity %d %%\n", (unsigned)robotStatus,
              (unsigned)batteryStatus, (int)remainingCapacity);
}

void OPowerStatus::PrintDetail() const {
    Print();
    osysprint("temperature %d fullyChargedCapacity %d voltage %d current %d timeDif %d volume %d\n", (int)temperature,
              (int)fullyChargedCapacity, (int)voltage, (int)current, (int)timeDif, (int)volume);
}

/* The OPENR:: calls. */

OStatus OPENR::OpenPrimitive(const char* locator, OPrimitiveID* id) {
    if (id != NULL) *id = oprimitiveID_UNDEF; /* Sony: "If it fails, oprimitiveID_UNDEF is returned" */
    if (locator == NULL || id == NULL) return oINVALID_ARG;
    for (size_t i = 0; i < primitives.size(); i++) {
        if (primitives[i].locator == locator) {
            opened[i] = true;
            *id = (OPrimitiveID)i;
            return oSUCCESS;
        }
    }
    return oNOT_FOUND;
}

OStatus OPENR::ClosePrimitive(OPrimitiveID id) {
    if (!Valid(id) || !opened[id]) return oINVALID_PRIMITIVE_ID;
    opened[id] = false;
    return oSUCCESS;
}

static OStatus CameraParam(void* param, size_t size, longword* value) {
    if (param == NULL || size != sizeof(OPrimitiveControl_CameraParam)) return oINVALID_ARG;
    *value = ((OPrimitiveControl_CameraParam*)param)->camparam;
    return *value >= 1 && *value <= 3 ? oSUCCESS : oINVALID_ARG;
}

OStatus OPENR::ControlPrimitive(OPrimitiveID id, OPrimitiveRequest request, void* param, size_t paramSize,
                                void* result, size_t resultSize) {
    if (!Valid(id) || !opened[id]) return oINVALID_PRIMITIVE_ID;
    OPrimitiveType type = primitives[id].type;
    if (type == oprimitiveFBKIMAGESENSOR) {
        if (request == oprmreqCAM_SET_WHITE_BALANCE || request == oprmreqCAM_SET_GAIN
            || request == oprmreqCAM_SET_SHUTTER_SPEED) {
            longword value;
            OStatus status = CameraParam(param, paramSize, &value);
            if (status != oSUCCESS) return status;
            slongword camera[2] = {(slongword)request, (slongword)value};
            RecordValues(AIBO_OPENR_RECORD_CAMERA, camera, 2);
            return oSUCCESS;
        }
        return request >= oprmreqCAM_GET_CDT_TABLE && request <= oprmreqCAM_AWB_OFF ? oNOT_SUPPORTED : oINVALID_ARG;
    }
    if (type == oprimitiveSPEAKER) {
        if (request == oprmreqSPEAKER_MUTE_ON || request == oprmreqSPEAKER_MUTE_OFF) {
            speakerMuted = request == oprmreqSPEAKER_MUTE_ON;
            return oSUCCESS;
        }
        if (request == oprmreqSPEAKER_SET_VOLUME) {
            if (param == NULL || paramSize < sizeof(OPrimitiveControl_SpeakerVolume)) return oINVALID_ARG;
            longword volume = ((OPrimitiveControl_SpeakerVolume*)param)->volume;
            double db = volume == ospkvolinfdB ? -1e9 : (double)(sword)(word)volume / 256.0;
            speakerGain = db < -200 ? 0.0 : pow(10.0, (db + 10.0) / 20.0);  /* ospkvol10dB plays as recorded */
            return oSUCCESS;
        }
        if (request == oprmreqSPEAKER_SET_SOUND_TYPE) {
            if (param == NULL || paramSize < sizeof(OPrimitiveControl_SpeakerSoundType)) return oINVALID_ARG;
            soundType = ((OPrimitiveControl_SpeakerSoundType*)param)->type;
            return oSUCCESS;
        }
        if (request == oprmreqSPEAKER_GET_SOUND_TYPE) {
            void* out = result != NULL ? result : param;
            size_t outSize = result != NULL ? resultSize : paramSize;
            if (out == NULL || outSize < sizeof(OPrimitiveControl_SpeakerSoundType)) return oINVALID_ARG;
            ((OPrimitiveControl_SpeakerSoundType*)out)->type = soundType;
            return oSUCCESS;
        }
        return oINVALID_ARG;
    }
    if (type == oprimitiveMIC) {
        return request >= oprmreqMIC_UNI && request <= oprmreqMIC_ALC_OFF ? oSUCCESS : oINVALID_ARG;
    }
    if (type == oprimitiveJOINT2 && request == oprmreqJOINT2_SET_COMMAND) {
        if (param == NULL || paramSize < sizeof(OPrimitiveControl_JointCommandValue2)) return oINVALID_ARG;
        Command((int)id, ((OPrimitiveControl_JointCommandValue2*)param)->command.value);
        return oSUCCESS;
    }
    if (type == oprimitiveJOINT2 && request == oprmreqJOINT2_GET_VALUE) {
        if (result == NULL || resultSize < sizeof(OPrimitiveControl_JointValue)) return oINVALID_ARG;
        return GetJointValue(id, &((OPrimitiveControl_JointValue*)result)->jval);
    }
    if (type == oprimitiveJOINT4 && request == oprmreqJOINT4_SET_COMMAND) {
        if (param == NULL || paramSize < sizeof(OPrimitiveControl_JointCommandValue4)) return oINVALID_ARG;
        Command((int)id, (slongword)((OPrimitiveControl_JointCommandValue4*)param)->command.value);
        return oSUCCESS;
    }
    if (type == oprimitiveLED2 && request == oprmreqLED2_SET_COMMAND) {
        if (param == NULL || paramSize < sizeof(OPrimitiveControl_LEDCommandValue2)) return oINVALID_ARG;
        Command((int)id, ((OPrimitiveControl_LEDCommandValue2*)param)->command.led == oledON ? 255 : 0);
        return oSUCCESS;
    }
    if (type == oprimitiveLED3 && request == oprmreqLED3_SET_COMMAND) {
        if (param == NULL || paramSize < sizeof(OPrimitiveControl_LEDCommandValue3)) return oINVALID_ARG;
        OLEDCommandValue3& led = ((OPrimitiveControl_LEDCommandValue3*)param)->command;
        Command((int)id, led.intensity, led.mode);
        return oSUCCESS;
    }
    return oINVALID_ARG;
}

static void FillVectorInfo(ODataVectorInfo* info, MemoryRegionID id, size_t total, ODataType type, size_t infoSize,
                           size_t count) {
    info->memRegionID = id;
    info->totalSize = (longword)total;
    info->type = type;
    info->infoOffset = sizeof(ODataVectorInfo);
    info->infoSize = (longword)infoSize;
    info->maxNumData = (longword)count;
    info->numData = 0;
}

/* A vector's region, its header and `count` infos of `infoSize` bytes each followed by data of
 * `dataSize`: oNO_MEMORY (Sony's "fails to reserve shared memory") where its size overflows the
 * longwords that describe it or the memory is not there (a bad_alloc killed the object). */
OStatus NewVectorRegion(size_t count, size_t infoSize, size_t dataSize, MemoryRegionID* memID, void** memory) {
    const size_t most = 0xFFFFFFFFu;
    if (count > (most - sizeof(ODataVectorInfo)) / (infoSize + dataSize)) return oNO_MEMORY;
    try {
        *memID = NewRegion(sizeof(ODataVectorInfo) + count * (infoSize + dataSize), memory);
    } catch (const std::bad_alloc&) {
        return oNO_MEMORY;
    }
    return oSUCCESS;
}

OStatus OPENR::NewCommandVectorData(size_t count, MemoryRegionID* memID, OCommandVectorData** base) {
    if (memID == NULL || base == NULL || count == 0) return oINVALID_ARG;
    size_t infos = sizeof(ODataVectorInfo) + count * sizeof(OCommandInfo);
    size_t total = infos + count * sizeof(OCommandData);
    void* memory;
    OStatus made = NewVectorRegion(count, sizeof(OCommandInfo), sizeof(OCommandData), memID, &memory);
    if (made != oSUCCESS) return made;
    *base = (OCommandVectorData*)memory;
    FillVectorInfo(&(*base)->vectorInfo, *memID, total, odataCOMMAND_VECTOR, sizeof(OCommandInfo), count);
    for (size_t i = 0; i < count; i++) {
        OCommandInfo* info = (*base)->GetInfo((int)i);
        info->type = odataUNDEF;
        info->primitiveID = oprimitiveID_UNDEF;
        info->frameSize = sizeof(OCommandValue);
        info->dataOffset = (longword)(infos + i * sizeof(OCommandData));
        info->dataSize = sizeof(OCommandData);
    }
    return oSUCCESS;
}

OStatus OPENR::DeleteCommandVectorData(MemoryRegionID memID) {
    if (RegionBase(memID) == NULL) return oFAIL;
    DeleteRegion(memID);
    return oSUCCESS;
}

OStatus OPENR::NewSoundVectorData(size_t count, size_t dataSize, MemoryRegionID* memID, OSoundVectorData** base) {
    if (memID == NULL || base == NULL || count == 0) return oINVALID_ARG;
    size_t infos = sizeof(ODataVectorInfo) + count * sizeof(OSoundInfo);
    size_t total = infos + count * dataSize;
    void* memory;
    OStatus made = NewVectorRegion(count, sizeof(OSoundInfo), dataSize, memID, &memory);
    if (made != oSUCCESS) return made;
    *base = (OSoundVectorData*)memory;
    FillVectorInfo(&(*base)->vectorInfo, *memID, total, odataSOUND_VECTOR, sizeof(OSoundInfo), count);
    for (size_t i = 0; i < count; i++) {
        OSoundInfo* info = (*base)->GetInfo((int)i);
        info->dataOffset = (longword)(infos + i * dataSize);
        info->maxDataSize = (longword)dataSize;
        info->format = osoundformatPCM;
        info->channel = osoundchannelMONO;
    }
    return oSUCCESS;
}

OStatus OPENR::DeleteSoundVectorData(MemoryRegionID memID) {
    if (RegionBase(memID) == NULL) return oINVALID_ARG;
    DeleteRegion(memID);
    return oSUCCESS;
}

static OStatus ForJoints(OPrimitiveID id, OStatus (*action)(int)) {
    if (id != oprimitiveID_UNDEF) {
        if (!Valid(id) || !opened[id] || primitives[id].type != oprimitiveJOINT2) return oINVALID_PRIMITIVE_ID;
        return action((int)id);
    }
    OStatus status = oSUCCESS;
    for (size_t i = 0; i < primitives.size(); i++) {
        if (opened[i] && primitives[i].type == oprimitiveJOINT2) {
            OStatus one = action((int)i);
            if (one != oSUCCESS) status = one;
        }
    }
    return status;
}

static OStatus Enable(int joint) {
    gains[joint].enabled = true;
    return oSUCCESS;
}

static OStatus Disable(int joint) {
    Gain& gain = gains[joint];
    gain.enabled = false;
    memset(gain.values, 0, sizeof gain.values);
    RecordGain(joint);
    return oSUCCESS;
}

static word pendingGain[6];

static OStatus SetGain(int joint) {
    Gain& gain = gains[joint];
    if (!gain.enabled) return oGAIN_DISABLED;
    memcpy(gain.values, pendingGain, sizeof gain.values);
    RecordGain(joint);
    return oSUCCESS;
}

static OStatus RegisterDefault(int joint) {
    Gain& gain = gains[joint];
    gain.hasDefault = true;
    memcpy(gain.defaults, pendingGain, sizeof gain.defaults);
    return oSUCCESS;
}

static OStatus SetDefault(int joint) {
    Gain& gain = gains[joint];
    if (!gain.enabled) return oGAIN_DISABLED;
    if (!gain.hasDefault) return oNOT_REGISTERED;
    memcpy(gain.values, gain.defaults, sizeof gain.values);
    RecordGain(joint);
    return oSUCCESS;
}

OStatus OPENR::EnableJointGain(OPrimitiveID id) { return ForJoints(id, Enable); }
OStatus OPENR::DisableJointGain(OPrimitiveID id) { return ForJoints(id, Disable); }

OStatus OPENR::SetJointGain(OPrimitiveID id, word pg, word ig, word dg, word ps, word is, word ds) {
    word values[6] = {pg, ig, dg, ps, is, ds};
    memcpy(pendingGain, values, sizeof values);
    return ForJoints(id, SetGain);
}

OStatus OPENR::RegisterDefaultJointGain(OPrimitiveID id, word pg, word ig, word dg, word ps, word is, word ds) {
    word values[6] = {pg, ig, dg, ps, is, ds};
    memcpy(pendingGain, values, sizeof values);
    return ForJoints(id, RegisterDefault);
}

OStatus OPENR::SetDefaultJointGain(OPrimitiveID id) { return ForJoints(id, SetDefault); }

/* The six gain registers into pg..ds, or zeros with `status` when it is not oSUCCESS (Sony's manual). */
static OStatus CopyGain(OStatus status, const word* values, word* pg, word* ig, word* dg, word* ps, word* is,
                        word* ds) {
    word* out[6] = {pg, ig, dg, ps, is, ds};
    for (int k = 0; k < 6; k++) {
        if (out[k] == NULL) return oINVALID_ARG;
    }
    for (int k = 0; k < 6; k++) *out[k] = status == oSUCCESS ? values[k] : 0;
    return status;
}

OStatus OPENR::GetJointGain(OPrimitiveID id, word* pg, word* ig, word* dg, word* ps, word* is, word* ds) {
    static const word none[6] = {0, 0, 0, 0, 0, 0};
    if (!Valid(id) || primitives[id].type != oprimitiveJOINT2) {
        return CopyGain(oINVALID_PRIMITIVE_ID, none, pg, ig, dg, ps, is, ds);
    }
    const Gain& gain = gains[(int)id];
    return CopyGain(gain.enabled ? oSUCCESS : oGAIN_DISABLED, gain.values, pg, ig, dg, ps, is, ds);
}

OStatus OPENR::GetDefaultJointGain(OPrimitiveID id, word* pg, word* ig, word* dg, word* ps, word* is, word* ds) {
    static const word none[6] = {0, 0, 0, 0, 0, 0};
    if (!Valid(id) || primitives[id].type != oprimitiveJOINT2) {
        return CopyGain(oINVALID_PRIMITIVE_ID, none, pg, ig, dg, ps, is, ds);
    }
    const Gain& gain = gains[(int)id];
    return CopyGain(gain.hasDefault ? oSUCCESS : oNOT_REGISTERED, gain.defaults, pg, ig, dg, ps, is, ds);
}

OStatus OPENR::GetJointValue(OPrimitiveID id, OJointValue* value) {
    int entry = SensorEntry(id);
    if (entry < 0 || !opened[id] || primitives[id].type != oprimitiveJOINT2) return oINVALID_PRIMITIVE_ID;
    if (value == NULL) return oINVALID_ARG;
    const slongword* v = &latest[entry * AIBO_OPENR_VALUES_PER_SENSOR];
    *value = OJointValue(v[0], (word)v[1], (sword)v[2], v[3], 0);
    return oSUCCESS;
}

OStatus OPENR::GetSensorValue(OPrimitiveID id, OSensorValue* value) {
    int entry = SensorEntry(id);
    if (entry < 0 || !opened[id] || primitives[id].type != oprimitiveSENSOR) return oINVALID_PRIMITIVE_ID;
    if (value == NULL) return oINVALID_ARG;
    const slongword* v = &latest[entry * AIBO_OPENR_VALUES_PER_SENSOR];
    memset(value, 0, sizeof *value);
    value->value = v[0];
    value->signal = (word)v[1];
    return oSUCCESS;
}

/* Sync keys start several command vectors together; the host plays each vector as it comes. */
OStatus OPENR::NewSyncKey(OVRSyncKey* key) {
    if (key == NULL) return oINVALID_ARG;
    *key = nextSyncKey++;
    return oSUCCESS;
}

OStatus OPENR::CancelSyncKey(OVRSyncKey key) { return key == ovrsynckeyUNDEF ? oINVALID_SYNC_KEY : oSUCCESS; }

OStatus OPENR::DivideSyncKey(OVRSyncKey key, OVRSyncKey* key1, OVRSyncKey* key2) {
    if (key == ovrsynckeyUNDEF || key1 == NULL || key2 == NULL) return oINVALID_SYNC_KEY;
    *key1 = nextSyncKey++;
    *key2 = nextSyncKey++;
    return oSUCCESS;
}

OStatus OPENR::NewCdtVectorData(MemoryRegionID* memID, OCdtVectorData** base) {
    if (memID == NULL || base == NULL) return oINVALID_ARG;
    void* memory;
    *memID = NewRegion(sizeof(OCdtVectorData), &memory);
    *base = (OCdtVectorData*)memory;
    FillVectorInfo(&(*base)->vectorInfo, *memID, sizeof(OCdtVectorData), odataCDT_VECTOR, sizeof(OCdtInfo),
                   ocdtNUM_CHANNELS);
    return oSUCCESS;
}

OStatus OPENR::DeleteCdtVectorData(MemoryRegionID memID) {
    if (RegionBase(memID) == NULL) return oFAIL;
    DeleteRegion(memID);
    return oSUCCESS;
}

OStatus OPENR::SetCdtVectorData(MemoryRegionID memID) {
    OCdtVectorData* cdt = (OCdtVectorData*)RegionBase(memID);
    if (cdt == NULL) return oFAIL;
    if (cdt->vectorInfo.type != odataCDT_VECTOR) return oINVALID_DATA_TYPE;
    OCdtChannel given = 0;
    for (longword i = 0; i < cdt->vectorInfo.numData && i < (longword)ocdtNUM_CHANNELS; i++) {
        OCdtChannel channel = cdt->info[i].channel;
        /* one bit each, channels 0-6 ("In ERS-7, channel 7 is NOT available": Model Information), once each */
        if (channel == ocdtCHANNEL_UNDEF || (channel & (channel - 1)) || channel >= ocdtCHANNEL7 || (given & channel)) {
            return oINVALID_ARG;
        }
        given |= channel;
        if (cdt->info[i].primitiveID != (OPrimitiveID)cameraIndex) return oINVALID_PRIMITIVE_ID;
    }
    Record(AIBO_OPENR_RECORD_CDT, cdt, sizeof *cdt);
    memcpy(&cdtInUse, cdt, sizeof cdtInUse);  /* the C layer of the images the runtime makes */
    cdtSet = true;
    return oSUCCESS;
}

OStatus OPENR::SetMotorPower(OPower on) {
    if (on != motorPower) {
        motorPower = on;
        slongword value = on;
        RecordValues(AIBO_OPENR_RECORD_MOTOR_POWER, &value, 1);
        SetPowerStatus(power);
    }
    return oSUCCESS;
}

OStatus OPENR::Shutdown(const OBootCondition&) {
    StopRun();
    return oSUCCESS;
}

OStatus OPENR::GetBootCondition(OBootCondition* condition) {
    if (condition == NULL) return oINVALID_ARG;
    *condition = OBootCondition(obcbPAUSE_SW);
    return oSUCCESS;
}

OStatus OPENR::GetPowerStatus(OPowerStatus* status) {
    if (status == NULL) return oINVALID_ARG;
    *status = power;
    return oSUCCESS;
}

OStatus OPENR::ObservePowerStatus(const OPowerStatus& mask, const OServiceEntry& entry) {
    for (size_t i = 0; i < powerObservers.size(); i++) {
        if (powerObservers[i].entry == entry) return oALREADY_REGISTERED;
    }
    PowerObserver observer = {mask, entry};
    powerObservers.push_back(observer);
    return oSUCCESS;
}

OStatus OPENR::UnobservePowerStatus(const OServiceEntry& entry) {
    for (size_t i = 0; i < powerObservers.size(); i++) {
        if (powerObservers[i].entry == entry) {
            powerObservers.erase(powerObservers.begin() + i);
            return oSUCCESS;
        }
    }
    return oNOT_REGISTERED;
}

OStatus OPENR::FindDesignData(const char* keyword, ODesignDataID* id, byte** data, size_t* size) {
    if (keyword == NULL || id == NULL || data == NULL || size == NULL) return oINVALID_ARG;
    std::map<std::string, std::string>::const_iterator found = designData.find(keyword);
    if (found == designData.end()) return oNOT_FOUND;
    SystemCode system;
    std::string error, path = MapPath(found->second.c_str(), false, &error);
    FILE* file = path.empty() ? NULL : fopen(path.c_str(), "rb");
    if (file == NULL) {
        osyslog(osyslogERROR, "FindDesignData(%s): cannot read %s", keyword, found->second.c_str());
        return oNOT_FOUND;
    }
    std::string bytes;
    char chunk[65536];
    size_t n;
    while ((n = fread(chunk, 1, sizeof chunk, file)) > 0) bytes.append(chunk, n);
    fclose(file);
    if (bytes.empty()) return oDESIGNDATA_SIZE_ZERO;
    void* memory;
    *id = NewRegion(bytes.size(), &memory);
    memcpy(memory, bytes.data(), bytes.size());
    *data = (byte*)memory;
    *size = bytes.size();
    return oSUCCESS;
}

OStatus OPENR::DeleteDesignData(ODesignDataID id) {
    if (RegionBase(id) == NULL) return oINVALID_ARG;
    DeleteRegion(id);
    return oSUCCESS;
}

OStatus OPENR::GetRobotDesign(char* robotDesign) {
    if (robotDesign == NULL) return oINVALID_ARG;
    strncpy(robotDesign, design.c_str(), orobotdesignNAME_MAX);
    robotDesign[orobotdesignNAME_MAX] = 0;
    return oSUCCESS;
}

OStatus OPENR::GetMemoryStickStatus(OMemoryStickStatus* status) {
    if (status == NULL) return oINVALID_ARG;
    *status = omemorystickWRITABLE;
    return oSUCCESS;
}

/* The robot sounds its warning and its power goes off: no entry runs after this one returns. */
OStatus OPENR::Fatal(OFatal fatal) {
    osyslog(osyslogERROR, "OPENR::Fatal(%u): the robot's power goes off", (unsigned)fatal);
    std::string payload((const char*)&fatal, sizeof fatal);
    Object* object = host::Current() != NULL ? host::Current() : host::Constructing();  /* an entry, or loading */
    payload += object != NULL ? object->name : "";
    Record(AIBO_OPENR_RECORD_FATAL, payload.data(), payload.size());
    PowerOff();
    StopRun();
    return oSUCCESS;
}

OStatus OPENR::SetTime(const OTime& time) {
    clockOffset = (long)(time.GetClock() - CLOCK_START) - (long)Seconds();
    timeDifference = time.GetTimeDif();
    return oSUCCESS;
}

OStatus OPENR::GetTime(OTime* time) {
    if (time == NULL) return oINVALID_ARG;
    *time = OTime(CLOCK_START + clockOffset + (time_t)Seconds(), timeDifference);
    return oSUCCESS;
}

OStatus OPENR::SetTimeDifference(sbyte difference) {
    timeDifference = difference;
    return oSUCCESS;
}

OStatus OPENR::GetTimeDifference(sbyte* difference) {
    if (difference == NULL) return oINVALID_ARG;
    *difference = timeDifference;
    return oSUCCESS;
}

OStatus OPENR::SetVolumeSwitch(OVolumeSwitch value) {
    if (value > ovolumeSW3) return oINVALID_ARG;
    volumeSwitch = value;
    return oSUCCESS;
}

OStatus OPENR::GetVolumeSwitch(OVolumeSwitch* value) {
    if (value == NULL) return oINVALID_ARG;
    *value = volumeSwitch;
    return oSUCCESS;
}

OStatus OPENR::RequireMWInfo(MWIID) { return oNOT_SUPPORTED; }
OStatus OPENR::CancelMWInfo(MWIID) { return oNOT_SUPPORTED; }
OStatus OPENR::IsMWInfoRequired(MWIID, bool* required) {
    if (required != NULL) *required = false;
    return oSUCCESS;
}
