/*
 * A bounded check of an LCM event log before LCM reads it. LCM 1.3's reader trusts each
 * event's lengths: an absurd data length makes it allocate (and read into) whatever the
 * length says, and crash; a bad sync word or channel length mid-log ends its reading as if
 * the log had ended. This reader looks at the 28-byte event headers only, never allocates
 * by a length read from the file, and finds the first place where the log stops being a log.
 */
#ifndef MVOD_IPC_LOG_CHECK_H
#define MVOD_IPC_LOG_CHECK_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "mvod/ipc.h"


/* Checks the log open on fd (read with pread). 0, or -errno when it cannot be read. */
int mvod_lcmlog_check(int fd, struct mvod_lcmlog_check *out);


#endif
