/*
 * ODataFormats.h: the data OPEN-R objects exchange with the robot: command, sensor, sound,
 * image and colour-table vectors, with the ERS-7's byte layouts.
 *
 * Every field the robot stores as `size_t`, `longword` or a pointer is 32 bits here, so each
 * structure has the size it has on the robot (checked below) and the host reads the bytes a
 * robot, or aibo-sim's encoder, writes. Where the robot keeps a physical address the host
 * keeps a 32-bit slot.
 */
#ifndef _ODataFormats_h_DEFINED
#define _ODataFormats_h_DEFINED

#include <OPENR/OPENR.h>
#include <OPENR/OUnits.h>

typedef longword ODataType;
const ODataType odataUNDEF               = 0;
const ODataType odataNO_DIMENSION        = 1;
const ODataType odataLENGTH              = 2;
const ODataType odataMASS                = 3;
const ODataType odataTIME                = 4;
const ODataType odataDATE                = 5;
const ODataType odataANGULAR             = 6;
const ODataType odataVELOCITY            = 7;
const ODataType odataFORCE               = 8;
const ODataType odataACCELERATION        = 9;
const ODataType odataANGULAR_VELOCITY    = 10;
const ODataType odataTEMPERATURE         = 11;
const ODataType odataPRESSURE            = 12;
const ODataType odataPERCENTAGE          = 13;
const ODataType odataSWITCH              = 14;
const ODataType odataLED                 = 15;
const ODataType odataSOUND               = 16;
const ODataType odataIMAGE               = 17;
const ODataType odataJOINT_VALUE         = 18;
const ODataType odataFBK_YCrCb           = 19;
const ODataType odataFBK_CDT             = 20;
const ODataType odataCDT                 = 21;
const ODataType odataPRIMITIVE_INFO      = 22;
const ODataType odataCPC_INFO            = 23;
const ODataType odataFBK_YCrCb_HPF       = 24;
const ODataType odataJOINT_COMMAND       = 256;
const ODataType odataCAMERA_COMMAND      = 257;
const ODataType odataLED_COMMAND         = 258;
const ODataType odataJOINT_COMMAND2      = 259;
const ODataType odataLED_COMMAND2        = 260;
const ODataType odataJOINT_COMMAND3      = 261;
const ODataType odataJOINT_COMMAND4      = 262;
const ODataType odataLED_COMMAND3        = 263;
const ODataType odataRAW_JOINT_COMMAND   = 512;
const ODataType odataRAW_CAMERA_COMMAND  = 513;
const ODataType odataRAW_LED_COMMAND     = 514;
const ODataType odataRAW_JOINT_COMMAND2  = 515;
const ODataType odataCOMMAND_VECTOR      = 1024;
const ODataType odataSENSOR_FRAME_VECTOR = 1025;
const ODataType odataSOUND_VECTOR        = 1026;
const ODataType odataFBKIMAGE_VECTOR     = 1027;
const ODataType odataCDT_VECTOR          = 1028;
const ODataType odataPRIMITIVE_MAP       = 1029;
const ODataType odataCPC_TREE            = 1030;
const ODataType odataDONT_CARE           = 0xffffffff;

typedef longword OSwitchValue;
const OSwitchValue oswitchOFF = 0;
const OSwitchValue oswitchON  = 1;

typedef longword OLEDValue;
const OLEDValue oledOFF = 0;
const OLEDValue oledON  = 1;

typedef word OLED3Mode;
const OLED3Mode oled3_MODE_UNDEF = 0xffff;
const OLED3Mode oled3_MODE_A     = 0;
const OLED3Mode oled3_MODE_B     = 1;

typedef longword OJointValue3;
const OJointValue3 ojoint3_STATE_UNDEF = 0xffffffff;
const OJointValue3 ojoint3_STATE0      = 0;
const OJointValue3 ojoint3_STATE1      = 1;

typedef longword OJointValue4;
const OJointValue4 ojoint4_STATE_UNDEF = 0xffffffff;
const OJointValue4 ojoint4_STATE0      = 0;
const OJointValue4 ojoint4_STATE1      = 1;

typedef word OCameraRequest;
const OCameraRequest ocamreqAE_OFF       = 0;
const OCameraRequest ocamreqAE_ON        = 1;
const OCameraRequest ocamreqSET_AWB_MODE = 2;
const OCameraRequest ocamreqDRAW_BOX     = 3;
const byte ocamparamAWB_AUTO_MODE    = 0;
const byte ocamparamAWB_INDOOR_MODE  = 1;
const byte ocamparamAWB_OUTDOOR_MODE = 2;
const byte ocamparamAWB_USER_MODE    = 3;
const byte ocamparamAWB_FL_MODE      = 4;
const byte ocamparamBOX1 = 1;
const byte ocamparamBOX2 = 2;

