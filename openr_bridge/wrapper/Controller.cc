/*
 * Controller.cc: the wrapper object's OPEN-R side (see Controller.h): its entries, the 8 ms
 * frame clock driven by the effector, sensor vectors and images in, command vectors out.
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <OPENR/OPENRAPI.h>
#include <OPENR/OPENRMessages.h>
#include <OPENR/OSyslog.h>
#include <OPENR/core_macro.h>
#include "Controller.h"
#include "Ers7Table.h"
#include "entry.h"

/* The controller's main(), renamed by the Makefile (-Dmain=...): a C one, or a C++ one of
 * either form. Weak: the one the controller defines is not null. */
extern "C" int aibo_controller_main_c(int, char**) __attribute__((weak));
int aibo_controller_main_cc() __attribute__((weak));
int aibo_controller_main_cc(int, char**) __attribute__((weak));
/* exit(), its calls made these (the Makefile links with ld's --wrap=exit): Controller::Exit,
 * and the C library's. */
extern "C" void __wrap_exit(int status) { Controller::Exit(status); }
extern "C" void __real_exit(int status) __attribute__((noreturn));
/* aibo-sim's host runtime: told that the controller failed (the robot has none: null there). */
extern "C" void aibo_sim_controller_failed(const char* message) __attribute__((weak));

/* The robot's sizes of the OPEN-R structures read and written here (the host SDK's headers
 * keep them on a 64-bit machine too); a negative array size stops the compiler otherwise. */
#define WRAPPER_STATIC_ASSERT(condition, name) typedef char wrapper_assert_##name[(condition) ? 1 : -1]
WRAPPER_STATIC_ASSERT(sizeof(ODataVectorInfo) == 192, ODataVectorInfo_is_192_bytes);
WRAPPER_STATIC_ASSERT(sizeof(OCommandInfo) == 32, OCommandInfo_is_32_bytes);
WRAPPER_STATIC_ASSERT(sizeof(OCommandData) == 128, OCommandData_is_128_bytes);
WRAPPER_STATIC_ASSERT(sizeof(OJointCommandValue2) == 8, OJointCommandValue2_is_8_bytes);
WRAPPER_STATIC_ASSERT(sizeof(OJointCommandValue4) == 8, OJointCommandValue4_is_8_bytes);
WRAPPER_STATIC_ASSERT(sizeof(OLEDCommandValue2) == 8, OLEDCommandValue2_is_8_bytes);
WRAPPER_STATIC_ASSERT(sizeof(OLEDCommandValue3) == 8, OLEDCommandValue3_is_8_bytes);
WRAPPER_STATIC_ASSERT(sizeof(OSensorFrameInfo) == 32, OSensorFrameInfo_is_32_bytes);
WRAPPER_STATIC_ASSERT(sizeof(OSensorFrameData) == 256, OSensorFrameData_is_256_bytes);
WRAPPER_STATIC_ASSERT(sizeof(OSensorValue) == 16 && sizeof(OJointValue) == 16, sensor_values_are_16_bytes);
WRAPPER_STATIC_ASSERT(sizeof(OFbkImageInfo) == 32, OFbkImageInfo_is_32_bytes);
WRAPPER_STATIC_ASSERT(sizeof(slongword) == 4 && sizeof(longword) == 4 && sizeof(word) == 2, words_are_the_robots);

namespace {

const size_t SENSOR_FRAMES = 4;   /* frames per sensor vector on the ERS-7: the primer's length */
const int EAR_FLICK_FRAMES = 16;  /* an ear plunger's time on, 128 ms: Sony's MovingEar7 */

template <class T, size_t N> size_t Count(const T (&)[N]) { return N; }

bool IsType(const char* locator, const char* type) { return strstr(locator, type) != 0; }

/* A set-point in the command vectors' unit, micro-radians (to the nearest). */
slongword Microradians(double radians) {
    double scaled = radians * 1e6;
    return (slongword)(scaled < 0 ? -(long)(0.5 - scaled) : (long)(scaled + 0.5));
}

bool SameCommands(const wrapper::FrameCommand& a, const wrapper::FrameCommand& b) {
    return a.jointMoved == b.jointMoved && a.ledSet == b.ledSet;
}

}  // namespace

