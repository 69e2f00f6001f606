/*
 * mvod's own writer of LCM event logs (file://PATH?mode=w), since LCM 1.3's file provider
 * drops write errors: a full disk gave a log cut mid-event and exit status 0.
 */
#ifndef MVOD_IPC_LCM_LOG_H
#define MVOD_IPC_LCM_LOG_H

#include <stddef.h>
#include <stdint.h>

#include "mvod/ipc.h"

/* Bytes before the channel name in every event: sync, number, time, two lengths. */
#define MVOD_LCM_LOG_HEADER 28

struct mvod_lcm_log;

/*
 * Opens path through the output policy (util/output.h: locked, truncated only at the first
 * event); what names it in messages. max_event: the largest channel name plus message, in
 * bytes; the one event buffer is allocated here. Returns 0 or -errno with a reason in err.
 */
int mvod_lcm_log_open(const char *what, const char *path, size_t max_event,
		      struct mvod_lcm_log **out, char *err, size_t errlen);
/*
 * Appends one event (channel, data, now as its time) with one write(2): LCM's format, all
 * big-endian: u32 sync 0xEDA1DA01, i64 event number from 0, i64 microseconds since the epoch,
 * u32 channel length, u32 data length, the channel (no NUL), the data. After the first
 * failure nothing more is written and every call returns that error. No allocation.
 */
int mvod_lcm_log_write(struct mvod_lcm_log *log, const char *channel, const void *data, size_t len);
/* The same with the event's time given (microseconds): a log made offline (mvod speed-log). */
int mvod_lcm_log_write_at(struct mvod_lcm_log *log, const char *channel, const void *data,
			  size_t len, int64_t utime);
/* Log rotation: mvod_output_reopen (util/output.h) of the file; 0 or -errno, why in err. */
int mvod_lcm_log_reopen(struct mvod_lcm_log *log, char *err, size_t errlen);
/* fsyncs and closes; the first error of any write or of this. NULL: 0. */
int mvod_lcm_log_close(struct mvod_lcm_log *log);

#endif
