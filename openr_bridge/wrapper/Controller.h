/*
 * Controller.h: the Webots OPEN-R wrapper object. A controller written against the Webots
 * Aibo API (<device/robot.h>, <device/servo.h>, ... as aibo_sim/cbind/include has them) is
 * linked with this object and runs on the robot's OPEN-R messages:
 *
 *   Controller.Effector.OCommandVectorData.S      -> OVirtualRobotComm.Effector: set-points, LEDs
 *   OVirtualRobotComm.Sensor.OSensorFrameVectorData.S    -> Controller.Sensor: 4 frames / 32 ms
 *   OVirtualRobotComm.FbkImageSensor.OFbkImageVectorData.S -> Controller.Image (the report's Notify)
 *
 * Start (DoStart): motor power on, Sony's standard joint gains (Model Information 2.2), then the
 * controller's main() is called: robot_live(init) calls init, robot_die registers, robot_run
 * stores the run function and leaves main() (its statements after robot_run are never reached,
 * as in Webots; called in the run function, it leaves that and the new one starts at once).
 * robot_step cannot be: an Aperios object is one thread that must
 * return from each message before the next (the next sensor data) can arrive, so a loop that
 * waits inside a call would never see time pass. robot_step is therefore an explicit error
 * that ends the controller; write the controller with robot_run.
 *
 * Time: 8 ms frames, numbered from the first sensor frame (t = 0). Frame t's sensor values and
 * the newest image taken by then are what the devices sample at t, by Webots' rules
 * (aibo_sim/robot.py): a device enabled with period P samples at every multiple of P after
 * the call. run(ms) is called at the times it asks for (0, then each returned step), after the
 * samples of that time; the servos then move their set-points one frame at a time towards the
 * targets under their velocity and acceleration limits, and MTN motions write theirs, as
 * aibo_sim's Servos and OPEN-R-mode playback do.
 *
 * Because the robot sends sensor values in vectors of 4 frames every 32 ms, frames t-3 .. t
 * are known only at frame t (t = 3, 7, ...): the object computes those 4 frames (samples, run
 * calls, set-points) when the effector asks for its next command vector, right after playing
 * frame t, and sends them as one 4-frame vector. So every set-point the controller causes
 * plays 4 frames (32 ms) after the simulation time the controller saw, exactly: the run
 * equals aibo-sim's openr backend with Simulation(command_latency_frames=4). LEDs go in the
 * same vectors, and are as late; the camera settings (camera_set_*, OPENR::ControlPrimitive)
 * and servo_set_control_p (SetJointGain) act when the call is made, up to 3 frames after the
 * time the controller saw. A first vector of 4 frames (the LEDs as robot_live's function left
 * them, LED2 l1 when it set none) starts the effector's clock.
 *
 * Values as the robot gives them: joint angles and the commanded set-points in micro-radians,
 * distances in micrometres, accelerations in micrometres/s^2; touch sensors 0/1 (switches as
 * sent, pressure sensors above their threshold). Ears (Joint4) are plungers: a set-point rising
 * above mid-range flicks the ear up for EAR_FLICK_FRAMES (128 ms, as Sony's MovingEar7; Sony's
 * Model Information warns that a plunger held on may damage the robot), then it is let down
 * until the set-point falls below mid-range and rises again. LED2 lights are on or off: on for
 * any value but 0.
 *
 * An error in a call (an unknown device, a sample not there yet, ...) prints aibo_sim's message
 * for it, runs the robot_die functions and shuts the robot down (OPENR::Shutdown), as an error
 * ends an aibo-sim run; so does a main() that returns without robot_run. The pause switch
 * shuts the robot down too.
 */
#ifndef AIBO_WRAPPER_CONTROLLER_H
#define AIBO_WRAPPER_CONTROLLER_H

#include <deque>
#include <map>
#include <setjmp.h>
#include <vector>
#include <OPENR/OObject.h>
#include <OPENR/OSubject.h>
#include <OPENR/OObserver.h>
#include <OPENR/OPrimitiveControl.h>
#include "def.h"
#include "Robot.h"

class Controller : public OObject {
public:
    Controller();
    virtual ~Controller() {}

    OSubject*  subject[numOfSubject];
    OObserver* observer[numOfObserver];

    virtual OStatus DoInit(const OSystemEvent& event);
    virtual OStatus DoStart(const OSystemEvent& event);
    virtual OStatus DoStop(const OSystemEvent& event);
    virtual OStatus DoDestroy(const OSystemEvent& event);

    void Ready(const OReadyEvent& event);          /* the effector wants the next vector */
    void NotifySensor(const ONotifyEvent& event);  /* 4 frames of sensor values */
    void Notify(const ONotifyEvent& event);        /* an image (the report's Notify) */
    void NotifyPower(void* message);               /* the pause switch */

    /* For the C API (WebotsApi.cc). */
    static Controller& Instance() { return *instance_; }
    wrapper::Robot& GetRobot() { return robot_; }
    void Die(void (*function)(void));
    void Run(int (*function)(int));
    void CameraControl(int tag, const char* function, int value);
    void SetControlP(int tag, double p);
    void Fail(const char* message) __attribute__((noreturn));
    static void Exit(int status) __attribute__((noreturn));

private:
    enum State { LOADED, RUNNING, ENDED };
    struct Received {
        longword frame;
        RCRegion* region;
    };

    static void CallMain(void*);
    static void CallRun(void*);
    static void CallDie(void*);
    bool Protected(void (*call)(void*), void* argument);
    void End(bool shutdown);
    long TickOf(longword frame) const;
    bool NewestImage(long tick, wrapper::Image* image) const;
    void Process(long last);
    void Flush();
    void Fill(OCommandVectorData* vector, size_t first, size_t end);

    static Controller* instance_;
    wrapper::Robot robot_;
    State state_;
    jmp_buf* failJump_;
    jmp_buf* runJump_;                       /* where robot_run leaves main() or the run function */
    std::vector<OPrimitiveID> ids_;          /* by robot_.Locators(): the joints first */
    std::vector<OPrimitiveID> ledIds_;
    std::map<OPrimitiveID, int> slots_;      /* sensor primitive -> snapshot slot */
    OPrimitiveID cameraId_;
    std::vector<void (*)(void)> dieFunctions_;
    size_t nextDie_;
    int (*run_)(int);
    int lastStep_;
    long runTick_, nextTick_, newestTick_;
    bool haveOrigin_, primed_;
    longword origin_;                        /* frame number of t = 0 */
    std::deque<wrapper::Snapshot> snapshots_;
    std::deque<Received> images_;
    std::vector<wrapper::FrameCommand> pending_;
    std::vector<RCRegion*> regions_;
    std::deque<RCRegion*> outgoing_;
    std::vector<int> earUpFrames_;           /* by joint: frames since an ear's set-point rose above mid-range */
};

#endif
