/* The controller side of aibo-sim's C binding: each API call becomes a message to the
 * simulator (aibo_sim/cbind/protocol.py), which makes the same call on the Python API.
 *
 * The simulator starts the controller with AIBO_SIM_FD (its end of a socket) and AIBO_SIM_SHM
 * (a file mapped by both: camera images). A call with results is sent at once and waits for
 * its answer; calls without results are queued and go with it (or at exit). robot_step's answer
 * brings the answers of the calls that only read the state (protocol.PREFETCHED) the controller
 * made before: they serve it until its next call without results. When the
 * simulator answers "end" (the run is over), the controller exits with status 0; at exit, the
 * robot_die functions run, and one that steps past the end ends there, as Python's
 * SimulationEnd ends it. Where the binding cannot go on (the controller closed its end of the
 * socket, then called; a call from a second thread, or from a signal handler that interrupted
 * a call; a call too large), it exits, leaving the
 * reason for the simulator in AIBO_SIM_SHM, past the images (serve.py reports it). Standard
 * output is line-buffered and flushed at each call, so what the controller printed shows
 * before its end, in a file or a pipe too. */
#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <device/accelerometer.h>
#include <device/camera.h>
#include <device/distance_sensor.h>
#include <device/led.h>
#include <device/mtn.h>
#include <device/robot.h>
#include <device/servo.h>
#include <device/touch_sensor.h>

#include "aibo_ops.h"

#define MAX_DIE_FUNCTIONS 64
/* How long a call polls for its answer before it sleeps: the simulator answers most calls in
 * microseconds, and a process that sleeps wakes up slowly on a virtual machine. */
#define SPIN_NS 2000000L

static int channel = -1;
static enum aibo_op current_op; /* the call being made */
static unsigned char *images;
/* Calls without results wait in `outgoing` and go with the next call that has results (one
 * write); `start` is where the call being built begins. Answers arrive in `answer`. */
static unsigned char outgoing[1 << 16], answer[AIBO_MAX_ANSWER_BYTES];
static size_t outgoing_length, start, cursor, answer_end;
/* The answers robot_step brought ahead: (int32 call, int32 argument, uint32 size, results)... */
static unsigned char ahead[1 << 16];
static size_t ahead_length;
static void (*die_functions[MAX_DIE_FUNCTIONS])(void);
static int die_count, exiting, dying;
static jmp_buf die_function_end; /* where a robot_die function ends that steps past the run's end (while dying) */
static pthread_t caller;          /* the thread that made the first call: the only one answered */
static pthread_mutex_t calling = PTHREAD_MUTEX_INITIALIZER; /* held by a call being made */
static __thread volatile sig_atomic_t in_call; /* this thread makes a call: one of its signal handler's would deadlock */
static int forked;                     /* this is a child the controller forked: its calls are refused */
static char reason_file[4096];         /* AIBO_SIM_SHM, where the binding leaves its reasons */
static size_t reason_length;           /* of the reasons left there so far */

static void in_a_forked_child(void) { forked = 1; }

/* What the controller printed shows before anything ends it, in a file or a pipe too; a child it
 * forks, even before its first call, is known as one. */
__attribute__((constructor)) static void prepare(void) {
    setvbuf(stdout, NULL, _IOLBF, BUFSIZ);
    pthread_atfork(NULL, NULL, in_a_forked_child);
}

/* The controller's error as the simulator reports it: in AIBO_SIM_SHM past the images (serve.py
 * reads it, up to AIBO_MAX_REASON_BYTES, NUL-terminated), after the reasons left before (a
 * robot_die function's), or on stderr where that file cannot be opened. */
