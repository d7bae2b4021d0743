/*
 * OSyslog.h: the console. OSYSPRINT((format, ...)) prints; OSYSLOG1..4((priority, format, ...))
 * log at the levels OSYSLOG_SHOW enables (1 by default); OSYSDEBUG prints only with OPENR_DEBUG.
 * On the host both go to the run's log, each line marked with the object that printed it.
 */
#ifndef _OSyslog_h_DEFINED
#define _OSyslog_h_DEFINED

#include <Types.h>
#include <OPENR/OPENR.h>

#ifndef OSYSLOG_SHOW
#if defined(SYSMSGSHOW) && SYSMSGSHOW > 0
#define OSYSLOG_SHOW 4
#else
#define OSYSLOG_SHOW 1
#endif
#endif

#if OSYSLOG_SHOW > 0
#define OSYSLOG1(x) (osyslog x)
#else
#define OSYSLOG1(x)
#endif
#if OSYSLOG_SHOW > 1
#define OSYSLOG2(x) (osyslog x)
#else
#define OSYSLOG2(x)
#endif
#if OSYSLOG_SHOW > 2
#define OSYSLOG3(x) (osyslog x)
#else
#define OSYSLOG3(x)
#endif
#if OSYSLOG_SHOW > 3
#define OSYSLOG4(x) (osyslog x)
#else
#define OSYSLOG4(x)
#endif

#define OSYSPRINT(x) (osysprint x)
#ifdef OPENR_DEBUG
#define OSYSDEBUG(x) (osysprint x)
#else
#define OSYSDEBUG(x)
#endif

const size_t osyslogMAX_SIZE = 243;

typedef longword OSyslogPriority;
const OSyslogPriority osyslogERROR            = 1;
const OSyslogPriority osyslogWARNING          = 2;
const OSyslogPriority osyslogINFO             = 3;
const OSyslogPriority osyslogDEBUG            = 0xffffffff;
const OSyslogPriority osyslogDEBUG_NO_NEWLINE = 0xfffffffe;

OStatus osyslog(OSyslogPriority priority, const char* format, ...) __attribute__((format(printf, 2, 3)));
OStatus osysprint(const char* format, ...) __attribute__((format(printf, 1, 2)));

#endif /* _OSyslog_h_DEFINED */
