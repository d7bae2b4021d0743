/* MWInformationTypes.h: middleware information identifiers. */
#ifndef _OPENR_MWInformationTypes_h_DEFINED_
#define _OPENR_MWInformationTypes_h_DEFINED_

#include <Types.h>

typedef longword MWIID;
const MWIID mwiidINVALID = 0xFFFFFFFF;
typedef byte SensorType;
typedef byte AttachedParts;
typedef byte AttachedPosition;

#endif