static void leave_reason(const char *format, va_list args) {
    char why[AIBO_MAX_REASON_BYTES];
    int size = snprintf(why, sizeof why, "%s", reason_length ? "\nthen " : "");
    int more = vsnprintf(why + size, sizeof why - (size_t)size, format, args);
    size = more < 0 ? size : size + more;
    if (size >= (int)sizeof why) size = (int)sizeof why - 1;
    size_t room = sizeof why - 1 - reason_length; /* the whole text, its NUL included, fits in what serve reads */
    size_t length = (size_t)size < room ? (size_t)size : room;
    why[length] = 0;
    int file = reason_file[0] ? open(reason_file, O_WRONLY | O_CLOEXEC) : -1;
    if (file >= 0 && pwrite(file, why, length + 1, AIBO_MAX_IMAGE_BYTES + reason_length) == (ssize_t)length + 1) {
        close(file);
        reason_length += length;
    } else {
        fprintf(stderr, "aibo-sim C binding: %s\n", why);
    }
}

/* The binding cannot go on: its reason, and the controller ends without its robot_die functions. */
static void binding_failed(const char *format, ...) {
    va_list args;
    va_start(args, format);
    leave_reason(format, args);
    va_end(args);
    _exit(70);
}

/* An error the Python API raises: its reason, and the controller ends through its robot_die
 * functions, as an exception ends a Python controller. */
static void controller_failed(const char *format, ...) {
    va_list args;
    va_start(args, format);
    leave_reason(format, args);
    va_end(args);
    exit(1);
}

static void fail(const char *what) { binding_failed("%s: %s", what, strerror(errno)); }

static void flush_calls(void);
static void settle_calls(void);

/* At exit (main returned, exit() called, or the run's end): the robot_die functions, in the
 * thread that ended the controller (the only one answered from then on), each after the calls
 * queued before it are settled (a failed one ends the controller, not the next function), then
 * the calls still waiting to be sent. It is registered again first: after a robot_die function
 * that calls exit(), it goes on with the next one there (glibc runs a handler registered during
 * exit). A forked child's exit leaves the controller's connection alone. */
static void at_exit(void) {
    if (forked) return;
    if (in_call) {
        binding_failed("exit() called in a signal handler that interrupted %s: the robot_die functions cannot run "
                       "(exit() is not async-signal-safe: set a flag that the controller's loop reads)",
                       aibo_op_names[current_op]);
    }
    pthread_mutex_lock(&calling); /* after the call another thread is making */
    if (!exiting) {
        __atomic_store_n(&exiting, 1, __ATOMIC_RELEASE);
        __atomic_store_n(&caller, pthread_self(), __ATOMIC_RELEASE);
    }
    int ending = pthread_equal(pthread_self(), caller);
    pthread_mutex_unlock(&calling);
    if (!ending) {
        for (;;) pause(); /* another thread's exit() while the controller ends: that ending goes on */
    }
    if (die_count) atexit(at_exit);
    dying = 0; /* here again: the robot_die function that called exit() is over */
    while (die_count) {
        settle_calls();
        void (*exit_fn)(void) = die_functions[0];
        memmove(die_functions, die_functions + 1, --die_count * sizeof *die_functions);
        dying = 1;
        if (!setjmp(die_function_end)) exit_fn(); /* C++: the locals it left are not destroyed */
        dying = 0;
    }
    flush_calls();
}

static void connect_to_simulator(void) {
    const char *fd = getenv("AIBO_SIM_FD"), *shm = getenv("AIBO_SIM_SHM");
    if (!fd || !shm) {
        fprintf(stderr, "aibo-sim C binding: run this controller with `aibo-sim run`\n");
        _exit(70);
    }
    channel = atoi(fd);
    snprintf(reason_file, sizeof reason_file, "%s", shm);
    int file = open(shm, O_RDONLY);
    if (file < 0) fail(shm);
    images = mmap(NULL, AIBO_MAX_IMAGE_BYTES, PROT_READ, MAP_SHARED, file, 0);
    if (images == MAP_FAILED) fail("mmap");
    close(file);
    /* The programs it runs inherit neither the connection nor the variables naming it. */
    fcntl(channel, F_SETFD, FD_CLOEXEC);
    unsetenv("AIBO_SIM_FD");
    unsetenv("AIBO_SIM_SHM");
    __atomic_store_n(&caller, pthread_self(), __ATOMIC_RELEASE);
    atexit(at_exit);
}