namespace wrapper {

void Fail(const char* format, ...) {
    char message[1024];
    va_list arguments;
    va_start(arguments, format);
    vsnprintf(message, sizeof message, format, arguments);
    va_end(arguments);
    Controller::Instance().Fail(message);
}

}  // namespace wrapper

Controller* Controller::instance_ = 0;

Controller::Controller()
    : state_(LOADED), failJump_(0), runJump_(0), cameraId_(oprimitiveID_UNDEF), nextDie_(0), run_(0), lastStep_(0), runTick_(0),
      nextTick_(0), newestTick_(-1), haveOrigin_(false), primed_(false), origin_(0) {
    instance_ = this;
}

OStatus Controller::DoInit(const OSystemEvent&) {
    NEW_ALL_SUBJECT_AND_OBSERVER;
    REGISTER_ALL_ENTRY;
    SET_ALL_READY_AND_NOTIFY_ENTRY;
    const std::vector<std::string>& locators = robot_.Locators();
    ids_.assign(locators.size(), oprimitiveID_UNDEF);
    earUpFrames_.assign(locators.size(), 0);
    for (size_t i = 0; i < locators.size(); i++) {
        if (OPENR::OpenPrimitive(locators[i].c_str(), &ids_[i]) != oSUCCESS) {
            OSYSLOG1((osyslogERROR, "cannot open the primitive %s", locators[i].c_str()));
            continue;
        }
        int slot = robot_.SlotOf(locators[i].c_str());
        if (slot >= 0) slots_[ids_[i]] = slot;
        if (IsType(locators[i].c_str(), "-FbkImageSensor:")) cameraId_ = ids_[i];
    }
    for (size_t l = 0; l < Count(ers7::LEDS); l++) {
        for (size_t i = 0; i < locators.size(); i++) {
            if (locators[i] == ers7::LEDS[l]) ledIds_.push_back(ids_[i]);
        }
    }
    return oSUCCESS;
}

OStatus Controller::DoStart(const OSystemEvent&) {
    ENABLE_ALL_SUBJECT;
    OPENR::SetMotorPower(opowerON);
    OPENR::EnableJointGain(oprimitiveID_UNDEF);
    for (size_t j = 0; j < Count(ers7::JOINTS); j++) {
        const ers7::Joint& joint = ers7::JOINTS[j];
        if (IsType(joint.locator, "-Joint2:")) {
            OPENR::SetJointGain(ids_[j], joint.p, joint.i, joint.d, ers7::PSHIFT, ers7::ISHIFT, ers7::DSHIFT);
        }
    }
    OPowerStatus pause;
    pause.robotStatus = orsbPAUSE;
    OPENR::ObservePowerStatus(pause, OServiceEntry(myOID_, Extra_Entry[entryNotifyPower]));
    state_ = RUNNING;
    if (Protected(CallMain, this) && run_ == 0) {
        OSYSPRINT(("the controller's main() returned without calling robot_run: it has ended\n"));
        End(true);
    }
    ASSERT_READY_TO_ALL_OBSERVER;
    return oSUCCESS;
}

OStatus Controller::DoStop(const OSystemEvent&) {
    if (state_ == RUNNING) End(false);
    DISABLE_ALL_SUBJECT;
    DEASSERT_READY_TO_ALL_OBSERVER;
    return oSUCCESS;
}

OStatus Controller::DoDestroy(const OSystemEvent&) {
    robot_.Release();
    while (!images_.empty()) {
        images_.front().region->RemoveReference();
        images_.pop_front();
    }
    DELETE_ALL_SUBJECT_AND_OBSERVER;
    return oSUCCESS;
}

/* ------------------------------------------------------------------ controller code */

