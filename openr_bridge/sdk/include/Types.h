/*
 * Types.h: the Aperios basic types of OPEN-R, for the aibo-sim host SDK.
 *
 * On the ERS-7 (MIPS, 32-bit) Sony declares longword as `unsigned long` and size_t as
 * `unsigned int`, both 32 bits. On a 64-bit host `long` is 64 bits, so the host types are
 * fixed-width: every OPEN-R structure keeps the robot's byte layout (see ODataFormats.h).
 * On Sony's SDK, malloc, atoi, printf, strcpy and friends were visible to code that never
 * included <stdlib.h>, <stdio.h> or <string.h>: Sony's headers include <string.h>, <stdio.h>
 * (ODebug.h) and <string> (core_macro2.h), and gcc 3.3's <string> brought in the rest. Today's
 * C++ headers do not, so this one does (tests/test_sony_sdk.py checks our wrapper without it).
 */
#ifndef _Types_h_DEFINED
#define _Types_h_DEFINED

#include <stdint.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>

typedef uint8_t  byte;
typedef uint16_t word;
typedef uint32_t longword;
typedef int8_t   sbyte;
typedef int16_t  sword;
typedef int32_t  slongword;
typedef byte*    pbyte;
typedef word*    pword;
typedef int*     plongword;
typedef uint32_t magicword;

typedef int8_t   int8;
typedef uint8_t  uint8;
typedef int16_t  int16;
typedef uint16_t uint16;
typedef int32_t  int32;
typedef uint32_t uint32;
typedef int64_t  int64;
typedef uint64_t uint64;

#ifndef NULL
#define NULL 0
#endif
#ifndef TRUE
#define TRUE  1
#define FALSE 0
#endif
typedef bool Boolean;

typedef slongword sError;
typedef longword  Selector;
typedef byte*     VirtualAddress;
typedef void*     PhysicalAddress;

#ifdef __cplusplus
const Selector UNDEF = 0xffffffff;
#else
#define UNDEF 0xffffffff
#endif

/* An entry point of an object: called with a pointer to its message. */
typedef void (*Entry)(...);

typedef unsigned int   MemoryRegionID;
typedef MemoryRegionID SharedMemoryRegionID;
typedef enum {
    MEMPROTINFO_INVALID = 0,
    MEMPROTINFO_R       = 1,
    MEMPROTINFO_RW      = 2
} MemoryProtectionInfo;
typedef MemoryProtectionInfo SharedMemoryProtectionInfo;

/* A compile-time check of the robot's structure sizes (static_assert before C++11). */
#if defined(__cplusplus) && __cplusplus >= 201103L
#define OPENR_STATIC_ASSERT(condition, name) static_assert(condition, #name)
#else
#define OPENR_STATIC_ASSERT(condition, name) \
    typedef char openr_static_assert_##name[(condition) ? 1 : -1] __attribute__((unused))
#endif

#endif /* _Types_h_DEFINED */