/* The socket failed: the simulator is gone (EPIPE, ECONNRESET), and reports why itself; else the
 * controller closed its descriptor (EBADF), or the number now names another file or socket,
 * which the simulator, still there, is told. */
static void channel_failed(void) {
    if (errno != EPIPE && errno != ECONNRESET) {
        binding_failed("closed its connection to the simulator (descriptor %d, AIBO_SIM_FD), then made a call",
                       channel);
    }
    _exit(70); /* the simulator is gone: it reports why */
}

/* ---- sending */

static void write_all(const unsigned char *bytes, size_t size) {
    while (size) {
        ssize_t sent = send(channel, bytes, size, MSG_NOSIGNAL); /* never write()s into a file in its place */
        if (sent < 0 && errno == EINTR) continue;
        if (sent <= 0) channel_failed();
        bytes += sent;
        size -= (size_t)sent;
    }
}

static void flush_calls(void) {
    if (channel >= 0 && start) write_all(outgoing, start);
    start = outgoing_length = 0;
}

static void put(const void *bytes, size_t size) {
    if (outgoing_length + size > sizeof outgoing) {
        if (start == 0) binding_failed("%s: its arguments exceed %zu bytes", aibo_op_names[current_op], sizeof outgoing);
        size_t building = outgoing_length - start; /* send the calls before this one */
        write_all(outgoing, start);
        memmove(outgoing, outgoing + start, building);
        start = 0;
        outgoing_length = building;
        put(bytes, size);
        return;
    }
    memcpy(outgoing + outgoing_length, bytes, size);
    outgoing_length += size;
}

/* A call is made from the thread that made the first (at exit, the one that ended the
 * controller), holding `calling` until it is sent (and answered); another thread's would mix
 * their messages: it ends the run, or at exit waits for the end. A call from a signal handler
 * that interrupted a call, or from a forked child, is refused. */
static void start_call(enum aibo_op call) {
    if (forked) {
        fprintf(stderr, "aibo-sim C binding: %s called in a child process (fork): only the controller's process calls\n",
                aibo_op_names[call]);
        _exit(70);
    }
    if (in_call) {
        binding_failed("%s called in a signal handler that interrupted %s: the API is not async-signal-safe (set a "
                       "flag that the controller's loop reads)",
                       aibo_op_names[call], aibo_op_names[current_op]);
    }
    /* Known before waiting for `calling`: the caller, calling in a loop, could keep it for good.
     * The caller is read before `exiting`, which at_exit sets first: a caller changed at exit is
     * seen with it. */
    pthread_t calls = __atomic_load_n(&caller, __ATOMIC_ACQUIRE);
    if (!pthread_equal(pthread_self(), calls) && !__atomic_load_n(&exiting, __ATOMIC_ACQUIRE)) {
        binding_failed("%s called from a second thread: a C controller makes its calls from one thread",
                       aibo_op_names[call]);
    }
    in_call = 1;
    pthread_mutex_lock(&calling);
    if (pthread_equal(pthread_self(), caller)) {
        current_op = call;
        return;
    }
    in_call = 0;
    if (!exiting) {
        binding_failed("%s called from a second thread: a C controller makes its calls from one thread",
                       aibo_op_names[call]);
    }
    pthread_mutex_unlock(&calling);
    for (;;) pause();
}

/* The call is sent (and answered): another may start. */
static void finish_call(void) {
    in_call = 0;
    pthread_mutex_unlock(&calling);
}

static void begin(enum aibo_op call) {
    if (channel < 0) connect_to_simulator();
    start_call(call);
    int32_t code = call, size = 0;
    put(&size, 4); /* the length, filled in by end_call */
    put(&code, 4);
}

