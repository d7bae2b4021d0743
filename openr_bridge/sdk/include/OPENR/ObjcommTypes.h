/* ObjcommTypes.h: identities, commands and versions of inter-object communication. */
#ifndef ObjcommTypes_h_DEFINED
#define ObjcommTypes_h_DEFINED

#include <iostream>
#include <list>
#include <string.h>
#include <OPENR/OPENR.h>

using std::cout;
using std::endl;
using std::ostream;
using std::list;

/* A subject is known by its Ready entry, an observer by its Notify entry. */
typedef OServiceEntry SubjectID;
typedef OServiceEntry ObserverID;
inline SubjectID  ENTRY2SUBJECTID(const OServiceEntry& e) { return e; }
inline ObserverID ENTRY2OBSERVERID(const OServiceEntry& e) { return e; }

ostream& operator<<(ostream& os, const OServiceEntry& id);

typedef longword ObjcommMessageType;
const ObjcommMessageType objcommMSG_UNDEF   = 0;
const ObjcommMessageType objcommMSG_NOTIFY  = 1;
const ObjcommMessageType objcommMSG_CONTROL = 2;
const ObjcommMessageType objcommMSG_READY   = 3;

typedef longword ObjcommDataType;
const ObjcommDataType objcommDATA_TYPE_UNDEF = 0;
const ObjcommDataType objcommDATA_TYPE_MSG   = 1;
const ObjcommDataType objcommDATA_TYPE_SHM   = 2;

typedef int ObjcommStatus;
const ObjcommStatus objcommSUCCESS             = 0;
const ObjcommStatus objcommNOTIFY_UNDEF        = 1;
const ObjcommStatus objcommFRAMENUMBER_UNDEF   = 2;
const ObjcommStatus objcommADDOBSERVER_FAIL    = 3;
const ObjcommStatus objcommREMOVEOBSERVER_FAIL = 4;
const ObjcommStatus objcommCOMMAND_UNDEF       = 5;

typedef int ObjcommCommand;
const ObjcommCommand objcommCMD_UNDEF               = 0;
const ObjcommCommand objcommCMD_ADDOBSERVER         = 1;
const ObjcommCommand objcommCMD_REMOVEOBSERVER      = 2;
const ObjcommCommand objcommCMD_ASSERT_READY        = 3;
const ObjcommCommand objcommCMD_DEASSERT_READY      = 4;
const ObjcommCommand objcommCMD_ADDOBSERVER_SELF    = 5;
const ObjcommCommand objcommCMD_REMOVEOBSERVER_SELF = 6;
const ObjcommCommand objcommCMD_ADDOBSERVER_V22     = 7;
const ObjcommCommand objcommCMD_REMOVEOBSERVER_V22  = 8;

typedef unsigned int ObjcommVersion;
const ObjcommVersion objcommVERSION10     = 1;
const ObjcommVersion objcommVERSION20     = 2;
const ObjcommVersion objcommVERSION21     = 3;
const ObjcommVersion objcommVERSION22     = 4;
const ObjcommVersion objcommVERSION_UNDEF = 0xffffffff;

#endif /* ObjcommTypes_h_DEFINED */
