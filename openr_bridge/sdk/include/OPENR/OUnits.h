/* OUnits.h: OPEN-R's units (micro-metres, micro-radians, ...) and conversions. */
#ifndef _OUnits_h_DEFINED
#define _OUnits_h_DEFINED

#include <Types.h>

typedef slongword Length;          /* 1e-6 m */
typedef slongword Mass;            /* 1e-6 kg */
typedef slongword Angle;           /* 1e-6 rad */
typedef slongword Temperature;     /* 1e-6 degree Celsius */
typedef slongword Velocity;        /* 1e-6 m/s */
typedef slongword Acceleration;    /* 1e-6 m/s^2 */
typedef slongword AngularVelocity; /* 1e-6 rad/s */
typedef slongword Force;           /* 1e-6 N */
typedef slongword Percentage;      /* 1e-6 % */

const slongword oradiansPI   = 3141592;
const slongword oradiansPI_2 = 1570796;
const slongword oradiansPI_4 = 785398;

inline slongword micro(double value) { return (slongword)(value * 1000000.0); }
inline double radians(double deg) { return 3.14159265358979323846 * deg / 180.0; }
inline double degrees(double rad) { return 180.0 * rad / 3.14159265358979323846; }
inline slongword oradians(double deg) { return micro(radians(deg)); }

#endif /* _OUnits_h_DEFINED */
