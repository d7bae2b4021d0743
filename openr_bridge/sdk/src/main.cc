/*
 * main.cc: openr-host, the process that runs a memory stick's objects for a simulator
 * (openr_bridge/host_protocol.py describes the messages). Started by aibo-sim with the
 * socket's descriptor in AIBO_OPENR_FD, the shared memory block's path in AIBO_OPENR_SHM and,
 * optionally, a log file's descriptor in AIBO_OPENR_LOG_FD.
 */
#include <dlfcn.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <unistd.h>
#include <OPENR/OPENRMessages.h>
#include <OPENR/OSyslog.h>
#include <openr_host_protocol.h>
#include "host.h"

using namespace host;

namespace {

const size_t MESSAGES_PER_FRAME = 100000;  /* deliveries in one 8 ms frame before the rest wait for the next */

int channel = -1;
char* shared = NULL;
std::vector<std::string> foretold;  /* the records of the frames the last answer foretold */

bool ReadAll(void* buffer, size_t size) {
    char* at = (char*)buffer;
    while (size > 0) {
        ssize_t n = read(channel, at, size);
        if (n <= 0) return false;
        at += n;
        size -= (size_t)n;
    }
    return true;
}

void WriteAll(const void* buffer, size_t size) {
    const char* at = (const char*)buffer;
    while (size > 0) {
        ssize_t n = write(channel, at, size);
        if (n <= 0) _exit(1);
        at += n;
        size -= (size_t)n;
    }
}

void Answer(longword kind, const std::string& payload) {
    longword header[2] = {(longword)(payload.size() + 4), kind};
    std::string message((const char*)header, sizeof header);
    message += payload;
    WriteAll(message.data(), message.size());
}

void Fail(const std::string& text) {
    longword size = (longword)text.size();
    Answer(AIBO_OPENR_REPLY_FAILED, std::string((const char*)&size, 4) + text);
    _exit(1);
}

/* The fields of one message, read in order. */
class Reader {
public:
    explicit Reader(const std::string& bytes) : bytes_(bytes), at_(0) {}
    longword U32() {
        longword value = 0;
        if (at_ + 4 <= bytes_.size()) memcpy(&value, bytes_.data() + at_, 4);
        at_ += 4;
        return value;
    }
    slongword I32() { return (slongword)U32(); }
    std::string String() {
        longword size = U32();
        std::string text = at_ + size <= bytes_.size() ? bytes_.substr(at_, size) : "";
        at_ += size;
        return text;
    }
    const char* Here() const { return bytes_.data() + at_; }
    void Skip(size_t size) { at_ += size; }

private:
    const std::string& bytes_;
    size_t at_;
};

bool ReadMessage(longword* kind, std::string* payload) {
    longword size;
    if (!ReadAll(&size, 4) || size < 4) return false;
    payload->resize(size);
    if (!ReadAll(&(*payload)[0], size)) return false;
    memcpy(kind, payload->data(), 4);
    payload->erase(0, 4);
    return true;
}

void AppendString(std::string* out, const std::string& text) {
    longword size = (longword)text.size();
    out->append((const char*)&size, 4);
    out->append(text);
}

/* Before the process dies of a signal: which object, which entry (or that it was loading); no
 * text when no object's code ran. */
void Crashed(int signal) {
    char text[256];
    size_t used = 0;
    const Object* object = Current();
    const Object* loading = object == NULL ? Constructing() : NULL;
    const char* name = object != NULL ? object->name.c_str() : loading != NULL ? loading->name.c_str() : "";
    const char* parts[] = {name, object != NULL ? " (entry " : loading != NULL ? " (while loading)" : "", ""};
    for (int k = 0; k < 2; k++) {
        for (const char* c = parts[k]; *c && used < 200; c++) text[used++] = *c;
    }
    if (object != NULL && shared != NULL) {
        longword selector = ((volatile longword*)shared)[1], digits = 1;
        while (digits * 10 <= selector) digits *= 10;
        for (; digits > 0; digits /= 10) text[used++] = (char)('0' + selector / digits % 10);
        text[used++] = ')';
    }
    longword header[3] = {(longword)(used + 8), AIBO_OPENR_REPLY_CRASHED, (longword)used};
    if (write(channel, header, sizeof header) > 0 && write(channel, text, used) > 0) {
    }
    ::signal(signal, SIG_DFL);
    raise(signal);
}

/* The robot's own objects (system) or the memory stick's, in their order. */
std::vector<Object*> ObjectsOf(bool system) {
    std::vector<Object*> chosen;
    for (size_t i = 0; i < Objects().size(); i++) {
        if (Objects()[i]->system == system) chosen.push_back(Objects()[i]);
    }
    return chosen;
}

void Boot(OReason reason, Selector selector, const std::vector<Object*>& order) {
    OBootParam boot(omemorystickWRITABLE);
    OShutdownParam shutdown(true);
    OReasonMessage message(reason, reason == oreasonBOOT ? (const void*)&boot : (const void*)&shutdown,
                           reason == oreasonBOOT ? sizeof boot : sizeof shutdown);
    for (size_t i = 0; i < order.size(); i++) Invoke(order[i], selector, &message);
}

std::string LoadObjects(Reader& setup) {
    longword count = setup.U32();
    for (longword i = 0; i < count && !PoweredOff(); i++) { /* after a Fatal, no other object is loaded */
        std::string path = setup.String(), label = setup.String();
        std::string file = label.substr(label.rfind('/') + 1);
        /* the file's name (HELLO for /MS/OPEN-R/MW/OBJS/HELLO.BIN) until the stub names the object:
         * what its constructors print is stamped with it */
        Object* object = AddObject(file.substr(0, file.find('.')), NULL, false);
        SetConstructing(object);
        EnterObjectCode(true);
        void* library = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
        EnterObjectCode(false);
        SetConstructing(NULL);
        if (library == NULL) Fail(label + ": cannot load: " + dlerror());
        const ObjectEntry* table = (const ObjectEntry*)dlsym(library, "ObjectEntryTable");
        if (table == NULL) Fail(label + ": no ObjectEntryTable (is it an OPEN-R object built by stubgen2 and mkbin?)");
        for (; table->selector != UNDEF; table++) object->entries[table->selector] = table->entry;
        const char* name = (const char*)dlsym(library, "aibo_openr_object_name");
        if (name != NULL) object->name = name;  /* else a stub not made by our stubgen2: the file's name */
    }
    Boot(oreasonBOOT, oentryINIT, Objects());
    const std::vector<Object*> programs = ObjectsOf(false);
    longword loaded = (longword)programs.size();
    std::string services((const char*)&loaded, 4);
    for (size_t i = 0; i < programs.size(); i++) {
        AppendString(&services, programs[i]->name);
        longword n = (longword)programs[i]->services.size();
        services.append((const char*)&n, 4);
        for (longword k = 0; k < n; k++) AppendString(&services, programs[i]->services[k].first);
    }
    return services + TakeRecords();
}

void Setup(const std::string& payload) {
    Reader setup(payload);
    std::string design = setup.String(), stick = setup.String(), workdir = setup.String();
    std::vector<Primitive> primitives(setup.U32());
    for (size_t i = 0; i < primitives.size(); i++) primitives[i].locator = setup.String();
    std::vector<int> sensors(2 * setup.U32());
    for (size_t i = 0; i < sensors.size(); i++) sensors[i] = setup.I32();
    int camera = setup.I32(), speaker = setup.I32(), mic = setup.I32();
    std::vector<slongword> now(sensors.size() / 2 * AIBO_OPENR_VALUES_PER_SENSOR);
    if (!now.empty()) memcpy(&now[0], setup.Here(), now.size() * sizeof(slongword));
    setup.Skip(now.size() * sizeof(slongword));
    std::map<std::string, std::string> designData;
    for (longword n = setup.U32(); n > 0; n--) {
        std::string keyword = setup.String();
        designData[keyword] = setup.String();
    }
    OPowerStatus power;
    const char* fields = setup.Here();
    setup.Skip(AIBO_OPENR_POWER_FIELDS * 4);
    slongword values[AIBO_OPENR_POWER_FIELDS];
    memcpy(values, fields, sizeof values);
    power = OPowerStatus(values[0], values[1], values[2], values[3], values[4], values[5], values[6], values[7],
                         values[8]);
    SetRobot(design, primitives, sensors, camera, speaker, mic);
    SetLatestValues(now);
    SetDesignData(designData);
    SetMemoryStick(stick, workdir);
    SetPowerStatus(power);
    StartSystemObjects();
    Answer(AIBO_OPENR_REPLY_SERVICES, LoadObjects(setup));
}

void ConnectAndStart(const std::string& payload) {
    Reader connect(payload);
    for (longword n = connect.U32(); n > 0; n--) {
        std::string subject = connect.String(), observer = connect.String();
        if (Connect(subject, observer) != oSUCCESS) Fail("cannot connect " + subject + " to " + observer);
    }
    /* The robot's own objects start first, and their observers' ready events reach the programs'
     * subjects before the programs start, as on the robot: Sony's MovingHead7 checks IsReady() in
     * DoStart for it, and SoundPlay, which fills both speaker buffers in DoStart, needs it. */
    Boot(oreasonBOOT, oentrySTART, ObjectsOf(true));
    Deliver(MESSAGES_PER_FRAME);
    Boot(oreasonBOOT, oentrySTART, ObjectsOf(false));
    Deliver(MESSAGES_PER_FRAME);
    Answer(AIBO_OPENR_REPLY_FRAME_DONE, TakeRecords());
}

/* The frames the simulator stepped on the last answer's lookahead (their count, then each one's
 * frame number and sensor values), played now as they were foretold: no object code runs. */
void CatchUp(Reader& frame, size_t sensors) {
    longword count = frame.U32();
    if (count > foretold.size()) Fail("openr-host: the simulator stepped frames the runtime did not foretell");
    std::vector<slongword> values(sensors * AIBO_OPENR_VALUES_PER_SENSOR);
    for (longword i = 0; i < count; i++) {
        SetFrameNumber(frame.U32());
        if (!values.empty()) memcpy(&values[0], frame.Here(), values.size() * sizeof(slongword));
        frame.Skip(values.size() * sizeof(slongword));
        SetFrameValues(values.empty() ? NULL : &values[0]);
        PlayFrame();
        if (!MailboxEmpty() || TakeRecords() != foretold[i]) {
            Fail("openr-host: a foretold frame did not play as foretold (a bug of aibo-sim's OPEN-R runtime)");
        }
    }
    foretold.clear();
}

void Frame(const std::string& payload, size_t sensors) {
    Reader frame(payload);
    frame.U32();  /* the tick, low and high words: the runtime counts time in frame numbers */
    frame.U32();
    longword number = frame.U32(), flags = frame.U32(), lookahead = frame.U32();
    CatchUp(frame, sensors);
    SetFrameNumber(number);
    std::vector<slongword> values(sensors * AIBO_OPENR_VALUES_PER_SENSOR);
    if (!values.empty()) memcpy(&values[0], frame.Here(), values.size() * sizeof(slongword));
    frame.Skip(values.size() * sizeof(slongword));
    SetFrameValues(values.empty() ? NULL : &values[0]);
    if (flags & AIBO_OPENR_FLAG_IMAGE) {
        longword slot = frame.U32(), size = frame.U32();
        if (slot > AIBO_OPENR_IMAGE_SLOTS || size > AIBO_OPENR_MAX_IMAGE_BYTES) {
            Fail("openr-host: an image out of the shared memory");
        }
        PublishImage(slot, size, NULL);
    }
    if (flags & AIBO_OPENR_FLAG_RAW_IMAGE) {
        longword slot = frame.U32();
        ImageFrame image;
        image.frameNumber = frame.U32();
        image.fieldCounter = frame.U32();
        if (slot > AIBO_OPENR_IMAGE_SLOTS) Fail("openr-host: an image out of the shared memory");
        PublishImage(slot, 0, &image);
    }
    if (flags & AIBO_OPENR_FLAG_POWER) {
        slongword v[AIBO_OPENR_POWER_FIELDS];
        for (int k = 0; k < AIBO_OPENR_POWER_FIELDS; k++) v[k] = frame.I32();
        SetPowerStatus(OPowerStatus(v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8]));
    }
    Deliver(MESSAGES_PER_FRAME);
    PlayFrame();
    Deliver(MESSAGES_PER_FRAME);
    AnnounceImageSlot();
    std::string answer = TakeRecords();
    foretold = Lookahead(number, lookahead < AIBO_OPENR_LOOKAHEAD_FRAMES ? lookahead : AIBO_OPENR_LOOKAHEAD_FRAMES);
    const longword next[2] = {AIBO_OPENR_RECORD_NEXT_FRAME, 0};
    for (size_t i = 0; i < foretold.size(); i++) {
        answer.append((const char*)next, sizeof next);
        answer += foretold[i];
    }
    Answer(AIBO_OPENR_REPLY_FRAME_DONE, answer);
}

}  // namespace