/* Calls main(), which robot_run leaves (Run): as in Webots, its statements after robot_run never run. */
void Controller::CallMain(void* self) {
    static char name[] = "Controller";
    static char* argv[] = {name, 0};
    Controller& controller = *(Controller*)self;
    jmp_buf ran;
    controller.runJump_ = &ran;
    int (*plain)() = aibo_controller_main_cc;
    int (*withArguments)(int, char**) = aibo_controller_main_cc;
    if (setjmp(ran) != 0) {
        /* robot_run was called */
    } else if (aibo_controller_main_c != 0) {
        aibo_controller_main_c(1, argv);
    } else if (withArguments != 0) {
        withArguments(1, argv);
    } else if (plain != 0) {
        plain();
    } else {
        wrapper::Fail("the controller has no main()");
    }
    controller.runJump_ = 0;
}

/* Calls the run function; one that calls robot_run is left (Run) and the new one called at once
 * with 0, as in the simulator, where that robot_run never returns. */
void Controller::CallRun(void* self) {
    Controller& controller = *(Controller*)self;
    jmp_buf replaced;
    controller.runJump_ = &replaced;
    if (setjmp(replaced) != 0) controller.lastStep_ = 0;
    int ms = controller.run_(controller.lastStep_);
    controller.runJump_ = 0;
    if (ms <= 0) wrapper::Fail("run function returned %d: it must return the next step in ms (e.g. TIME_STEP)", ms);
    if (ms % wrapper::FRAME_MS != 0) {
        wrapper::Fail("step of %d ms: must be a positive whole multiple of the %d ms joint frame", ms,
                      wrapper::FRAME_MS);
    }
    controller.lastStep_ = ms;
    controller.runTick_ += ms / wrapper::FRAME_MS;
}

void Controller::CallDie(void* self) {
    Controller& controller = *(Controller*)self;
    controller.dieFunctions_[controller.nextDie_++]();
}

/* Calls controller code; false when an error in it ended the controller (Fail). */
bool Controller::Protected(void (*call)(void*), void* argument) {
    jmp_buf here;
    jmp_buf* outer = failJump_;
    jmp_buf* outerRun = runJump_;
    failJump_ = &here;
    if (setjmp(here) == 0) {
        call(argument);
        failJump_ = outer;
        return true;
    }
    failJump_ = outer;
    runJump_ = outerRun;  /* the failed call's, if it set one, is gone */
    return false;
}

void Controller::Fail(const char* message) {
    char text[1024 + 64];  /* wrapper::Fail's message whole, and the time before it */
    snprintf(text, sizeof text, "controller error at t = %.3f s: %s", robot_.TimeMs() / 1000.0, message);
    OSYSPRINT(("%s\n", text));
    if (aibo_sim_controller_failed != 0) aibo_sim_controller_failed(text);
    if (state_ == RUNNING) End(true);
    if (failJump_ == 0) abort();  /* not called from the controller's code: a bug of the wrapper */
    longjmp(*failJump_, 1);
}

/* exit() in the controller's code, as a Python controller's sys.exit() in the simulator: exit(0)
 * ends the controller (its robot_die functions run, the robot shuts down), another status fails
 * it; in a robot_die function it ends that one. Outside the controller's code, the C library's. */
void Controller::Exit(int status) {
    if (instance_ == 0 || instance_->failJump_ == 0) __real_exit(status);
    if (status != 0) wrapper::Fail("exited with exit(%d)", status);
    if (instance_->state_ == RUNNING) instance_->End(true);
    longjmp(*instance_->failJump_, 1);
}

/* The controller has ended: its robot_die functions run (each once, whatever the others do),
 * then, unless the robot is already stopping, it shuts down. */
void Controller::End(bool shutdown) {
    state_ = ENDED;
    runJump_ = 0;  /* robot_run in a robot_die function returns */
    while (nextDie_ < dieFunctions_.size()) Protected(CallDie, this);
    if (shutdown) OPENR::Shutdown(OBootCondition(obcbPAUSE_SW));
}

void Controller::Die(void (*function)(void)) {
    if (function == 0) wrapper::Fail("robot_die(NULL): the exit function must be callable");
    dieFunctions_.push_back(function);
}

