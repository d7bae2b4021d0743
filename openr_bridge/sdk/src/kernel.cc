/*
 * kernel.cc: objects, their mailbox, services and connections, shared memory regions, the
 * console and simulated time of the aibo-sim OPEN-R runtime.
 */
#include <deque>
#include <errno.h>
#include <stdarg.h>
#include <unistd.h>
#include <MCOOP.h>
#include <OPENR/OSyslog.h>
#include <OPENR/ObjcommMessages.h>
#include <openr_host_protocol.h>
#include "host.h"

namespace host {

namespace {

struct Message {
    Object*           target;
    Selector          selector;
    std::vector<char> bytes;
};

std::vector<Object*> objects;
Object* current = NULL;
Object* constructing = NULL;
std::deque<Message> mailbox;
std::map<std::string, OServiceEntry> services;
void*  replySlot = NULL;
size_t replySize = 0;
bool   replied = false;
bool   poweredOff = false;        /* OPENR::Fatal was called */

struct Region {
    std::vector<char> bytes;
    char*  memory;                    /* the region's bytes: its own, or memory it was placed in */
    size_t size;
};
std::map<MemoryRegionID, Region*> regions;
MemoryRegionID nextRegion = 1;
char* placement = NULL;               /* where the next region goes (PlaceNextRegion) */

int consoleFd = 1, logFd = -1;
bool lineOpen = false;       /* the console's last line is not ended yet (a prompt) */
Object* lineObject = NULL;   /* whose it is */
longword frameNumber = 0;
std::string records;
volatile longword* statusArea = NULL;

void SetStatus(Object* object, Selector selector) {
    if (statusArea == NULL) return;
    longword index = 0;
    for (size_t i = 0; object != NULL && i < objects.size(); i++) {
        if (objects[i] == object) index = (longword)i + 1;
    }
    statusArea[0] = index;
    statusArea[1] = selector;
}

bool WriteAll(int fd, const std::string& text) {
    size_t done = 0;
    while (fd >= 0 && done < text.size()) {
        ssize_t n = write(fd, text.data() + done, text.size() - done);
        if (n == 0) errno = EIO;
        if (n <= 0) return false;
        done += (size_t)n;
    }
    return true;
}

/* Console text, in the log, then on standard output until its reader has gone (EPIPE; the
 * runtime ignores SIGPIPE): the log keeps every line, and the objects run on. A log that cannot
 * be written (a full disk) is written no more and told to the simulator, which ends the run. */
void WriteConsole(const std::string& text) {
    if (!WriteAll(logFd, text)) {
        longword error = errno;
        Record(AIBO_OPENR_RECORD_LOG_FAILED, &error, sizeof error);
        logFd = -1;
    }
    if (!WriteAll(consoleFd, text) && errno == EPIPE) consoleFd = -1;
}

}  // namespace

Object* ObjectOf(const OID& oid) {
    for (size_t i = 0; i < objects.size(); i++) {
        if (oid.GetAddress() == objects[i]) return objects[i];
    }
    return NULL;
}

Object* Current() { return current; }
Object* Constructing() { return constructing; }
void SetConstructing(Object* object) {
    constructing = object;
    SetStatus(object, object != NULL ? AIBO_OPENR_LOADING : 0); /* an exit or endless loop there is named */
}
const std::vector<Object*>& Objects() { return objects; }

Object* AddObject(const std::string& name, const ObjectEntry* table, bool system) {
    Object* object = new Object();
    object->name = name;
    object->system = system;
    for (; table != NULL && table->selector != UNDEF; table++) object->entries[table->selector] = table->entry;
    objects.push_back(object);
    return object;
}

void PowerOff() {
    poweredOff = true;
    mailbox.clear();
}

bool PoweredOff() { return poweredOff; }

void Invoke(Object* object, Selector selector, void* message) {
    if (poweredOff) return;  /* OPENR::Fatal: no entry runs any more */
    std::map<Selector, Entry>::iterator entry = object->entries.find(selector);
    if (entry == object->entries.end()) {
        char text[160];
        snprintf(text, sizeof text, "%s has no entry %u: a message for it is lost\n", object->name.c_str(),
                 (unsigned)selector);
        Object* caller = current;
        current = object;
        Print(text);
        current = caller;
        return;
    }
    Object* caller = current;
    longword callerSelector = statusArea != NULL ? statusArea[1] : 0;
    bool inside = InObjectCode();
    current = object;
    SetStatus(object, selector);
    EnterObjectCode(true);
    ((void (*)(void*))entry->second)(message);
    EnterObjectCode(inside);
    current = caller;
    SetStatus(caller, callerSelector);
}

void SetStatusArea(volatile longword* area) { statusArea = area; }

void Send(const OServiceEntry& to, const void* message, size_t size) {
    Object* target = ObjectOf(to.oid);
    if (target == NULL) return;
    Message queued;
    queued.target = target;
    queued.selector = to.selector;
    queued.bytes.assign((const char*)message, (const char*)message + size);
    mailbox.push_back(queued);
}

bool Deliver(size_t limit) {
    for (size_t delivered = 0; !mailbox.empty(); delivered++) {
        if (delivered == limit) return false;
        Message message = mailbox.front();
        mailbox.pop_front();
        Invoke(message.target, message.selector, &message.bytes[0]);
    }
    return true;
}

bool MailboxEmpty() { return mailbox.empty(); }

OStatus Call(const OServiceEntry& to, void* message, void* reply, size_t size) {
    Object* target = ObjectOf(to.oid);
    if (target == NULL) return oINVALID_OID;
    void* outerSlot = replySlot;
    size_t outerSize = replySize;
    bool outerReplied = replied;
    replySlot = reply;
    replySize = size;
    replied = false;
    Invoke(target, to.selector, message);
    bool answered = replied;
    replySlot = outerSlot;
    replySize = outerSize;
    replied = outerReplied;
    return answered ? oSUCCESS : oFAIL;
}

void Reply(const void* reply, size_t size) {
    if (replySlot != NULL) {
        memcpy(replySlot, reply, size < replySize ? size : replySize);
        replied = true;
    }
}

OStatus Register(const OServiceEntry& entry, const char* name) {
    Object* object = ObjectOf(entry.oid);
    if (object == NULL || name == NULL) return oFAIL;
    if (services.count(name)) return oALREADY_EXIST;
    services[name] = entry;
    object->services.push_back(std::make_pair(std::string(name), entry));
    return oSUCCESS;
}

const OServiceEntry* FindService(const std::string& name) {
    std::map<std::string, OServiceEntry>::const_iterator found = services.find(name);
    return found == services.end() ? NULL : &found->second;
}

OStatus Connect(const std::string& subject, const std::string& observer) {
    const OServiceEntry* control = FindService(subject);
    const OServiceEntry* connect = FindService(observer);
    if (control == NULL || connect == NULL) return oNOT_FOUND;
    OConnectMessage message;
    message.command = oconnectcmdCONNECT;
    message.subjectID = *control;
    strncpy(message.subName, subject.c_str(), oserviceNAME_MAX);
    message.subName[oserviceNAME_MAX] = 0;
    Invoke(ObjectOf(connect->oid), connect->selector, &message);
    return oSUCCESS;
}

MemoryRegionID NewRegion(size_t size, void** base) {
    Region* region = new Region();
    region->size = size ? size : 1;
    if (placement != NULL) {
        region->memory = placement;   /* its bytes are already there: not cleared */
        placement = NULL;
    } else {
        region->bytes.assign(region->size, 0);
        region->memory = &region->bytes[0];
    }
    MemoryRegionID id = nextRegion++;
    regions[id] = region;
    *base = region->memory;
    return id;
}

void PlaceNextRegion(void* memory) { placement = (char*)memory; }

void* RegionBase(MemoryRegionID id, size_t* size) {
    std::map<MemoryRegionID, Region*>::iterator found = regions.find(id);
    if (found == regions.end()) return NULL;
    if (size != NULL) *size = found->second->size;
    return found->second->memory;
}

void DeleteRegion(MemoryRegionID id) {
    std::map<MemoryRegionID, Region*>::iterator found = regions.find(id);
    if (found == regions.end()) return;
    delete found->second;
    regions.erase(found);
}

void SetConsole(int stdoutFd, int logFileFd) {
    consoleFd = stdoutFd;
    logFd = logFileFd;
}

/* Text an object prints, on the console and in the log at once (a prompt without its newline
 * too, as a terminal shows it), each line stamped with the time and the object's name (its
 * file's while its globals are constructed); a line left open by another object is ended first. */
void Print(const char* text) {
    Object* object = current != NULL ? current : constructing;
    if (lineOpen && lineObject != object) FlushConsole();
    std::string out;
    for (const char* c = text; *c; c++) {
        if (!lineOpen) {
            char stamp[32];
            snprintf(stamp, sizeof stamp, "[%9.3f s] ", Seconds());
            out += stamp + (object ? object->name : std::string("system")) + ": ";
            lineOpen = true;
            lineObject = object;
        }
        out += *c;
        if (*c == '\n') lineOpen = false;
    }
    WriteConsole(out);
}

void FlushConsole() {
    if (!lineOpen) return;
    lineOpen = false;
    WriteConsole("\n");
}

longword FrameNumber() { return frameNumber; }
void SetFrameNumber(longword frame) { frameNumber = frame; }
double Seconds() { return frameNumber * 0.008; }

void Record(longword kind, const void* payload, size_t size) {
    longword header[2] = {kind, (longword)size};
    records.append((const char*)header, sizeof header);
    records.append((const char*)payload, size);
}

std::string TakeRecords() {
    std::string taken;
    taken.swap(records);
    return taken;
}

}  // namespace host

