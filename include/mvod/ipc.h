/*
 * LCM publishing of mvod.pose2_t and mvod.status2_t (on MVOD_POSE2, MVOD_STATUS2) and, beside
 * them for subscribers built against the first types, mvod.pose_t and mvod.status_t (on
 * MVOD_POSE, MVOD_STATUS).
 */
#ifndef MVOD_IPC_H
#define MVOD_IPC_H

#include <stddef.h>
#include <stdint.h>

#include <lcm/lcm.h>

#include "mvod/vo.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MVOD_DEFAULT_POSE_CHANNEL "MVOD_POSE"
#define MVOD_DEFAULT_STATUS_CHANNEL "MVOD_STATUS"
/* The longest channel name: its v2 channel, one character longer, must fit LCM's limit. */
#define MVOD_MAX_CHANNEL_LENGTH (LCM_MAX_CHANNEL_NAME_LENGTH - 1)

struct mvod_status; /* mvod/pipeline.h */
struct mvod_ipc;

/*
 * Channels: pose_channel and status_channel carry v1, the same names + "2" v2 (MVOD_POSE2).
 * url: an LCM provider URL, or NULL for LCM_DEFAULT_URL and then LCM's own default.
 * Channels NULL = the defaults above. Encoding buffers are allocated here, once.
 * A file://PATH?mode=w URL is written by mvod's own log writer (LCM's event-log format), which,
 * unlike LCM 1.3's, reports write errors; the file is opened by mvod_ipc_open_log, after the
 * inputs were checked, never here.
 */
int mvod_ipc_create(const char *url, const char *pose_channel, const char *status_channel,
		    struct mvod_ipc **out);
/* Same, on an lcm_t the caller owns and keeps alive longer (tests over memq://). */
int mvod_ipc_create_on(lcm_t *lcm, const char *pose_channel, const char *status_channel,
		       struct mvod_ipc **out);
/*
 * The publish seam: every encoded message goes to send(ctx, channel, buf, len), which returns
 * 0 or -errno (tests make publishing fail with it). ctx is borrowed.
 */
typedef int (*mvod_ipc_send_fn)(void *ctx, const char *channel, const void *buf, size_t len);
int mvod_ipc_create_with(mvod_ipc_send_fn send, void *ctx, const char *pose_channel,
			 const char *status_channel, struct mvod_ipc **out);
/*
 * Opens the file:// log, through the output policy (locked; an existing log is truncated only
 * when the first event is written); 0 for other URLs. Returns 0 or -errno, reason in err.
 */
int mvod_ipc_open_log(struct mvod_ipc *ipc, char *err, size_t errlen);
/*
 * Log rotation (SIGHUP): when the file:// log's path no longer names the open file, opens a
 * new one there, appending, and closes the old one after an fsync; 0 without a log. The log
 * goes on in the file open before when this fails (-errno, reason in err).
 */
int mvod_ipc_reopen_log(struct mvod_ipc *ipc, char *err, size_t errlen);
/* The file:// log's path, or NULL. */
const char *mvod_ipc_log_path(const struct mvod_ipc *ipc);
/*
 * Closes the file:// log after an fsync; publishing afterwards fails with -EBADF. Returns the
 * first error of any event written or of the close (0 without a log): a log that is
 * incomplete fails the run, as the trajectory does. NULL: 0.
 */
int mvod_ipc_finish(struct mvod_ipc *ipc);
/* Finishes (ignoring the result) and frees. NULL is a no-op. */
void mvod_ipc_destroy(struct mvod_ipc *ipc);

int mvod_ipc_publish_pose(struct mvod_ipc *ipc, int64_t utime, int64_t frame,
			  const struct mvod_vo_result *res);
int mvod_ipc_publish_status(struct mvod_ipc *ipc, const struct mvod_status *st);

/*
 * The one conversion between struct mvod_status and the generated mvod.status2_t
 * (mvod_status2_t.h), both ways: publishing uses the first, mvod view the second.
 */
struct _mvod_status2_t;
void mvod_status_to_msg(const struct mvod_status *st, struct _mvod_status2_t *msg);
/*
 * A message's state byte as an enum mvod_run_state value (pipeline.h): itself when it is one,
 * else MVOD_RUN_UNKNOWN (-1), so that no reader loads an out-of-range enum.
 */
int mvod_run_state_from_wire(int state);
void mvod_status_from_msg(const struct _mvod_status2_t *msg, struct mvod_status *st);
/*
 * A v1 message as its v2 type: the same fields, the new ones 0 (mvod view reads logs of
 * mvod versions that published only v1).
 */
struct _mvod_pose_t;
struct _mvod_pose2_t;
struct _mvod_status_t;
void mvod_pose_msg_upgrade(const struct _mvod_pose_t *v1, struct _mvod_pose2_t *v2);
void mvod_status_msg_upgrade(const struct _mvod_status_t *v1, struct _mvod_status2_t *v2);

/* Reading LCM logs (mvod view, --speed-url file://): file:// URLs, a bounded check first. */
/*
 * A file://PATH[?options] URL: PATH into path and LCM's mode option into *mode: 'r' (also
 * when absent), 'w', 'a', or '?' for any other value. 0 when it is one; -ENOENT for any
 * other URL (NULL too), -EINVAL for an empty PATH, -ENAMETOOLONG when PATH does not fit.
 */
int mvod_lcm_file_url(const char *url, char *path, size_t len, char *mode);

struct mvod_lcmlog_check {
	int64_t events;   /* whole events before bad_offset (all of them when sound) */
	int64_t size;     /* bytes in the file */
	int64_t bad_offset; /* where the first bad event starts; -1 when the log is sound */
	bool cut;         /* the bad event is the last and only cut short (a writer stopped
			     mid-event): LCM reads up to it and stops, safely */
	char why[160];    /* what is wrong at bad_offset, one line */
};

/*
 * What every reader of a log (mvod view, --speed-url file://) does before LCM reads it:
 * opens path through the input path (util/input.h: noted as an input, so no output of the
 * run may be it; a regular file only) and checks the log. 0 when LCM can read it safely:
 * sound, or only cut short at its end (out->cut; the caller may warn). Else a one-line
 * reason naming path in err and -EIO when it is corrupt (where, and the truncate that keeps
 * the intact events), -ENODATA when it holds no whole event, -errno when it cannot be read.
 */
int mvod_lcmlog_vet(const char *path, struct mvod_lcmlog_check *out, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif

#endif