void Controller::Run(int (*function)(int)) {
    if (function == 0) wrapper::Fail("robot_run(NULL): the run function must be callable");
    run_ = function;
    if (runJump_ != 0) longjmp(*runJump_, 1);  /* out of main(); C++: its locals are not destroyed */
}

void Controller::CameraControl(int tag, const char* function, int value) {
    std::string locator = robot_.DeviceLocator(tag, wrapper::Robot::CAMERA);
    for (size_t s = 0; s < Count(ers7::CAMERA_SETTINGS); s++) {
        const ers7::CameraSetting& setting = ers7::CAMERA_SETTINGS[s];
        if (strcmp(setting.function, function) != 0) continue;
        OPrimitiveControl_CameraParam param((longword)value);
        OStatus status = OPENR::ControlPrimitive(cameraId_, setting.request, &param, sizeof param, 0, 0);
        if (status == oOUT_OF_RANGE || status == oINVALID_ARG) {
            wrapper::Fail("%s: %s(%d): the value must be %s (OPENR::ControlPrimitive returned %s)", locator.c_str(),
                          function, value, setting.allowed, status == oOUT_OF_RANGE ? "oOUT_OF_RANGE" : "oINVALID_ARG");
        }
        if (status != oSUCCESS) {
            wrapper::Fail("%s(%d): OPENR::ControlPrimitive(fbkID, %s, ...) returned OStatus %d", function, value,
                          setting.requestName, (int)status);
        }
    }
}

/* Webots' P gain as Sony's P register (its unit: KP_PER_SONY_P N m/rad), to the nearest (at least 1). */
void Controller::SetControlP(int tag, double p) {
    int joint = robot_.JointOf(tag, wrapper::Robot::SERVO);
    if (robot_.CheckedNumber(tag, wrapper::Robot::SERVO, "control P", p) <= 0) {
        wrapper::Fail("%s: control P must be above 0, not %g", ers7::JOINTS[joint].locator, p);
    }
    double value = p / ers7::KP_PER_SONY_P;
    word gain = value >= 0xFF ? 0xFF : value < 1 ? 1 : (word)(value + 0.5);
    const ers7::Joint& table = ers7::JOINTS[joint];
    if (IsType(table.locator, "-Joint2:")) {
        OPENR::SetJointGain(ids_[joint], gain, table.i, table.d, ers7::PSHIFT, ers7::ISHIFT, ers7::DSHIFT);
    }
}

/* ------------------------------------------------------------------ data in */

/* The frame number's 8 ms frame since t = 0 (frame numbers start again at 1 after
 * oframeMAX_NUMBER). */
long Controller::TickOf(longword frame) const {
    long difference = (long)frame - (long)origin_;
    const long cycle = (long)oframeMAX_NUMBER;
    if (difference < -cycle / 2) difference += cycle;
    if (difference > cycle / 2) difference -= cycle;
    return difference;
}

void Controller::NotifySensor(const ONotifyEvent& event) {
    OSensorFrameVectorData* vector = (OSensorFrameVectorData*)event.Data(0);
    for (longword i = 0; i < vector->vectorInfo.numData; i++) {
        OSensorFrameInfo* info = vector->GetInfo((int)i);
        std::map<OPrimitiveID, int>::const_iterator slot = slots_.find(info->primitiveID);
        if (slot == slots_.end()) continue;
        if (info->type == odataSWITCH) robot_.SetSwitch(slot->second);
        if (!haveOrigin_) {
            origin_ = info->frameNumber;
            haveOrigin_ = true;
        }
        OSensorFrameData* data = vector->GetData((int)i);
        for (longword f = 0; f < info->numFrames && f < osensorframeMAX_FRAMES; f++) {
            long tick = TickOf(info->frameNumber + f);
            if (tick < nextTick_) continue;
            while (snapshots_.empty() || snapshots_.back().tick < tick) {
                wrapper::Snapshot next;
                next.tick = snapshots_.empty() ? nextTick_ : snapshots_.back().tick + 1;
                next.values = snapshots_.empty() ? std::vector<slongword>(robot_.NumSlots(), 0)
                                                 : snapshots_.back().values;
                next.duties = snapshots_.empty() ? std::vector<sword>(robot_.NumSlots(), 0)
                                                 : snapshots_.back().duties;
                snapshots_.push_back(next);
            }
            wrapper::Snapshot& snapshot = snapshots_[tick - snapshots_.front().tick];
            snapshot.values[slot->second] = data->frame[f].value;
            if (info->type == odataJOINT_VALUE) {  /* a joint's frames are OJointValues, as Sony's samples read them */
                const OJointValue* joint = (const OJointValue*)data->frame;
                snapshot.duties[slot->second] = joint[f].pwmDuty;
            }
            if (tick > newestTick_) newestTick_ = tick;
        }
    }
    observer[event.ObsIndex()]->AssertReady();
    /* The effector waits (the robot's clocks drifted apart): the frames before the newest go
     * now, the newest with the next vector, once this frame's image has surely arrived. */
    if (state_ == RUNNING && primed_ && outgoing_.empty() && subject[sbjEffector]->IsReady()) {
        Process(newestTick_ - 1);
        Flush();
    }
}

