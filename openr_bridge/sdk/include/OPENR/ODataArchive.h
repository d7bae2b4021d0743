/* ODataArchive.h: the magic numbers of the files inside an OPEN-R data archive (.ODA). */
#ifndef _ODataArchive_h_DEFINED
#define _ODataArchive_h_DEFINED

#include <Types.h>
#include <OPENR/OStatus.h>

const size_t odaMAX_SIZE = 32;

typedef longword ODataArchiveMagic;
const ODataArchiveMagic odamagicUNDEF = 0xffffffff;
const ODataArchiveMagic odamagicOSND  = 0x444e534f; /* "OSND" */
const ODataArchiveMagic odamagicODAR  = 0x5241444f; /* "ODAR" */
const ODataArchiveMagic odamagicOMTN  = 0x4e544d4f; /* "OMTN" */
const ODataArchiveMagic odamagicWAVE  = 0x45564157; /* "WAVE" */
const ODataArchiveMagic odamagicMIDI  = 0x4944494d; /* "MIDI" */
const ODataArchiveMagic odamagicLED   = 0x0044454c; /* "LED" */
const ODataArchiveMagic odamagicSYN   = 0x004e5953; /* "SYN" */
const ODataArchiveMagic odamagicSTT   = 0x00545453; /* "STT" */

typedef longword ODataArchiveID;
const ODataArchiveID odaID_UNDEF = 0xffffffff;

#endif /* _ODataArchive_h_DEFINED */
