/* OTime.h: calendar time with a time-zone difference (in hours). The clock is kept in 32 bits, the
 * robot's time_t, so that an OTime has the robot's 8 bytes here too. */
#ifndef _OTime_h_DEFINED
#define _OTime_h_DEFINED

#include <time.h>
#include <Types.h>
#include <OPENR/OStatus.h>

const sbyte otimeTIME_DIF_UNDEF = 0x7F;
const int   otimeSTART_YEAR     = 2000;

class OTime {
public:
    OTime() : clock_(0), timeDif_(otimeTIME_DIF_UNDEF) {}
    OTime(time_t clock, sbyte timeDif) : clock_((slongword)clock), timeDif_(timeDif) {}
    bool operator<(const OTime& rhs) const { return clock_ < rhs.clock_; }
    bool operator<=(const OTime& rhs) const { return clock_ <= rhs.clock_; }
    bool operator>(const OTime& rhs) const { return clock_ > rhs.clock_; }
    bool operator>=(const OTime& rhs) const { return clock_ >= rhs.clock_; }
    bool operator==(const OTime& rhs) const { return clock_ == rhs.clock_; }
    OStatus Set(time_t clock, sbyte timeDif) { clock_ = (slongword)clock; timeDif_ = timeDif; return oSUCCESS; }
    OStatus SetClock(time_t clock) { clock_ = (slongword)clock; return oSUCCESS; }
    OStatus SetLocalTime(time_t local) { clock_ = (slongword)(local - (time_t)timeDif_ * 3600); return oSUCCESS; }
    OStatus SetTimeDif(sbyte timeDif) { timeDif_ = timeDif; return oSUCCESS; }
    time_t GetClock() const { return clock_; }
    time_t GetLocalTime() const { return clock_ + (time_t)timeDif_ * 3600; }
    sbyte  GetTimeDif() const { return timeDif_; }

private:
    slongword clock_;
    sbyte     timeDif_;
};
OPENR_STATIC_ASSERT(sizeof(OTime) == 8, OTime_is_8_bytes);

#endif /* _OTime_h_DEFINED */