static void put_int(int value) {
    int32_t v = value;
    put(&v, 4);
}

static void put_double(double value) { put(&value, 8); }

static void put_string(const char *text) {
    if (!text) text = "";
    uint32_t size = (uint32_t)strlen(text);
    put(&size, 4);
    put(text, size);
}

/* The call built since begin() is complete: its length goes in front. */
static void end_call(void) {
    uint32_t size = (uint32_t)(outgoing_length - start - 4);
    memcpy(outgoing + start, &size, 4);
    start = outgoing_length;
}

/* A call without results joins the queue; it may change what the answers ahead say. */
static void send_call(void) {
    end_call();
    ahead_length = 0;
    finish_call();
}

/* ---- answers */

static long now_ns(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1000000000L + t.tv_nsec;
}

/* Reads at least `need` bytes of the answer: polls for SPIN_NS, yielding the core between
 * polls, then sleeps. */
static size_t read_answer(size_t have, size_t need) {
    long deadline = now_ns() + SPIN_NS;
    while (have < need) {
        int flags = now_ns() < deadline ? MSG_DONTWAIT : 0;
        ssize_t got = recv(channel, answer + have, sizeof answer - have, flags);
        if (got > 0) {
            have += (size_t)got;
        } else if (got < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
            sched_yield();
        } else if (got == 0) {
            _exit(70); /* the simulator is gone: it reports why */
        } else if (errno != EINTR) {
            channel_failed();
        }
    }
    return have;
}

/* Sends the queue and this call, and reads its answer; on "end" or "failed", the controller
 * ends (a robot_die function ends there). */
static void call(void) {
    end_call();
    fflush(stdout); /* what the controller printed shows even if this call's error ends it */
    flush_calls();
    size_t have = read_answer(0, 4);
    uint32_t size;
    memcpy(&size, answer, 4);
    if (size > sizeof answer - 4) binding_failed("%s: an answer of %u bytes is too large", aibo_op_names[current_op], size);
    read_answer(have, 4 + size);
    cursor = 8;
    answer_end = 4 + size;
    int32_t status;
    memcpy(&status, answer + 4, 4);
    finish_call();
    if (status == AIBO_STATUS_END || status == AIBO_STATUS_FAILED) {
        /* the run is over, or a call failed (the simulator reports it): at_exit runs the
         * robot_die functions; in one of them, it ends there */
        if (!exiting) exit(status == AIBO_STATUS_END ? 0 : 1);
        if (dying) longjmp(die_function_end, 1); /* else an atexit handler of its own: the call returns */
    }
}

/* The calls queued so far made, and answered together by robot_get_mode's answer: the
 * simulator reports one that failed, and what the controller does next goes on. */
static void settle_calls(void) {
    if (start == 0) return;
    begin(AIBO_OP_robot_get_mode);
    call();
}

static int get_int(void) {
    int32_t v;
    memcpy(&v, answer + cursor, 4);
    cursor += 4;
    return v;
}

static double get_double(void) {
    double v;
    memcpy(&v, answer + cursor, 8);
    cursor += 8;
    return v;
}

/* A string answer, kept until the next call of the same kind. */
static const char *get_string(char *keep, size_t capacity) {
    uint32_t size;
    memcpy(&size, answer + cursor, 4);
    cursor += 4;
    if (size >= capacity) size = (uint32_t)capacity - 1;
    memcpy(keep, answer + cursor, size);
    keep[size] = 0;
    return keep;
}

/* The answer of `op` on `arg` (a tag, a motion, 0 for none) robot_step brought, into `answer`. */
static int answered_ahead(enum aibo_op op, int arg) {
    if (channel < 0) return 0;
    start_call(op);
    for (size_t at = 0; at < ahead_length;) {
        int32_t entry[2];
        uint32_t size;
        memcpy(entry, ahead + at, 8);
        memcpy(&size, ahead + at + 8, 4);
        if (entry[0] == (int32_t)op && entry[1] == arg) {
            memcpy(answer + 8, ahead + at + 12, size);
            cursor = 8;
            finish_call();
            return 1;
        }
        at += 12 + size;
    }
    finish_call();
    return 0;
}