void Controller::Notify(const ONotifyEvent& event) {
    OFbkImageVectorData* fbkImageVectorData = (OFbkImageVectorData*)event.Data(0);
    Received image = {fbkImageVectorData->GetInfo(ofbkimageLAYER_H)->frameNumber, event.RCData(0)};
    image.region->AddReference();
    images_.push_back(image);
    observer[event.ObsIndex()]->AssertReady();
}

void Controller::NotifyPower(void* message) {
    if (((OPowerStatusMessage*)message)->powerStatus.robotStatus & orsbPAUSE) {
        OSYSPRINT(("the pause switch: shutting down\n"));
        OPENR::Shutdown(OBootCondition(obcbPAUSE_SW));
    }
}

bool Controller::NewestImage(long tick, wrapper::Image* image) const {
    bool found = false;
    for (size_t i = 0; haveOrigin_ && i < images_.size() && TickOf(images_[i].frame) <= tick; i++) {
        image->tick = TickOf(images_[i].frame);
        image->region = images_[i].region;
        found = true;
    }
    return found;
}

/* The frames up to `last` whose sensor values are here: samples, run calls, set-points. */
void Controller::Process(long last) {
    while (state_ == RUNNING && nextTick_ <= last && !snapshots_.empty() && snapshots_.front().tick == nextTick_) {
        const wrapper::Snapshot& frame = snapshots_.front();
        if (nextTick_ == 0) {
            robot_.Start(frame);
        } else {
            wrapper::Image image;
            robot_.Sample(nextTick_, frame, NewestImage(nextTick_, &image) ? &image : 0);
        }
        if (nextTick_ == runTick_ && !Protected(CallRun, this)) break;
        wrapper::FrameCommand command;
        robot_.PlayFrame(&command);
        pending_.push_back(command);
        nextTick_++;
        snapshots_.pop_front();
        while (images_.size() >= 2 && TickOf(images_[1].frame) <= nextTick_) {
            images_.front().region->RemoveReference();
            images_.pop_front();
        }
    }
}

/* ------------------------------------------------------------------ commands out */

void Controller::Ready(const OReadyEvent& event) {
    if (!event.IsAssert()) return;
    if (!primed_) {
        primed_ = true;
        wrapper::FrameCommand leds;
        robot_.Commands(&leds);
        pending_.assign(SENSOR_FRAMES, leds);
    } else if (outgoing_.empty()) {
        Process(newestTick_);
    }
    Flush();
}

/* The frames computed go out as command vectors (frames alike in what they command, 16 at
 * most), one each time the effector is ready. */
