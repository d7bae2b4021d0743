/* apsys.h: Aperios system declarations; the host needs none beyond MCOOP.h. */
#ifndef _apsys_h_DEFINED
#define _apsys_h_DEFINED
#include <MCOOP.h>
#endif