/* The header of every data vector. */
const size_t odataOPTIONAL_MAX = 128;
struct ODataVectorInfo {
    MemoryRegionID memRegionID;
    longword       physAddr;    /* a pointer on the robot */
    longword       offset;
    longword       totalSize;
    ODataType      type;
    longword       infoOffset;
    longword       infoSize;
    longword       maxNumData;
    longword       numData;
    OVRSyncKey     syncKey;
    longword       wait;
    longword       optOffset;
    longword       optSize;
    longword       padding[3];
    byte           optional[odataOPTIONAL_MAX];
};

/* Command vectors: joint, LED and camera commands, up to 16 frames of 8 ms each. */
const size_t ocommandMAX_FRAMES = 16;

struct OCommandValue {
    slongword value[2];
};

struct OJointCommandValue {
    slongword value;
    byte      p;
    byte      i;
    byte      d;
    byte      padding;
    void Set(slongword v, byte kp, byte ki, byte kd) { value = v; p = kp; i = ki; d = kd; }
};

struct OJointCommandValue2 {
    slongword value;    /* 1e-6 rad */
    slongword padding;
};

struct OJointCommandValue3 {
    OJointValue3 value;
    word         reserved;
    word         padding;
};

struct OJointCommandValue4 {
    OJointValue4 value;
    word         period;    /* in 8 ms frames */
    word         reserved;
};

struct OCameraCommandValue {
    OCameraRequest request;
    byte           param[6];
};

struct OLEDCommandValue {
    OLEDValue led;
    word      period;    /* in 128 ms */
    word      padding;
};

struct OLEDCommandValue2 {
    OLEDValue led;
    word      period;    /* in 8 ms frames */
    word      reserved;
};

struct OLEDCommandValue3 {
    sword     intensity; /* 0 - 255 */
    OLED3Mode mode;
    word      period;    /* in 8 ms frames */
    word      reserved;
};

struct ORawJointCommandValue {
    word signal;
    byte p;
    byte i;
    byte d;
    byte padding[3];
    void Set(word s, byte kp, byte ki, byte kd) { signal = s; p = kp; i = ki; d = kd; }
};

struct ORawJointCommandValue2 {
    word signal;
    word padding[3];
};

struct ORawCameraCommandValue {
    word signal;
    word padding[3];
    void Set(word s) { signal = s; }
};

struct ORawLEDCommandValue {
    word signal;
    word padding[3];
    void Set(word s) { signal = s; }
};

struct OCommandInfo {
    ODataType    type;
    OPrimitiveID primitiveID;
    longword     frameNumber;
    longword     numFrames;
    longword     frameSize;
    longword     dataOffset;
    longword     dataSize;
    longword     padding[1];
    void Set(ODataType t, OPrimitiveID id, size_t frames) {
        type = t;
        primitiveID = id;
        numFrames = (longword)frames;
    }
};

struct OCommandData {
    OCommandValue value[ocommandMAX_FRAMES];
};

/* ODataVectorInfo, then OCommandInfo[n], then OCommandData[n]. */
struct OCommandVectorData {
    ODataVectorInfo vectorInfo;
    OCommandInfo    info[1];
    void          SetNumData(size_t n) { vectorInfo.numData = (longword)n; }
    OCommandInfo* GetInfo(int index) { return &info[index]; }
    OCommandData* GetData(int index) { return (OCommandData*)((byte*)&vectorInfo + info[index].dataOffset); }
};

/* Sensor frame vectors: up to 16 frames of each sensor (the ERS-7 sends 4, every 32 ms). */
const size_t    osensorframeMAX_FRAMES     = 16;
const word      osensorframeINVALID_SIGNAL = 0xffff;
const slongword opsdINVALID_VALUE          = 0;

struct OSensorValue {
    slongword value;
    word      signal;
    word      padding[5];
};
/* Each quantity is a type of its own (a program may overload on them), laid out as OSensorValue. */
#define OPENR_SENSOR_QUANTITY(name) \
    struct name {                   \
        slongword value;            \
        word      signal;           \
        word      padding[5];       \
    }
OPENR_SENSOR_QUANTITY(OAcceleration);
OPENR_SENSOR_QUANTITY(OAngularVelocity);
OPENR_SENSOR_QUANTITY(OTemperature);
OPENR_SENSOR_QUANTITY(OForce);
OPENR_SENSOR_QUANTITY(OPressure);
OPENR_SENSOR_QUANTITY(OLength);
#undef OPENR_SENSOR_QUANTITY

struct OSwitchStatus {
    OSwitchValue value;
    word         signal;
    word         padding[5];
};