void Controller::Flush() {
    for (size_t first = 0, end; first < pending_.size(); first = end) {
        end = first + 1;
        while (end < pending_.size() && end - first < ocommandMAX_FRAMES
               && SameCommands(pending_[first], pending_[end])) {
            end++;
        }
        RCRegion* region = 0;
        for (size_t r = 0; r < regions_.size() && region == 0; r++) {
            bool queued = false;
            for (size_t q = 0; q < outgoing_.size(); q++) queued = queued || outgoing_[q] == regions_[r];
            if (!queued && regions_[r]->NumberOfReference() == 1) region = regions_[r];
        }
        if (region == 0) {
            OCommandVectorData* vector;
            MemoryRegionID id;
            OPENR::NewCommandVectorData(Count(ers7::JOINTS) + Count(ers7::LEDS), &id, &vector);
            region = new RCRegion(vector->vectorInfo.memRegionID, vector->vectorInfo.offset, (void*)vector,
                                  vector->vectorInfo.totalSize);
            regions_.push_back(region);
        }
        Fill((OCommandVectorData*)region->Base(), first, end);
        outgoing_.push_back(region);
    }
    pending_.clear();
    if (!outgoing_.empty() && subject[sbjEffector]->IsReady()) {
        subject[sbjEffector]->SetData(outgoing_.front());
        subject[sbjEffector]->NotifyObservers();
        outgoing_.pop_front();
    }
}

/* Frames [first, end) of pending_: a JOINT_COMMAND2 (ears: JOINT_COMMAND4) entry for each joint
 * the controller has moved, an LED_COMMAND2/3 entry for each LED it has set, LED 0 when none. */
void Controller::Fill(OCommandVectorData* vector, size_t first, size_t end) {
    const wrapper::FrameCommand& shape = pending_[first];
    const size_t frames = end - first, joints = Count(ers7::JOINTS);
    int entries = 0;
    for (size_t j = 0; j < joints; j++) {
        if (!shape.jointMoved[j]) continue;
        OCommandInfo* info = vector->GetInfo(entries);
        OCommandData* data = vector->GetData(entries++);
        if (IsType(ers7::JOINTS[j].locator, "-Joint4:")) {
            info->Set(odataJOINT_COMMAND4, ids_[j], frames);
            OJointCommandValue4* values = (OJointCommandValue4*)data->value;
            double middle = (ers7::JOINTS[j].low + ers7::JOINTS[j].high) / 2;
            for (size_t k = 0; k < frames; k++) {
                int& up = earUpFrames_[j];
                up = pending_[first + k].joints[j] > middle ? up + (up <= EAR_FLICK_FRAMES) : 0;
                values[k].value = up > 0 && up <= EAR_FLICK_FRAMES ? ojoint4_STATE1 : ojoint4_STATE0;
                values[k].period = 1;
            }
        } else {
            info->Set(odataJOINT_COMMAND2, ids_[j], frames);
            OJointCommandValue2* values = (OJointCommandValue2*)data->value;
            for (size_t k = 0; k < frames; k++) values[k].value = Microradians(pending_[first + k].joints[j]);
        }
    }
    bool anyLed = false;
    for (size_t l = 0; l < Count(ers7::LEDS); l++) anyLed = anyLed || shape.ledSet[l];
    for (size_t l = 0; l < Count(ers7::LEDS); l++) {
        if (!shape.ledSet[l] && !(l == 0 && entries == 0 && !anyLed)) continue;
        OCommandInfo* info = vector->GetInfo(entries);
        OCommandData* data = vector->GetData(entries++);
        OPrimitiveID id = ledIds_[l];
        if (IsType(ers7::LEDS[l], "-LED2:")) {
            info->Set(odataLED_COMMAND2, id, frames);
            OLEDCommandValue2* values = (OLEDCommandValue2*)data->value;
            for (size_t k = 0; k < frames; k++) {
                values[k].led = pending_[first + k].leds[l] > 0 ? oledON : oledOFF;
                values[k].period = 1;
            }
        } else {
            info->Set(odataLED_COMMAND3, id, frames);
            OLEDCommandValue3* values = (OLEDCommandValue3*)data->value;
            for (size_t k = 0; k < frames; k++) {
                values[k].intensity = (sword)pending_[first + k].leds[l];
                values[k].mode = oled3_MODE_A;
                values[k].period = 1;
            }
        }
    }
    vector->SetNumData(entries);
}