/* A call with results on a tag or a motion: answered ahead, or made. */
static void ask(enum aibo_op op, int arg) {
    if (answered_ahead(op, arg)) return;
    begin(op);
    put_int(arg);
    call();
}

/* A call without results on a tag, a motion or a period (`arg`), with no other argument. */
static void send_tag(enum aibo_op op, int arg) {
    begin(op);
    put_int(arg);
    send_call();
}

static void send_tag_int(enum aibo_op op, DeviceTag tag, int value) {
    begin(op);
    put_int(tag);
    put_int(value);
    send_call();
}

static void send_tag_double(enum aibo_op op, DeviceTag tag, double value) {
    begin(op);
    put_int(tag);
    put_double(value);
    send_call();
}

static double get_tag_double(enum aibo_op op, DeviceTag tag) {
    ask(op, tag);
    return get_double();
}

static int get_tag_int(enum aibo_op op, DeviceTag tag) {
    ask(op, tag);
    return get_int();
}

/* ---- robot */

void robot_live(void (*reset)(void)) {
    if (channel < 0) connect_to_simulator();
    if (reset) reset();
}

void robot_die(void (*exit_fn)(void)) {
    if (channel < 0) connect_to_simulator();
    if (!exit_fn) controller_failed("robot_die(NULL): the exit function must be callable");
    if (die_count == MAX_DIE_FUNCTIONS) binding_failed("more than %d robot_die functions", MAX_DIE_FUNCTIONS);
    die_functions[die_count++] = exit_fn;
}

int robot_step(int ms) {
    begin(AIBO_OP_robot_step);
    put_int(ms);
    call();
    ahead_length = 0;
    if (exiting) return 0;
    int result = get_int();
    ahead_length = answer_end - cursor;
    memcpy(ahead, answer + cursor, ahead_length);
    return result;
}

void robot_run(int (*run)(int)) {
    if (channel < 0) connect_to_simulator();
    if (!run) controller_failed("robot_run(NULL): the run function must be callable");
    int ms = 0;
    for (;;) {
        int returned = run(ms);
        if (returned <= 0) {
            controller_failed("run function returned %d: it must return the next step in ms (e.g. TIME_STEP)", returned);
        }
        if (returned % AIBO_FRAME_MS) { /* named as its own (robot_step(20) raised ..., a call it never made) */
            controller_failed("run function returned %d: a step must be a whole multiple of the %d ms joint frame",
                              returned, AIBO_FRAME_MS);
        }
        robot_step(ms = returned);
    }
}

DeviceTag robot_get_device(const char *name) {
    begin(AIBO_OP_robot_get_device);
    put_string(name);
    call();
    return (DeviceTag)get_int();
}

double robot_get_time(void) {
    if (!answered_ahead(AIBO_OP_robot_get_time, 0)) {
        begin(AIBO_OP_robot_get_time);
        call();
    }
    return get_double();
}

const char *robot_get_name(void) {
    static char name[64];
    begin(AIBO_OP_robot_get_name);
    call();
    return get_string(name, sizeof name);
}

int robot_get_mode(void) {
    begin(AIBO_OP_robot_get_mode);
    call();
    return get_int();
}

double robot_get_basic_time_step(void) {
    begin(AIBO_OP_robot_get_basic_time_step);
    call();
    return get_double();
}

int robot_get_synchronization(void) {
    begin(AIBO_OP_robot_get_synchronization);
    call();
    return get_int();
}

void robot_keyboard_enable(unsigned short ms) { send_tag(AIBO_OP_robot_keyboard_enable, ms); }

void robot_keyboard_disable(void) {
    begin(AIBO_OP_robot_keyboard_disable);
    send_call();
}

