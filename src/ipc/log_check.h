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

struct mvod_lcmlog_check {
	int64_t events;   /* whole events before bad_offset (all of them when sound) */
	int64_t size;     /* bytes in the file */
	int64_t bad_offset; /* where the first bad event starts; -1 when the log is sound */
	bool cut;         /* the bad event is the last and only cut short (a writer stopped
			     mid-event): LCM reads up to it and stops, safely */
	char why[160];    /* what is wrong at bad_offset, one line */
};

/* Checks the log open on fd (read with pread). 0, or -errno when it cannot be read. */
int mvod_lcmlog_check(int fd, struct mvod_lcmlog_check *out);

/*
 * What every reader of a log (mvod view, --speed-url file://) does before LCM reads it:
 * opens path through the input path (util/input.h: noted as an input, so no output of the
 * run may be it; a regular file only) and checks the log. 0 when LCM can read it safely:
 * sound, or only cut short at its end (out->cut; the caller may warn). Else a one-line
 * reason naming path in err and -EIO when it is corrupt (where, and the truncate that keeps
 * the intact events), -ENODATA when it holds no whole event, -errno when it cannot be read.
 */
int mvod_lcmlog_vet(const char *path, struct mvod_lcmlog_check *out, char *err, size_t errlen);

#endif