struct OJointValue {
    slongword value;     /* 1e-6 rad */
    word      signal;
    sword     pwmDuty;
    slongword refValue;  /* the commanded value, 1e-6 rad */
    word      refSignal;
    word      padding[1];
    OJointValue() {}
    OJointValue(slongword v, word s, sword pwm, slongword rv, word rs)
        : value(v), signal(s), pwmDuty(pwm), refValue(rv), refSignal(rs) {}
};

struct OSensorFrameInfo {
    ODataType    type;
    OPrimitiveID primitiveID;
    longword     frameNumber;
    longword     numFrames;
    longword     frameSize;
    longword     dataOffset;
    longword     dataSize;
    longword     padding[1];
    void Set(ODataType t, OPrimitiveID id, size_t frames) {
        type = t;
        primitiveID = id;
        numFrames = (longword)frames;
    }
};

struct OSensorFrameData {
    OSensorValue frame[osensorframeMAX_FRAMES];
};

/* ODataVectorInfo, then OSensorFrameInfo[n], then OSensorFrameData[n]. */
struct OSensorFrameVectorData {
    ODataVectorInfo   vectorInfo;
    OSensorFrameInfo  info[1];
    void              SetNumData(size_t n) { vectorInfo.numData = (longword)n; }
    OSensorFrameInfo* GetInfo(int index) { return &info[index]; }
    OSensorFrameData* GetData(int index) {
        return (OSensorFrameData*)((byte*)&vectorInfo + info[index].dataOffset);
    }
};

/* Sound vectors (the speaker: 8 kHz 8 bit or 16 kHz 16 bit mono PCM). */
typedef word OSoundFormat;
const OSoundFormat osoundformatUNDEF    = 0;
const OSoundFormat osoundformatPCM      = 1;
const OSoundFormat osoundformatUSB_MIDI = 2;
const OSoundFormat osoundformatSMF      = 3;

typedef word OSoundChannel;
const OSoundChannel osoundchannelUNDEF  = 0;
const OSoundChannel osoundchannelMONO   = 1;
const OSoundChannel osoundchannelSTEREO = 2;

struct OSoundInfo {
    ODataType     type;
    OPrimitiveID  primitiveID;
    longword      frameNumber;
    longword      frameSize;
    longword      dataOffset;
    longword      maxDataSize;
    longword      dataSize;
    OSoundFormat  format;
    OSoundChannel channel;
    word          samplingRate;
    word          bitsPerSample;
    longword      actualDataSize;
    longword      padding[6];
    void Set(ODataType t, OPrimitiveID id, size_t size) {
        type = t;
        primitiveID = id;
        dataSize = (longword)size;
    }
};

struct OSoundSampleStereo16 {
    sword L;
    sword R;
};

struct OSoundVectorData {
    ODataVectorInfo vectorInfo;
    OSoundInfo      info[1];
    void        SetNumData(size_t n) { vectorInfo.numData = (longword)n; }
    OSoundInfo* GetInfo(int index) { return &info[index]; }
    byte*       GetData(int index) { return (byte*)&vectorInfo + info[index].dataOffset; }
};

/* The camera's image vector: layers H, M, L (YCrCb with Haar detail bands) and C (CDT). */
struct OFbkImageInfo {
    ODataType    type;
    OPrimitiveID primitiveID;
    longword     frameNumber;
    longword     dataOffset;
    longword     dataSize;
    longword     width;
    longword     height;
    longword     padding[1];
};

struct OFbkImageVectorData {
    ODataVectorInfo vectorInfo;
    OFbkImageInfo   info[1];
    void SetPrimitiveID(OPrimitiveID id) {
        for (size_t i = 0; i < vectorInfo.numData; i++) info[i].primitiveID = id;
    }
    OFbkImageInfo* GetInfo(int index) { return &info[index]; }
    byte*          GetData(int index) { return (byte*)&vectorInfo + info[index].dataOffset; }
};

typedef int OFbkImageLayer;
const OFbkImageLayer ofbkimageLAYER_H = 0;
const OFbkImageLayer ofbkimageLAYER_M = 1;
const OFbkImageLayer ofbkimageLAYER_L = 2;
const OFbkImageLayer ofbkimageLAYER_C = 3;

/* Colour detection tables: per channel, a Cr and Cb range for each of 32 Y segments. */
const int ocdtNUM_CHANNELS = 8;
typedef longword OCdtChannel;
const OCdtChannel ocdtCHANNEL_UNDEF = 0x00;
const OCdtChannel ocdtCHANNEL0      = 0x01;
const OCdtChannel ocdtCHANNEL1      = 0x02;
const OCdtChannel ocdtCHANNEL2      = 0x04;
const OCdtChannel ocdtCHANNEL3      = 0x08;
const OCdtChannel ocdtCHANNEL4      = 0x10;
const OCdtChannel ocdtCHANNEL5      = 0x20;
const OCdtChannel ocdtCHANNEL6      = 0x40;
const OCdtChannel ocdtCHANNEL7      = 0x80;
const int      ocdtMAX_Y_SEGMENT = 32;
const longword ocdtINIT          = 0x80808080;
const longword ocdtCr_MAX_MASK   = 0x0000ff00;
const longword ocdtCr_MIN_MASK   = 0x000000ff;
const longword ocdtCb_MAX_MASK   = 0xff000000;
const longword ocdtCb_MIN_MASK   = 0x00ff0000;