int main() {
    const char* fd = getenv("AIBO_OPENR_FD");
    const char* shm = getenv("AIBO_OPENR_SHM");
    const char* log = getenv("AIBO_OPENR_LOG_FD");
    if (fd == NULL || shm == NULL) {
        fprintf(stderr, "openr-host: run by aibo-sim (aibo-sim run MEMORY_STICK), not by hand\n");
        return 2;
    }
    channel = atoi(fd);
    int shmFd = open(shm, O_RDWR);
    shared = shmFd < 0 ? NULL : (char*)mmap(NULL, AIBO_OPENR_SHM_SIZE, PROT_READ | PROT_WRITE, MAP_SHARED, shmFd, 0);
    if (shared == NULL || shared == MAP_FAILED) Fail(std::string("cannot map ") + shm);
    SetStatusArea((volatile longword*)shared);
    SetImageSlots(shared + AIBO_OPENR_SHM_HEADER);
    SetConsole(1, log != NULL ? atoi(log) : -1);
    setvbuf(stdout, NULL, _IOLBF, 0);
    const int fatal[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT};
    for (size_t i = 0; i < sizeof fatal / sizeof fatal[0]; i++) signal(fatal[i], Crashed);
    signal(SIGPIPE, SIG_IGN); /* a console reader that left: the console's copy stops (kernel.cc) */

    size_t sensors = 0;
    longword kind;
    std::string payload;
    while (ReadMessage(&kind, &payload)) {
        if (kind == AIBO_OPENR_MSG_SETUP) {
            Reader peek(payload);
            peek.String();
            peek.String();
            peek.String();
            for (longword n = peek.U32(); n > 0; n--) peek.String();
            sensors = peek.U32();
            Setup(payload);
        } else if (kind == AIBO_OPENR_MSG_CONNECT) {
            ConnectAndStart(payload);
        } else if (kind == AIBO_OPENR_MSG_FRAME) {
            Frame(payload, sensors);
        } else if (kind == AIBO_OPENR_MSG_STOP) {
            Reader stop(payload);
            longword number = stop.U32();
            CatchUp(stop, sensors);
            SetFrameNumber(number);
            Boot(oreasonSHUTDOWN, oentrySTOP, ObjectsOf(false));
            Deliver(MESSAGES_PER_FRAME);
            Boot(oreasonSHUTDOWN, oentryDESTROY, ObjectsOf(false));  /* "after DoStop() is called on all objects" */
            Deliver(MESSAGES_PER_FRAME);
            FlushConsole();
            Answer(AIBO_OPENR_REPLY_FRAME_DONE, TakeRecords());
            return 0;
        }
    }
    FlushConsole();
    return 0;
}