int robot_keyboard_get_key(void) {
    begin(AIBO_OP_robot_keyboard_get_key);
    call();
    return get_int();
}

/* Printed here, as Python's writes to its stdout: in order with the controller's printf. */
void robot_console_printf(const char *format, ...) {
    va_list args;
    va_start(args, format);
    vprintf(format, args);
    va_end(args);
    fflush(stdout);
}

/* ---- servos */

void servo_enable_position(DeviceTag s, unsigned short ms) { send_tag_int(AIBO_OP_servo_enable_position, s, ms); }
void servo_disable_position(DeviceTag s) { send_tag(AIBO_OP_servo_disable_position, s); }
double servo_get_position(DeviceTag s) { return get_tag_double(AIBO_OP_servo_get_position, s); }
void servo_set_position(DeviceTag s, double v) { send_tag_double(AIBO_OP_servo_set_position, s, v); }
void servo_set_velocity(DeviceTag s, double v) { send_tag_double(AIBO_OP_servo_set_velocity, s, v); }
void servo_set_acceleration(DeviceTag s, double v) { send_tag_double(AIBO_OP_servo_set_acceleration, s, v); }
void servo_set_motor_force(DeviceTag s, double v) { send_tag_double(AIBO_OP_servo_set_motor_force, s, v); }
void servo_set_control_p(DeviceTag s, double v) { send_tag_double(AIBO_OP_servo_set_control_p, s, v); }
void servo_enable_motor_force_feedback(DeviceTag s, unsigned short ms) {
    send_tag_int(AIBO_OP_servo_enable_motor_force_feedback, s, ms);
}
void servo_disable_motor_force_feedback(DeviceTag s) { send_tag(AIBO_OP_servo_disable_motor_force_feedback, s); }
double servo_get_motor_force_feedback(DeviceTag s) { return get_tag_double(AIBO_OP_servo_get_motor_force_feedback, s); }

/* ---- camera */

void camera_enable(DeviceTag c, unsigned short ms) { send_tag_int(AIBO_OP_camera_enable, c, ms); }
void camera_disable(DeviceTag c) { send_tag(AIBO_OP_camera_disable, c); }

unsigned char *camera_get_image(DeviceTag c) {
    static unsigned char *copy;
    ask(AIBO_OP_camera_get_image, c);
    int width = get_int(), height = get_int();
    size_t size = (size_t)width * (size_t)height * 3;
    /* The controller's own copy: the shared block changes with the next image. */
    if (!copy && !(copy = malloc(AIBO_MAX_IMAGE_BYTES))) fail("malloc");
    memcpy(copy, images, size);
    return copy;
}

/* A relative name is the controller's: its working folder goes with it (the simulator's may be another). */
int camera_save_image(DeviceTag c, const char *filename, int quality) {
    static char folder[8192];
    int relative = filename != NULL && filename[0] != 0 && filename[0] != '/';
    if (relative && getcwd(folder, sizeof folder) == NULL) { /* removed, say: no file can be made there */
        fprintf(stderr, "aibo-sim C binding: camera_save_image('%s', %d): cannot write %s: the working folder: %s\n",
                filename, quality, filename, strerror(errno));
        return -1;
    }
    begin(AIBO_OP_camera_save_image);
    put_int(c);
    put_string(relative ? folder : "");
    put_string(filename);
    put_int(quality);
    call();
    return get_int();
}

/* A camera's size and field of view are fixed for the run: asked once per tag, not at every call
 * (a pixel loop's bounds would cost a round trip each). */
#define CAMERA_CONSTANT(type, name, getter)                            \
    type camera_get_##name(DeviceTag c) {                              \
        static DeviceTag asked;                                        \
        static type value;                                             \
        if (c != asked || c == 0) {                                    \
            value = (type)getter(AIBO_OP_camera_get_##name, c);        \
            asked = c;                                                 \
        }                                                              \
        return value;                                                  \
    }
