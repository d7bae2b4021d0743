/* The Webots 5 Aibo controller API, as aibo-sim serves it: the robot.
 *
 * A controller calls robot_live(reset) first, then robot_run(run), or robot_step(ms) in a
 * loop of its own. Device tags are small positive numbers (0 is never a tag). Types are the
 * report's where it gives them; numbers passed in and read back are double (Webots 5's own
 * float or double is unconfirmed), so that a C controller computes exactly as the same
 * controller in Python. An error in a call (an unknown device, a bad value) ends the run
 * with the message the Python API gives, as a Python controller's exception does. */
#ifndef AIBO_SIM_DEVICE_ROBOT_H
#define AIBO_SIM_DEVICE_ROBOT_H

#ifdef __cplusplus
extern "C" {
#endif

typedef unsigned short DeviceTag;

/* Registers reset, the initialisation function, and calls it once. */
void robot_live(void (*reset)(void));
/* Registers a function called when the controller ends (its run is over or it exits). */
void robot_die(void (*exit_fn)(void));
/* Calls run(ms) until the run ends: ms is the step just simulated (0 on the first call),
 * the return value the next step in ms, a multiple of 8. Never returns. */
void robot_run(int (*run)(int));
/* Simulates ms milliseconds (a multiple of the 8 ms joint frame); returns 0. When the run's
 * duration is over, the robot_die functions run and the controller exits. */
int robot_step(int ms);
DeviceTag robot_get_device(const char *name);
double robot_get_time(void);
const char *robot_get_name(void);
void robot_console_printf(const char *format, ...);
/* 0: in the simulator (aibo-sim run); 1: cross-compiled on the robot (a build-ms memory stick,
 * on the robot or on aibo-sim's OPEN-R runtime). */
int robot_get_mode(void);
/* The simulation's step, of which every robot_step is a whole number: the 8 ms joint frame. */
double robot_get_basic_time_step(void);
/* 1: the simulation waits for the controller at each step; 0 on the robot (a build-ms memory stick). */
int robot_get_synchronization(void);
/* The keyboard: runs are headless and a robot has none, so robot_keyboard_get_key() is 0 (no key). */
void robot_keyboard_enable(unsigned short ms);
void robot_keyboard_disable(void);
int robot_keyboard_get_key(void);

#ifdef __cplusplus
}
#endif

#endif
