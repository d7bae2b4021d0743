/*
 * Robot.h: the Webots-era robot behind the wrapper's C API, a C++ port of aibo_sim/robot.py
 * (devices and Webots' sampling rules), aibo_sim/sim.py's Servos (set-points moved towards
 * their targets under velocity and acceleration limits, one 8 ms frame at a time) and the
 * OPEN-R-mode MTN playback of aibo_sim/robot.py. It knows nothing of OPEN-R's messages: the
 * object (Controller.cc) gives it each 8 ms frame's sensor values and the newest image, and
 * sends the set-points it computes.
 *
 * Device tables (locators, joint limits and speeds, Sony's gains) come from Ers7Table.h, which
 * aibo-sim build-ms writes from aibo_sim/ers7.py and the robot model.
 */
#ifndef AIBO_WRAPPER_ROBOT_H
#define AIBO_WRAPPER_ROBOT_H

#include <string>
#include <vector>
#include <OPENR/RCRegion.h>
#include <OPENR/ODataFormats.h>
#include "Mtn.h"

/* The MTN handle of <device/mtn.h>: a motion and its playback. */
struct MTN {
    wrapper::Motion motion;
    bool playing;
    long startMs;
};

namespace wrapper {

const int FRAME_MS = 8;

/* Ends the controller with `message` (formatted as printf): Controller.cc prints it, runs the
 * robot_die functions and shuts the robot down; never returns to the caller. */
void Fail(const char* format, ...) __attribute__((format(printf, 1, 2), noreturn));

/* What the sensor vector said at one 8 ms frame, by sensor slot (Robot::Slot*). */
struct Snapshot {
    long tick;
    std::vector<slongword> values;
    std::vector<sword> duties;  /* each joint slot's PWM duty (ers7::PWM_DUTY_FULL_SCALE: MAX_TORQUE) */
};

/* An image received, with the frame it was taken at. */
struct Image {
    long tick;
    RCRegion* region;
};

/* One 8 ms frame's commands: every joint's set-point and every LED's intensity, with which
 * of them the controller has moved or set so far (only those are commanded). */
struct FrameCommand {
    std::vector<double> joints;
    std::vector<bool> jointMoved;
    std::vector<int> leds;
    std::vector<bool> ledSet;
};

class Robot {
public:
    enum Kind { SERVO, CAMERA, DISTANCE, TOUCH, ACCELEROMETER, LED, FORCE_FEEDBACK };

    Robot();

    /* The sensor slots: joint j is slot j; then each other sensor's (three for the accelerometer). */
    int NumSlots() const { return numSlots_; }
    /* The slot a locator's values go to, or -1. SetSwitch marks a touch sensor whose values are
     * 0/1 switches (the others are pressure, AD values). */
    int SlotOf(const char* locator) const;
    void SetSwitch(int slot) { switch_[slot] = true; }
    const std::vector<std::string>& Locators() const { return locators_; }  /* every primitive opened */

    /* Time: the 8 ms frame being simulated, in ms since the first sensor frame. */
    long TimeMs() const { return tick_ * FRAME_MS; }

    /* Frame 0: the joints' set-points start where the sensors say they are. */
    void Start(const Snapshot& frame);
    /* Frame tick > 0: the devices due take their sample (Robot.step's after-frame sampling). */
    void Sample(long tick, const Snapshot& frame, const Image* newest);
    /* This frame's motions and servo step: its commands. */
    void PlayFrame(FrameCommand* command);
    void Commands(FrameCommand* command) const;  /* the commands now, without a step */
    void Release();                               /* gives back the sampled image */

    /* The API (errors end the controller through Fail, with aibo_sim's messages). */
    int GetDevice(const char* name);
    void Enable(int tag, Kind kind, int ms);
    void Disable(int tag, Kind kind);
    double Value(int tag, Kind kind, int axis);
    /* A servo's motor force feedback, sampled on a period of its own (a device without a name). */
    void EnableForceFeedback(int tag, int ms);
    void DisableForceFeedback(int tag) { DisableDevice(ForceFeedbackOf(tag)); }
    double ForceFeedback(int tag) { return DeviceValue(ForceFeedbackOf(tag), 0); }
    void SetPosition(int tag, double radians);
    void SetVelocity(int tag, double value);
    void SetAcceleration(int tag, double value);
    double CheckedNumber(int tag, Kind kind, const char* what, double value);
    int JointOf(int tag, Kind kind);
    void SetLed(int tag, int value);
    unsigned char* CameraImage(int tag);
    int CameraSaveImage(int tag, const char* filename, int quality);  /* PNG or JPEG; -1 when not written */
    int CameraWidth(int tag);
    int CameraHeight(int tag);
    std::string DeviceLocator(int tag, Kind kind);

    MTN* NewMotion(const char* filename);
    void PlayMotion(MTN* mtn);
    void StopMotion(MTN* mtn);
    bool IsOver(MTN* mtn);
    long MotionTime(MTN* mtn);
    MTN* CheckMotion(MTN* mtn, const char* function);
    const char* MotionError() const { return mtnError_.c_str(); } /* "" before any error, as Webots' */

private:
    struct Device {
        std::string locator;
        Kind kind;
        int index;          /* joint, LED, or first sensor slot */
        int period;         /* 0: disabled */
        long nextSampleMs;
        bool hasValue;
        double value[3];
        Image image;        /* the camera's sample (a reference held) */
        bool decoded;
        double threshold;   /* a pressure sensor's touch threshold, AD units */
    };

    Device& Tagged(int tag, Kind kind);
    Device& ForceFeedbackOf(int tag) { return devices_[forceFeedback_ + Tagged(tag, SERVO).index]; }
    void EnableDevice(Device& device, int ms);
    void DisableDevice(Device& device);
    double DeviceValue(Device& device, int axis);
    void TakeSample(Device& device, const Snapshot& frame, const Image* newest);
    void SetTarget(int joint, double position);
    void Advance();

    std::vector<Device> devices_;
    std::vector<std::string> names_;     /* robot_get_device's names (aliases too) */
    std::vector<int> named_;             /* the device of each name */
    std::vector<int> tags_;              /* tag k + 1's device */
    std::vector<std::string> locators_;
    int numSlots_;
    size_t forceFeedback_;  /* the first joint's force feedback device in devices_ */
    std::vector<bool> switch_;
    long tick_;

    /* Servos (sim.Servos): per joint. */
    std::vector<double> low_, high_, maxVelocity_, velocity_, acceleration_, target_, command_, speed_, start_;
    std::vector<bool> targeted_, moved_;

    std::vector<int> led_;
    std::vector<bool> ledSet_;
    std::vector<unsigned char> rgb_;
    std::vector<MTN*> playing_;
    std::string mtnError_;
};

}  // namespace wrapper

#endif