struct OCdtInfo {
    ODataType    type;
    OPrimitiveID primitiveID;
    OCdtChannel  channel;
    longword     table[ocdtMAX_Y_SEGMENT];
    longword     padding;
    void Init(OPrimitiveID id, OCdtChannel c) {
        type = odataCDT;
        primitiveID = id;
        channel = c;
        for (int i = 0; i < ocdtMAX_Y_SEGMENT; i++) table[i] = ocdtINIT;
    }
    void Set(int segment, byte crMax, byte crMin, byte cbMax, byte cbMin) {
        table[segment] = (((longword)crMax << 8) & ocdtCr_MAX_MASK) | ((longword)crMin & ocdtCr_MIN_MASK)
                       | (((longword)cbMax << 24) & ocdtCb_MAX_MASK) | (((longword)cbMin << 16) & ocdtCb_MIN_MASK);
    }
};

struct OCdtVectorData {
    ODataVectorInfo vectorInfo;
    OCdtInfo        info[ocdtNUM_CHANNELS];
    void      SetNumData(size_t n) { vectorInfo.numData = (longword)n; }
    OCdtInfo* GetInfo(int index) { return &info[index]; }
};

struct OPrimitiveInfo {
    ODataType      type;
    OPrimitiveID   primitiveID;
    OPrimitiveType primitiveType;
    OSensorType    sensorType;
    OStatus        primitiveStatus;
    longword       padding[3];
    char           locator[ovrPATH_MAX + 1];
};

struct OPrimitiveMapData {
    ODataVectorInfo vectorInfo;
    OPrimitiveInfo  info[1];
    OPrimitiveInfo* GetInfo(int index) { return &info[index]; }
};

struct OCPCInfo {
    ODataType type;
    word      cpcClass;
    word      cpcSubClass;
    word      cpcType;
    word      numReceptors;
};

struct OCPCTreeData {
    ODataVectorInfo vectorInfo;
    OCPCInfo        info[1];
    OCPCInfo* GetInfo(int index) { return &info[index]; }
};

/* The robot's sizes: the host must read and write the same bytes. */
OPENR_STATIC_ASSERT(sizeof(ODataVectorInfo) == 192, ODataVectorInfo_is_192_bytes);
OPENR_STATIC_ASSERT(sizeof(OCommandInfo) == 32, OCommandInfo_is_32_bytes);
OPENR_STATIC_ASSERT(sizeof(OCommandData) == 128, OCommandData_is_128_bytes);
OPENR_STATIC_ASSERT(sizeof(OJointCommandValue2) == 8, OJointCommandValue2_is_8_bytes);
OPENR_STATIC_ASSERT(sizeof(OJointCommandValue4) == 8, OJointCommandValue4_is_8_bytes);
OPENR_STATIC_ASSERT(sizeof(OLEDCommandValue2) == 8, OLEDCommandValue2_is_8_bytes);
OPENR_STATIC_ASSERT(sizeof(OLEDCommandValue3) == 8, OLEDCommandValue3_is_8_bytes);
OPENR_STATIC_ASSERT(sizeof(OSensorValue) == 16, OSensorValue_is_16_bytes);
OPENR_STATIC_ASSERT(sizeof(OJointValue) == 16, OJointValue_is_16_bytes);
OPENR_STATIC_ASSERT(sizeof(OSensorFrameInfo) == 32, OSensorFrameInfo_is_32_bytes);
OPENR_STATIC_ASSERT(sizeof(OSensorFrameData) == 256, OSensorFrameData_is_256_bytes);
OPENR_STATIC_ASSERT(sizeof(OSoundInfo) == 64, OSoundInfo_is_64_bytes);
OPENR_STATIC_ASSERT(sizeof(OFbkImageInfo) == 32, OFbkImageInfo_is_32_bytes);
OPENR_STATIC_ASSERT(sizeof(OCdtInfo) == 144, OCdtInfo_is_144_bytes);
OPENR_STATIC_ASSERT(sizeof(OCdtVectorData) == 192 + 8 * 144, OCdtVectorData_is_1344_bytes);
OPENR_STATIC_ASSERT(sizeof(OPrimitiveInfo) == 160, OPrimitiveInfo_is_160_bytes);
OPENR_STATIC_ASSERT(sizeof(OCPCInfo) == 12, OCPCInfo_is_12_bytes);

#endif /* _ODataFormats_h_DEFINED */
