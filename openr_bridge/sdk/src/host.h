/*
 * host.h: the aibo-sim OPEN-R runtime inside libOPENR (not a public header).
 *
 * One process runs every object of a memory stick. Objects talk through a mailbox: a
 * message is queued for an entry (an object and a selector) and delivered later, one
 * handler at a time, each to completion, in the order sent. Time is the simulator's: the
 * runtime delivers sensor data, images and the effector's ready events at 8 ms frames.
 */
#ifndef AIBO_OPENR_HOST_H
#define AIBO_OPENR_HOST_H

#include <map>
#include <string>
#include <vector>
#include <ObjectEntryTable.h>
#include <OPENR/OPENR.h>
#include <OPENR/OPower.h>

namespace host {

/* A loaded object: its entries and the services it registered. */
struct Object {
    std::string name;
    std::map<Selector, Entry> entries;
    std::vector<std::pair<std::string, OServiceEntry> > services;
    bool system;                       /* OVirtualRobotComm, OVirtualRobotAudioComm */
    std::vector<OServiceEntry> powerObservers;
};

Object* ObjectOf(const OID& oid);
Object* Current();                     /* the object whose handler runs, or NULL */
Object* AddObject(const std::string& name, const ObjectEntry* table, bool system);
Object* Constructing();                /* the object whose globals are being constructed */
void    SetConstructing(Object* object);
const std::vector<Object*>& Objects();

/* Messages between entries. */
void Send(const OServiceEntry& to, const void* message, size_t size);
bool Deliver(size_t limit);            /* deliver queued messages; false when `limit` were delivered and more wait */
bool MailboxEmpty();
void PowerOff();                       /* OPENR::Fatal: no entry runs after it, queued messages are lost */
bool PoweredOff();
void Invoke(Object* object, Selector selector, void* message);
OStatus Call(const OServiceEntry& to, void* message, void* reply, size_t replySize);
void Reply(const void* reply, size_t size);

/* Services and connections. */
OStatus Register(const OServiceEntry& entry, const char* name);
const OServiceEntry* FindService(const std::string& name);
OStatus Connect(const std::string& subject, const std::string& observer);

/* Shared memory regions, by MemoryRegionID. */
MemoryRegionID NewRegion(size_t size, void** base);
void   PlaceNextRegion(void* memory);  /* the next NewRegion uses `memory` (its bytes as they are) */
void*  RegionBase(MemoryRegionID id, size_t* size = NULL);
void   DeleteRegion(MemoryRegionID id);

/* The console: text an object prints, marked with its name and the simulated time. */
void Print(const char* text);
void SetConsole(int stdoutFd, int logFd);
void FlushConsole();

/* Simulated time. */
longword FrameNumber();                /* of the frame being processed */
void     SetFrameNumber(longword frame);
double   Seconds();

/* The robot (robot.cc). */
struct Primitive {
    OPrimitiveType type;
    std::string locator;
};
void SetRobot(const std::string& design, const std::vector<Primitive>& primitives,
              const std::vector<int>& sensorOrder, int camera, int speaker, int mic);
void StartSystemObjects();             /* creates OVirtualRobotComm and OVirtualRobotAudioComm */
void SetLatestValues(const std::vector<slongword>& values);  /* the state at boot: what GetJointValue reads */
void SetFrameValues(const slongword* values);             /* 4 per sensor-order entry */
void SetImageSlots(char* slots);      /* AIBO_OPENR_IMAGE_SLOTS + 1 areas of AIBO_OPENR_MAX_IMAGE_BYTES */
struct ImageFrame {                    /* a camera frame whose message the runtime makes */
    longword frameNumber;              /* the OPEN-R frame number of its exposure */
    longword fieldCounter;             /* its index, modulo 2^16 */
};
/* The image message the simulator wrote into area `slot` (`size` bytes) or, with `frame`, the
 * message made here of the Y, Cr, Cb frame in the last area, in `slot` (the copying one: a
 * region of its own). */
void PublishImage(longword slot, size_t size, const ImageFrame* frame);
void AnnounceImageSlot();              /* records where the next image goes, if that changed */
void SetPowerStatus(const OPowerStatus& status);  /* observers of what changed are told */
void PlayFrame();                      /* the effector and speaker at this frame */
/* The frames after frame `frame` (at most `limit`) in which no object code runs whatever the
 * simulator sends (the simulator's own events, images and power, aside), each with the records
 * the effector will make in it; nothing changes (host_protocol.py: lookahead). */
std::vector<std::string> Lookahead(longword frame, size_t limit);
void SetDesignData(const std::map<std::string, std::string>& data);  /* DESIGNDB.CFG: keyword -> /MS path */
void StopRun();                        /* OPENR::Shutdown was called */

/* What the frame made: records for the simulator (protocol.h's kinds). */
void Record(longword kind, const void* payload, size_t size);
std::string TakeRecords();

/* The memory stick (msfs.cc). */
void SetMemoryStick(const std::string& root, const std::string& workdir);
std::string MapPath(const char* path, bool create, std::string* error);
bool InObjectCode();
void EnterObjectCode(bool inside);

/* While one lives, file calls are the runtime's own (not mapped). */
struct SystemCode {
    bool was;
    SystemCode() : was(InObjectCode()) { EnterObjectCode(false); }
    ~SystemCode() { EnterObjectCode(was); }
};

/* Where the runtime says which object and entry run (read by the simulator while it waits). */
void SetStatusArea(volatile longword* area);

}  // namespace host

#endif
