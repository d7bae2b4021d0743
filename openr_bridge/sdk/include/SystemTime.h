/* SystemTime.h: Aperios's clock, seconds and microseconds since the robot started
 * (GetSystemTime, MCOOP.h). A structure of two 32-bit words, as on the robot. */
#ifndef _SystemTime_h_DEFINED
#define _SystemTime_h_DEFINED

#include <Types.h>

struct structSystemTime {
    longword seconds;
    longword useconds;
};

#ifdef __cplusplus
struct SystemTime : structSystemTime {
    SystemTime() { seconds = 0; useconds = 0; }
    SystemTime(longword sec, longword usec) { seconds = sec; useconds = usec; }
    /* An invalid time has every bit of both words set. */
    Boolean IsValid() { return !(seconds == 0xffffffff && useconds == 0xffffffff); }
    void MakeInvalid() { seconds = useconds = 0xffffffff; }
};

inline int operator<(const SystemTime& a, const SystemTime& b) {
    return a.seconds < b.seconds || (a.seconds == b.seconds && a.useconds < b.useconds);
}

inline SystemTime operator+(const SystemTime& a, const SystemTime& b) {
    longword micro = a.useconds + b.useconds;
    return micro >= 1000000 ? SystemTime(a.seconds + b.seconds + 1, micro - 1000000)
                            : SystemTime(a.seconds + b.seconds, micro);
}

/* a - b, for a not before b. */
inline SystemTime operator-(const SystemTime& a, const SystemTime& b) {
    return a.useconds < b.useconds ? SystemTime(a.seconds - b.seconds - 1, 1000000 + a.useconds - b.useconds)
                                   : SystemTime(a.seconds - b.seconds, a.useconds - b.useconds);
}
#else
typedef struct structSystemTime SystemTime;
#endif

OPENR_STATIC_ASSERT(sizeof(SystemTime) == 8, SystemTime_is_8_bytes);

#endif /* _SystemTime_h_DEFINED */