CAMERA_CONSTANT(unsigned short, width, get_tag_int)
CAMERA_CONSTANT(unsigned short, height, get_tag_int)
CAMERA_CONSTANT(float, fov, get_tag_double)
void camera_set_white_balance(DeviceTag c, int v) { send_tag_int(AIBO_OP_camera_set_white_balance, c, v); }
void camera_set_gain(DeviceTag c, int v) { send_tag_int(AIBO_OP_camera_set_gain, c, v); }
void camera_set_shutter_speed(DeviceTag c, int v) { send_tag_int(AIBO_OP_camera_set_shutter_speed, c, v); }

/* ---- sensors, LEDs */

void distance_sensor_enable(DeviceTag d, unsigned short ms) { send_tag_int(AIBO_OP_distance_sensor_enable, d, ms); }
void distance_sensor_disable(DeviceTag d) { send_tag(AIBO_OP_distance_sensor_disable, d); }
double distance_sensor_get_value(DeviceTag d) { return get_tag_double(AIBO_OP_distance_sensor_get_value, d); }
void touch_sensor_enable(DeviceTag t, unsigned short ms) { send_tag_int(AIBO_OP_touch_sensor_enable, t, ms); }
void touch_sensor_disable(DeviceTag t) { send_tag(AIBO_OP_touch_sensor_disable, t); }
double touch_sensor_get_value(DeviceTag t) { return get_tag_double(AIBO_OP_touch_sensor_get_value, t); }
void accelerometer_enable(DeviceTag a, unsigned short ms) { send_tag_int(AIBO_OP_accelerometer_enable, a, ms); }
void accelerometer_disable(DeviceTag a) { send_tag(AIBO_OP_accelerometer_disable, a); }

const float *accelerometer_get_values(DeviceTag a) {
    static float values[3];
    ask(AIBO_OP_accelerometer_get_values, a);
    for (int k = 0; k < 3; k++) values[k] = (float)get_double();
    return values;
}

void led_set(DeviceTag l, int value) { send_tag_int(AIBO_OP_led_set, l, value); }

/* ---- MTN */

/* An MTN pointer is the simulator's number for the motion, never dereferenced: it stays
   recognisable after mtn_delete, so a call on a deleted motion gets an error saying so. */
static int mtn_id(MTN *mtn) { return (int)(intptr_t)mtn; }

MTN *mtn_new(const char *filename) {
    begin(AIBO_OP_mtn_new);
    put_string(filename);
    call();
    return (MTN *)(intptr_t)get_int();
}

void mtn_delete(MTN *mtn) { send_tag(AIBO_OP_mtn_delete, mtn_id(mtn)); }

void mtn_play(MTN *mtn) { send_tag(AIBO_OP_mtn_play, mtn_id(mtn)); }

static int mtn_int(enum aibo_op op, MTN *mtn) {
    ask(op, mtn_id(mtn));
    return get_int();
}

int mtn_is_over(MTN *mtn) { return mtn_int(AIBO_OP_mtn_is_over, mtn); }
int mtn_get_length(MTN *mtn) { return mtn_int(AIBO_OP_mtn_get_length, mtn); }
int mtn_get_time(MTN *mtn) { return mtn_int(AIBO_OP_mtn_get_time, mtn); }

const char *mtn_get_name(MTN *mtn) {
    static char name[256];
    ask(AIBO_OP_mtn_get_name, mtn_id(mtn));
    return get_string(name, sizeof name);
}

void mtn_fprint(FILE *file, MTN *mtn) {
    static char text[8192];
    ask(AIBO_OP_mtn_fprint, mtn_id(mtn));
    fputs(get_string(text, sizeof text), file);
}

const char *mtn_get_error(void) {
    static char error[1024];
    begin(AIBO_OP_mtn_get_error);
    call();
    return get_string(error, sizeof error); /* "" before any error, as Webots' */
}
