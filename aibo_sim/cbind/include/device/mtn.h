/* OPEN-R motion files (WB5-REF section 7.1). mtn_new finds a relative name in the
 * controller's folder, then in the folder it runs in (--out), then among the bundled motions;
 * in each ignoring case as the memory stick's FAT file system did (wwfwd.mtn finds WWFWD.MTN)
 * where the exact name is absent; NULL on failure, mtn_get_error() says why. */
#ifndef AIBO_SIM_DEVICE_MTN_H
#define AIBO_SIM_DEVICE_MTN_H

#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct MTN MTN;

MTN *mtn_new(const char *filename);
void mtn_delete(MTN *mtn);          /* stops it; NULL does nothing; a call on it after is an error */
void mtn_play(MTN *mtn);            /* from its start, again from its start if it plays */
int mtn_is_over(MTN *mtn);
int mtn_get_length(MTN *mtn);       /* ms */
int mtn_get_time(MTN *mtn);         /* ms */
const char *mtn_get_name(MTN *mtn); /* not in Webots: the name stored in the file */
void mtn_fprint(FILE *file, MTN *mtn);
const char *mtn_get_error(void);    /* the last error, "" before any (Webots': never NULL) */

#ifdef __cplusplus
}
#endif

#endif