/* For interpose.c: an object's printf, puts or putchar, printed as OSYSPRINT prints; 0 for the
 * runtime's own calls, which the C library prints. */
extern "C" int aibo_openr_print(const char* text) {
    if (!host::InObjectCode()) return 0;
    host::Print(text);
    return 1;
}

/* Aperios: an entry returns when it is done. */
extern "C" void Exit() {}
extern "C" void Return(void*, size_t) {}
extern "C" void Prologue(void*) {}
extern "C" sError WhoAmI(OID* object) {
    *object = OID(host::Current());
    return 0;
}
extern "C" sError GetSystemTime(SystemTime* time) {
    unsigned long long micro = (unsigned long long)host::FrameNumber() * 8000;  /* 8 ms frames since boot */
    time->seconds = (longword)(micro / 1000000);
    time->useconds = (longword)(micro % 1000000);
    return 0;
}

/* The console. */
static OStatus PrintFormatted(const char* prefix, const char* format, va_list arguments, bool newline) {
    char text[4096];
    int used = snprintf(text, sizeof text, "%s", prefix);
    vsnprintf(text + used, sizeof text - used, format, arguments);
    if (newline) strncat(text, "\n", sizeof text - strlen(text) - 1);
    host::Print(text);
    return oSUCCESS;
}

OStatus osysprint(const char* format, ...) {
    va_list arguments;
    va_start(arguments, format);
    OStatus status = PrintFormatted("", format, arguments, false);
    va_end(arguments);
    return status;
}

OStatus osyslog(OSyslogPriority priority, const char* format, ...) {
    const char* prefix = priority == osyslogERROR ? "[ERROR] " : priority == osyslogWARNING ? "[WARNING] "
                       : priority == osyslogINFO ? "[INFO] " : "";
    va_list arguments;
    va_start(arguments, format);
    OStatus status = PrintFormatted(prefix, format, arguments, priority != osyslogDEBUG_NO_NEWLINE);
    va_end(arguments);
    return status;
}
