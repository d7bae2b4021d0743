/*
 * Robot.cc: devices, sampling, servos, LEDs, motions and the camera's RGB image (see Robot.h).
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <OPENR/OFbkImage.h>
#include <OPENR/OSyslog.h>
#include "Robot.h"
#include "Ers7Table.h"
#include "Picture.h"

/* aibo-sim's host runtime: told the frame number of each image the controller's camera takes
 * (the run writes those pictures; the robot has none: null there). */
extern "C" void aibo_sim_camera_captured(longword frameNumber) __attribute__((weak));

namespace wrapper {
namespace {

const double DT = FRAME_MS / 1000.0;
const char* const KIND_NAMES[] = {"servo",         "camera", "distance_sensor",     "touch_sensor",
                                  "accelerometer", "led",    "motor force feedback"};
const char* const ENABLE_CALLS[] = {"servo_enable_position", "camera_enable", "distance_sensor_enable",
                                    "touch_sensor_enable", "accelerometer_enable", "led_enable",
                                    "servo_enable_motor_force_feedback"};
const char DATA_FOLDER[] = "/MS/OPEN-R/MW/DATA/P/";

template <class T, size_t N> size_t Count(const T (&)[N]) { return N; }

bool IsJoint4(const std::string& locator) { return locator.find("-Joint4:") != std::string::npos; }

/* The report's YCrCb2RGB (section 3.2.4), operation for operation. */
byte Clip(double value) {
    if (value > 255.0) return 255;
    if (value < 0.0) return 0;
    return (byte)value;
}

void YCrCb2RGB(byte y, byte cr, byte cb, byte* r, byte* g, byte* b) {
    sbyte scr = (sbyte)(cr ^ 0x80);
    sbyte scb = (sbyte)(cb ^ 0x80);
    double Y = (double)y / 255.0;
    double Cr = (double)scr / 128.0;
    double Cb = (double)scb / 128.0;
    *r = Clip(255.0 * (Y + Cr));
    *g = Clip(255.0 * (Y - 0.51 * Cr - 0.19 * Cb));
    *b = Clip(255.0 * (Y + Cb));
}

std::string Upper(const char* text) {
    std::string upper(text);
    for (size_t i = 0; i < upper.size(); i++) {
        if (upper[i] >= 'a' && upper[i] <= 'z') upper[i] = (char)(upper[i] - 'a' + 'A');
    }
    return upper;
}

/* The 8.3 upper-case name build-ms gives a motion file on the memory stick (build_ms.short_name). */
std::string ShortName(const char* path) {
    const char* slash = strrchr(path, '/');
    std::string name = Upper(slash ? slash + 1 : path);
    size_t dot = name.rfind('.');
    std::string parts[2] = {dot == std::string::npos || dot == 0 ? name : name.substr(0, dot),
                            dot == std::string::npos || dot == 0 ? "" : name.substr(dot + 1)};
    for (int p = 0; p < 2; p++) {
        for (size_t i = 0; i < parts[p].size(); i++) {
            char c = parts[p][i];
            if (!((c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-')) parts[p][i] = '_';
        }
        parts[p] = parts[p].substr(0, p == 0 ? 8 : 3);
    }
    return parts[1].empty() ? parts[0] : parts[0] + "." + parts[1];
}

}  // namespace

Robot::Robot() : numSlots_(0), tick_(0) {
    for (size_t j = 0; j < Count(ers7::JOINTS); j++) {
        const ers7::Joint& joint = ers7::JOINTS[j];
        Device device = {joint.locator, SERVO, (int)j, 0, 0, false, {0, 0, 0}, {0, 0}, false, 0};
        devices_.push_back(device);
        low_.push_back(joint.low);
        high_.push_back(joint.high);
        maxVelocity_.push_back(joint.maxSpeed);
    }
    numSlots_ = (int)Count(ers7::JOINTS);
    for (size_t s = 0; s < Count(ers7::SENSORS); s++) {
        const ers7::Sensor& sensor = ers7::SENSORS[s];
        Kind kind = sensor.kind[0] == 'c' ? CAMERA : sensor.kind[0] == 'd' ? DISTANCE : sensor.kind[0] == 't'
                    ? TOUCH : ACCELEROMETER;
        Device device = {sensor.locator, kind, kind == CAMERA ? -1 : numSlots_, 0, 0, false, {0, 0, 0}, {0, 0}, false,
                         sensor.touchThreshold};
        devices_.push_back(device);
        if (kind != CAMERA) numSlots_ += kind == ACCELEROMETER ? 3 : 1;
    }
    for (size_t l = 0; l < Count(ers7::LEDS); l++) {
        Device device = {ers7::LEDS[l], LED, (int)l, 0, 0, false, {0, 0, 0}, {0, 0}, false, 0};
        devices_.push_back(device);
    }
    for (size_t d = 0; d < devices_.size(); d++) {
        names_.push_back(devices_[d].locator);
        named_.push_back((int)d);
        locators_.push_back(devices_[d].locator);
        if (devices_[d].kind == ACCELEROMETER) {
            for (size_t a = 0; a < Count(ers7::ACCELEROMETER_ALIASES); a++) {
                names_.push_back(ers7::ACCELEROMETER_ALIASES[a]);
                named_.push_back((int)d);
                locators_.push_back(ers7::ACCELEROMETER_ALIASES[a]);
            }
        }
    }
    forceFeedback_ = devices_.size();  /* after the named devices: reached through a servo's tag */
    for (size_t j = 0; j < Count(ers7::JOINTS); j++) {
        Device device = {ers7::JOINTS[j].locator, FORCE_FEEDBACK, (int)j, 0, 0, false, {0, 0, 0}, {0, 0}, false, 0};
        devices_.push_back(device);
    }
    switch_.assign(numSlots_, false);
    const size_t joints = Count(ers7::JOINTS);
    velocity_ = maxVelocity_;
    acceleration_.assign(joints, HUGE_VAL);
    target_.assign(joints, 0.0);
    command_.assign(joints, 0.0);
    speed_.assign(joints, 0.0);
    start_.assign(joints, 0.0);
    targeted_.assign(joints, false);
    moved_.assign(joints, false);
    led_.assign(Count(ers7::LEDS), 0);
    ledSet_.assign(Count(ers7::LEDS), false);
}

int Robot::SlotOf(const char* locator) const {
    for (size_t j = 0; j < Count(ers7::JOINTS); j++) {
        if (strcmp(ers7::JOINTS[j].locator, locator) == 0) return IsJoint4(locator) ? -1 : (int)j;
    }
    for (size_t d = 0; d < devices_.size(); d++) {
        const Device& device = devices_[d];
        if (device.kind == ACCELEROMETER) {
            if (device.locator == locator) return device.index;
            for (size_t a = 0; a < Count(ers7::ACCELEROMETER_ALIASES); a++) {
                if (strcmp(ers7::ACCELEROMETER_ALIASES[a], locator) == 0) return device.index + 1 + (int)a;
            }
        } else if ((device.kind == DISTANCE || device.kind == TOUCH) && device.locator == locator) {
            return device.index;
        }
    }
    return -1;
}

/* ------------------------------------------------------------------ frames */

void Robot::Start(const Snapshot& frame) {
    tick_ = 0;
    for (size_t j = 0; j < command_.size(); j++) {
        double position = IsJoint4(devices_[j].locator) ? low_[j] : frame.values[j] / 1e6;
        command_[j] = start_[j] = position < low_[j] ? low_[j] : position > high_[j] ? high_[j] : position;
        if (!targeted_[j]) target_[j] = command_[j];
    }
}

void Robot::Sample(long tick, const Snapshot& frame, const Image* newest) {
    tick_ = tick;
    const long now = TimeMs();
    for (size_t d = 0; d < devices_.size(); d++) {
        Device& device = devices_[d];
        if (device.period == 0) continue;
        /* The camera takes a new picture only when it has a newer one (robot.Camera). */
        bool same = device.kind == CAMERA && device.hasValue && newest != 0 && newest->tick == device.image.tick;
        if (!same && now >= device.nextSampleMs) TakeSample(device, frame, newest);
        while (device.nextSampleMs <= now) device.nextSampleMs += device.period;
    }
}

void Robot::TakeSample(Device& device, const Snapshot& frame, const Image* newest) {
    const std::vector<slongword>& v = frame.values;
    switch (device.kind) {
    case SERVO:
        device.value[0] = IsJoint4(device.locator) ? command_[device.index] : v[device.index] / 1e6;
        break;
    case FORCE_FEEDBACK:
        device.value[0] = frame.duties[device.index] * ers7::MAX_TORQUE / ers7::PWM_DUTY_FULL_SCALE;
        break;
    case DISTANCE:
        device.value[0] = v[device.index] / 1000.0;  /* micrometres to millimetres */
        break;
    case TOUCH:
        device.value[0] = switch_[device.index] ? v[device.index] != 0 : v[device.index] > device.threshold;
        break;
    case ACCELEROMETER:
        for (int axis = 0; axis < 3; axis++) {  /* Sony's a1 (backward), a2, a3 (down) as x, y, z */
            device.value[axis] = ers7::ACCELERATION_SIGNS[axis] * v[device.index + axis] / 1e6;
        }
        break;
    case CAMERA:
        if (newest == 0) return;
        newest->region->AddReference();
        if (device.hasValue) device.image.region->RemoveReference();
        device.image = *newest;
        device.decoded = false;
        if (aibo_sim_camera_captured != 0) {
            OFbkImageVectorData* taken = (OFbkImageVectorData*)newest->region->Base();
            aibo_sim_camera_captured(taken->GetInfo(ofbkimageLAYER_H)->frameNumber);
        }
        break;
    case LED:
        return;
    }
    device.hasValue = true;
}

void Robot::PlayFrame(FrameCommand* command) {
    const long now = TimeMs();
    for (size_t p = 0; p < playing_.size();) {
        MTN* mtn = playing_[p];
        long frame = (now - mtn->startMs) / FRAME_MS;
        if (frame >= mtn->motion.NumFrames()) {
            mtn->playing = false;
            playing_.erase(playing_.begin() + p);
            continue;
        }
        std::vector<slongword> values(mtn->motion.locators.size());
        mtn->motion.Frame(frame, &values[0]);
        for (size_t k = 0; k < values.size(); k++) {
            for (size_t j = 0; j < command_.size(); j++) {
                if (devices_[j].locator == mtn->motion.locators[k]) {
                    SetTarget((int)j, values[k] / 1e6);
                    command_[j] = target_[j];
                }
            }
        }
        p++;
    }
    Advance();
    for (size_t j = 0; j < command_.size(); j++) {
        if (command_[j] != start_[j]) moved_[j] = true;
    }
    Commands(command);
}

void Robot::Commands(FrameCommand* command) const {
    command->joints = command_;
    command->jointMoved = moved_;
    command->leds = led_;
    command->ledSet = ledSet_;
}

/* sim.Servos.advance: each set-point one frame towards its target. */
void Robot::Advance() {
    bool moving = false, unlimited = true;
    for (size_t j = 0; j < command_.size(); j++) {
        moving = moving || target_[j] - command_[j] != 0;
        unlimited = unlimited && acceleration_[j] == HUGE_VAL;
    }
    if (!moving) return;
    for (size_t j = 0; j < command_.size(); j++) {
        double error = target_[j] - command_[j];
        double limit = velocity_[j] < maxVelocity_[j] ? velocity_[j] : maxVelocity_[j];
        if (unlimited) {
            speed_[j] = error < 0 ? -limit : limit;
        } else {
            double acceleration = acceleration_[j] < 1e9 ? acceleration_[j] : 1e9;
            double stop = sqrt(2 * acceleration * fabs(error));
            double sign = error > 0 ? 1.0 : error < 0 ? -1.0 : 0.0;
            double wanted = sign * (limit < stop ? limit : stop);
            double lowest = speed_[j] - acceleration * DT, highest = speed_[j] + acceleration * DT;
            wanted = wanted > lowest ? wanted : lowest;
            speed_[j] = wanted < highest ? wanted : highest;
        }
        double step = speed_[j] * DT;
        if (fabs(step) >= fabs(error)) {
            command_[j] = target_[j];
            speed_[j] = 0;
        } else {
            command_[j] = command_[j] + step;
        }
    }
}

void Robot::SetTarget(int joint, double position) {
    double high = position > low_[joint] ? position : low_[joint];
    target_[joint] = high < high_[joint] ? high : high_[joint];
    targeted_[joint] = true;
}

void Robot::Release() {
    for (size_t d = 0; d < devices_.size(); d++) {
        if (devices_[d].kind == CAMERA && devices_[d].hasValue) {
            devices_[d].image.region->RemoveReference();
            devices_[d].hasValue = false;
        }
    }
}

/* ------------------------------------------------------------------ devices */

int Robot::GetDevice(const char* name) {
    for (size_t n = 0; name != 0 && n < names_.size(); n++) {
        if (names_[n] != name) continue;
        for (size_t t = 0; t < tags_.size(); t++) {
            if (tags_[t] == named_[n]) return (int)t + 1;
        }
        tags_.push_back(named_[n]);
        return (int)tags_.size();
    }
    Fail("no device named '%s' on the ERS-7; devices are OPEN-R locators, such as %s", name ? name : "(NULL)",
         names_[0].c_str());
}

Robot::Device& Robot::Tagged(int tag, Kind kind) {
    if (tag <= 0 || tag > (int)tags_.size()) {
        Fail("invalid device tag %d: use the value robot_get_device returned", tag);
    }
    Device& device = devices_[tags_[tag - 1]];
    if (device.kind != kind) {
        Fail("device %s is a %s, not a %s", device.locator.c_str(), KIND_NAMES[device.kind], KIND_NAMES[kind]);
    }
    return device;
}

std::string Robot::DeviceLocator(int tag, Kind kind) { return Tagged(tag, kind).locator; }

int Robot::JointOf(int tag, Kind kind) { return Tagged(tag, kind).index; }

void Robot::Enable(int tag, Kind kind, int ms) { EnableDevice(Tagged(tag, kind), ms); }

void Robot::EnableDevice(Device& device, int ms) {
    if (ms <= 0) Fail("%s: sampling period must be a positive whole number of ms, not %d", device.locator.c_str(), ms);
    if (device.kind == CAMERA && device.hasValue) device.image.region->RemoveReference();
    device.period = ms;
    device.hasValue = false;
    device.nextSampleMs = TimeMs() + ms;
}

void Robot::EnableForceFeedback(int tag, int ms) {
    Device& device = ForceFeedbackOf(tag);
    if (IsJoint4(device.locator)) {  /* aibo_sim.robot.MotorForceFeedback.enable */
        Fail("%s: an ear (Joint4) has no motor force feedback: the robot reports no duty", device.locator.c_str());
    }
    EnableDevice(device, ms);
}

void Robot::Disable(int tag, Kind kind) { DisableDevice(Tagged(tag, kind)); }

void Robot::DisableDevice(Device& device) {
    if (device.kind == CAMERA && device.hasValue) device.image.region->RemoveReference();
    device.period = 0;
    device.hasValue = false;
}

double Robot::Value(int tag, Kind kind, int axis) { return DeviceValue(Tagged(tag, kind), axis); }

double Robot::DeviceValue(Device& device, int axis) {
    if (device.period == 0) {
        Fail("%s: %s is not enabled (call %s first)", device.locator.c_str(), KIND_NAMES[device.kind],
             ENABLE_CALLS[device.kind]);
    }
    if (!device.hasValue) {
        Fail("%s: no sample yet: enabled with a %d ms period, first value at t = %ld ms (now %ld ms)",
             device.locator.c_str(), device.period, device.nextSampleMs, TimeMs());
    }
    return device.value[axis];
}

double Robot::CheckedNumber(int tag, Kind kind, const char* what, double value) {
    Device& device = Tagged(tag, kind);
    if (!(value - value == 0)) Fail("%s: %s must be a finite number, not %g", device.locator.c_str(), what, value);
    return value;
}

void Robot::SetPosition(int tag, double radians) {
    int joint = JointOf(tag, SERVO);
    SetTarget(joint, CheckedNumber(tag, SERVO, "position", radians));
}

void Robot::SetVelocity(int tag, double value) {
    int joint = JointOf(tag, SERVO);
    velocity_[joint] = fabs(CheckedNumber(tag, SERVO, "velocity", value));
}

void Robot::SetAcceleration(int tag, double value) {
    int joint = JointOf(tag, SERVO);
    double acceleration = CheckedNumber(tag, SERVO, "acceleration", value);
    if (acceleration != -1 && acceleration <= 0) {  /* Webots' range: -1 (unlimited) or (0, inf) */
        Fail("%s: acceleration must be -1 (unlimited) or above 0, not %g", Tagged(tag, SERVO).locator.c_str(),
             acceleration);
    }
    acceleration_[joint] = acceleration == -1 ? HUGE_VAL : acceleration;
}

void Robot::SetLed(int tag, int value) {
    int led = Tagged(tag, LED).index;
    led_[led] = value <= 0 ? 0 : value == 1 ? 255 : value > 255 ? 255 : value;
    ledSet_[led] = true;
}

unsigned char* Robot::CameraImage(int tag) {
    Value(tag, CAMERA, 0);
    Device& device = Tagged(tag, CAMERA);
    if (!device.decoded) {
        /* The report's camera_get_image: layer H, pixel by pixel, R, G, B. */
        OFbkImageVectorData* fbk = (OFbkImageVectorData*)device.image.region->Base();
        OFbkImageInfo* info = fbk->GetInfo(ofbkimageLAYER_H);
        byte* data = fbk->GetData(ofbkimageLAYER_H);
        OFbkImage yImage(info, data, ofbkimageBAND_Y);
        OFbkImage crImage(info, data, ofbkimageBAND_Cr);
        OFbkImage cbImage(info, data, ofbkimageBAND_Cb);
        int w = yImage.Width(), h = yImage.Height();
        rgb_.resize((size_t)w * h * 3);
        size_t f = 0;
        for (int y = 0; y < h; y++) {
            for (int x = 0; x < w; x++, f += 3) {
                YCrCb2RGB(yImage.Pixel(x, y), crImage.Pixel(x, y), cbImage.Pixel(x, y), &rgb_[f], &rgb_[f + 1],
                          &rgb_[f + 2]);
            }
        }
        device.decoded = true;
    }
    return &rgb_[0];
}

/* As the Python API: -1, the reason on the console, for a name it cannot write (Webots' answer). */
int Robot::CameraSaveImage(int tag, const char* filename, int quality) {
    const byte* image = CameraImage(tag);  /* not enabled, no picture yet: the controller fails */
    int width = CameraWidth(tag), height = CameraHeight(tag);
    std::string name = filename ? filename : "";
    const char* slash = strrchr(name.c_str(), '/');
    const char* dot = strrchr(slash ? slash : name.c_str(), '.');
    std::string ending = dot ? Upper(dot) : "", problem;
    std::vector<byte> data;
    if (name.empty()) {
        problem = "not a file name";
    } else if (ending == ".PNG") {
        data = Png(image, width, height);
    } else if (ending != ".JPG" && ending != ".JPEG") {
        problem = "the file name must end in .png, .jpg or .jpeg";
    } else if (quality < 1 || quality > 100) {
        problem = "a JPEG's quality must be a whole number 1-100";
    } else {
        data = Jpeg(image, width, height, quality);
    }
    if (problem.empty()) {
        FILE* file = fopen(filename, "wb");
        bool written = file != NULL && fwrite(&data[0], 1, data.size(), file) == data.size();
        if (file != NULL && fclose(file) != 0) written = false;
        if (written) return 0;
        problem = std::string("cannot write ") + filename + ": " + strerror(errno);
        if (file != NULL) remove(filename);  /* no half-written picture */
    }
    OSYSPRINT(("%s: camera_save_image('%s', %d): %s\n", Tagged(tag, CAMERA).locator.c_str(), name.c_str(), quality,
               problem.c_str()));
    return -1;
}

int Robot::CameraWidth(int tag) {
    Device& device = Tagged(tag, CAMERA);
    if (!device.hasValue) return ers7::IMAGE_WIDTH;
    return (int)((OFbkImageVectorData*)device.image.region->Base())->GetInfo(ofbkimageLAYER_H)->width;
}

int Robot::CameraHeight(int tag) {
    Device& device = Tagged(tag, CAMERA);
    if (!device.hasValue) return ers7::IMAGE_HEIGHT;
    return (int)((OFbkImageVectorData*)device.image.region->Base())->GetInfo(ofbkimageLAYER_H)->height;
}

/* ------------------------------------------------------------------ motions */

MTN* Robot::NewMotion(const char* filename) {
    if (filename == 0) {
        mtnError_ = "mtn_new(NULL): the file name must be a string";
        return 0;
    }
    /* On the memory stick: a /MS path as given, any other name in DATA/P under its 8.3 name. */
    std::string path = Upper(filename).compare(0, 4, "/MS/") == 0 ? filename : DATA_FOLDER + ShortName(filename);
    FILE* file = fopen(path.c_str(), "rb");
    if (file == 0) {
        mtnError_ = "File not found: " + Printable(filename, 200);
        return 0;
    }
    std::vector<byte> data;
    byte chunk[4096];
    size_t got;
    while ((got = fread(chunk, 1, sizeof chunk, file)) > 0) data.insert(data.end(), chunk, chunk + got);
    bool failed = ferror(file) != 0;
    fclose(file);
    MTN* mtn = new MTN();
    std::string error;
    if (failed) {
        error = Printable(path, 200) + ": cannot read it";
    } else if (ParseMotion(data, path, &mtn->motion, &error)) {
        for (size_t k = 0; error.empty() && k < mtn->motion.locators.size(); k++) {
            const std::string& locator = mtn->motion.locators[k];
            bool device = false, joint = false;
            for (size_t n = 0; n < names_.size(); n++) device = device || names_[n] == locator;
            for (size_t j = 0; j < command_.size(); j++) joint = joint || devices_[j].locator == locator;
            if (!device) {
                std::string other = AnotherRobot(mtn->motion);
                error = "Missing device in model: " + Printable(locator, 0) + (other.empty() ? "" : " (" + other + ")");
            } else if (!joint) {
                error = "Not a joint: " + Printable(locator, 0) + " (a motion moves joints only)";
            }
        }
        if (error.empty() && mtn->motion.frameTimeMs % SUBFRAME_MS != 0) {
            char frames[96];
            snprintf(frames, sizeof frames, ": frame time %d ms is not a multiple of %d ms", mtn->motion.frameTimeMs,
                     SUBFRAME_MS);
            error = Printable(mtn->motion.source, 200) + frames;
        }
    }
    if (!error.empty()) {
        mtnError_ = error;
        delete mtn;
        return 0;
    }
    mtn->playing = false;
    mtn->startMs = 0;
    return mtn;
}

MTN* Robot::CheckMotion(MTN* mtn, const char* function) {
    if (mtn == 0) {
        Fail("%s: MTN is NULL: mtn_new failed (%s)", function, mtnError_.empty() ? "no error recorded"
                                                                                   : mtnError_.c_str());
    }
    return mtn;
}

void Robot::PlayMotion(MTN* mtn) {
    CheckMotion(mtn, "mtn_play");
    mtn->motion.Prepare();
    StopMotion(mtn);
    mtn->playing = true;
    mtn->startMs = TimeMs();
    playing_.push_back(mtn);
}

void Robot::StopMotion(MTN* mtn) {
    for (size_t p = 0; p < playing_.size(); p++) {
        if (playing_[p] == mtn) {
            playing_.erase(playing_.begin() + p);
            break;
        }
    }
    mtn->playing = false;
}

bool Robot::IsOver(MTN* mtn) { return !CheckMotion(mtn, "mtn_is_over")->playing; }

long Robot::MotionTime(MTN* mtn) { return CheckMotion(mtn, "mtn_get_time")->playing ? TimeMs() - mtn->startMs : 0; }

}  // namespace wrapper
